"""Re-planning: one run of the registered scheduler, and what the manager does when no schedule
keeps the limit (plan within the lowest reachable peak, best effort, or shed load).

Main objects: :func:`plan_with`, :func:`planning_problem`, :func:`flight_segments`. Method:
docs/guide/flight-methods.md.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ...errors import InputError
from ..planning.flown import FlownPlanning
from ..planning.optimal import lowest_reachable_peak
from ..planning.optimal_nlp import flown_optimal_plan
from ..planning.optimal_shed import chosen_shed_plan, on_flown_model
from ..planning.plan import (FEASIBLE_TOLERANCE_K, LIMIT_TOLERANCE_K, PlanningProblem, PlanResult, evaluate, mission_segments,
                   rest_available_s, split_segments)
from ..system_frame import SystemFrame
from ..planning.registry import planner
from ..planning.price import PRICE_TOLERANCE_MIN, not_served_Ah, schedule_cost_min
from ..planning.shed import INFEASIBLE_RESPONSES, NOT_SERVED_TOLERANCE_A, priced_shed_plan
from .role_settings import PlannerSettings


def plan_with(scheduler: str, problem: PlanningProblem, settings: PlannerSettings, names, limit_C: float,
              previous=None, switched_off=None, when_infeasible: str | None = None,
              shedding: bool = False, flown_shed: FlownPlanning | None = None) -> PlanResult:
    """Run ``scheduler`` on ``problem``; when infeasible, plan within the lowest reachable peak or shed.

    Parameters
    ----------
    scheduler : str
        A registered planner (:mod:`genthermal.schedule.planning.registry`): heuristic, engineer,
        optimal, milp or one registered from outside.
    problem : PlanningProblem
        Its ``limit_C`` is the planning limit (θmax minus the margin); its ``rest_budget_s`` bounds
        the total rest of the plan (rests beyond it are cut, earliest kept).
    settings : PlannerSettings
        The planner's settings (:meth:`ManagerSettings.roles
        <genthermal.schedule.flight.manager_settings.ManagerSettings.roles>`; a ManagerSettings, whose
        fields of the same names these are, also serves).
    names : sequence of str
        Generator names, for the messages.
    limit_C : float
        θmax, °C.
    previous : Schedule, optional
        Warm start of the optimal scheduler.
    switched_off : array-like of bool, optional
        (n_generators,) generators already switched off: the plan is :func:`~.shed.shed_plan`.
    when_infeasible : str, optional
        One of :data:`INFEASIBLE_RESPONSES`, what to do when the lowest reachable peak is above
        θmax; None (default): ``settings.when_infeasible``.
    shedding : bool
        The manager sheds load now (its last plan did). It goes back to plans without shedding
        only once one keeps the planning limit: while the lowest reachable peak is above it, it
        keeps shedding rather than fly a schedule that uses up the margin (hysteresis). Measured
        on the robustness grid's case 15 (a k_flow 0.23 blockage on gen2 of 3): the lowest-peak
        schedules flown after the shedding, 0.2-0.6 K into the margin, moved gen2's landing load onto
        the healthy generators, which the plant's 25 % weaker cooling took to 110.5 °C (20 s
        above θmax).
    flown_shed : FlownPlanning, optional
        The filters the manager flies, for the optimal scheduler planning on the design model: when
        it must shed load it also plans its own shed plan on the flown model and flies it when it
        keeps θmax on its forecast, else the shared one (:mod:`~genthermal.schedule.planning.optimal_shed`). None (default, and
        for the baselines): the shared shed plan.

    Returns
    -------
    PlanResult
        ``feasible`` is True only when the plan's own prediction, with its back-off (the margin and
        the rise back-off), stays within the planning limit. Otherwise ``details`` hold the lowest
        reachable peak (``lowest_peak_C``, its generator and action), the peak of the plan flown
        (``planned_peak_C``) and what the manager does about it (``response``); when that peak is
        above θmax and ``when_infeasible`` is ``shed``, the plan sheds load (``method`` ``shed``;
        ``shedding``: the generators whose load is shed, ``switched_off``: the generators off); with
        ``best_effort`` it is the scheduler's own plan, all load served (``best_effort`` True in
        ``details``).
    """
    response_mode = settings.when_infeasible if when_infeasible is None else when_infeasible
    if response_mode not in INFEASIBLE_RESPONSES:
        raise InputError("when_infeasible", response_mode, f"must be one of {', '.join(INFEASIBLE_RESPONSES)}")
    if switched_off is not None and np.any(switched_off):
        off = np.array(switched_off, dtype=bool)
        return _shed(on_design_model(problem, settings, limit_C), off, off, names, limit_C, "", settings.margin_K)

    entry = planner(scheduler)
    own_settings = getattr(settings, entry.settings_field) if entry.settings_field else entry.settings

    def run(p, initial=previous):
        return entry.plan(p, own_settings, initial)
    lowest = result = None
    if shedding and response_mode == "shed" and problem.flown is not None:
        # shedding on the flown model, the lowest reachable peak first: above the planning limit no
        # plan of the scheduler keeps it (none peaks below the min-max), so its NLP is not solved
        # (on long missions that NLP is the costliest part of a re-plan; docs/results/robustness-grid.md)
        lowest = _within_budget(problem, lowest_reachable_peak(problem, settings.optimal))
    if lowest is None or lowest.peak_C <= problem.limit_C + FEASIBLE_TOLERANCE_K:
        result = _within_budget(problem, run(problem))
        if result.feasible:
            result.solve_s += 0.0 if lowest is None else lowest.solve_s
            return result
    if lowest is None:
        lowest = _within_budget(problem, lowest_reachable_peak(problem, settings.optimal))
    planned_s = 0.0 if result is None else result.solve_s  # the scheduler's own plan, when solved
    segment = problem.segments[lowest.peak_segment]
    where = (f"the lowest reachable peak is {lowest.peak_C:.1f} °C, on {names[lowest.peak_generator]} during "
             f"action {segment.action_index + 1} ({segment.label})")
    found = dict(lowest_peak_C=lowest.peak_C, lowest_peak_generator=names[lowest.peak_generator],
                 lowest_peak_action=segment.action_index + 1)
    keep_shedding = shedding and lowest.peak_C > problem.limit_C + LIMIT_TOLERANCE_K
    if (lowest.peak_C > limit_C or keep_shedding) and response_mode == "shed":
        nobody = np.zeros(problem.n_generators, dtype=bool)
        if lowest.peak_C <= limit_C:
            where += (f", within θmax {limit_C:g} °C: the manager, shedding, keeps shedding until a plan keeps "
                      "the margin")
        if problem.flown is not None:  # shed as little load as keeps θmax on the flown model
            shed = _flown_shed(problem, settings, previous, names, limit_C, where)
            if shed is not None:
                shed.solve_s += planned_s + lowest.solve_s
                shed.details.update(found)
                return shed
        design = on_design_model(problem, settings, limit_C)
        shed = _shed(design, nobody, nobody, names, limit_C, where, settings.margin_K,
                     within_margin=lowest.peak_C <= limit_C)
        if scheduler == "optimal" and flown_shed is not None and problem.flown is None:
            shed = _own_or_shared_shed(design, settings, shed, flown_shed, names, limit_C, where,
                                       within_margin=lowest.peak_C <= limit_C, previous=previous)
        shed.solve_s += planned_s + lowest.solve_s
        shed.details.update(found)
        return shed
    if lowest.peak_C > limit_C:  # best effort: the scheduler's own plan, all load served
        best = _best_effort(problem, result, names, limit_C, where, found)
        best.solve_s += lowest.solve_s
        return best
    within_lowest = dataclasses.replace(problem, limit_C=max(lowest.peak_C, problem.limit_C) + 0.1)
    relaxed = _within_budget(problem, run(within_lowest, lowest.schedule))  # the min-max schedule is feasible there
    # the scheduler's plan is flown when its peak is within lowest peak + 0.1 K by the tolerance every
    # plan is judged with (evaluate): a strict test put the rest-heavy min-max schedule in place of the optimal
    # scheduler's plan 0.01 K over it (blockage_large at 250 min: rest 50 s where the engineer's
    # heuristic, 0.01 K under it, rested 10 s on the same problem)
    if relaxed.peak_C > lowest.peak_C + 0.1 + FEASIBLE_TOLERANCE_K:  # worse than the min-max schedule: fly that
        relaxed = dataclasses.replace(lowest, method=f"{result.method} (lowest peak)", warnings=list(relaxed.warnings))
    if response_mode == "shed" and problem.flown is None:
        # the manager's price (genthermal.schedule.planning.price): the margin kept by shedding load after
        # the rest worth its minutes, when that costs less than the rest the lowest-peak schedule needs
        nobody = np.zeros(problem.n_generators, dtype=bool)
        shed = _shed(problem, nobody, nobody, names, limit_C, where, settings.margin_K, within_margin=True)
        relaxed_cost = schedule_cost_min(problem.segments, relaxed.schedule)
        shed_cost = shed.details["cost_min"] if shed.peak_C <= limit_C + LIMIT_TOLERANCE_K else np.inf
        if shed_cost < relaxed_cost - PRICE_TOLERANCE_MIN:
            shed.solve_s += result.solve_s + lowest.solve_s + relaxed.solve_s
            shed.details.update(found, lowest_peak_schedule_cost_min=relaxed_cost)
            shed.warnings[-1] += (f"; cheaper at the manager's price than the lowest-peak schedule's "
                                  f"{relaxed.schedule.added_rest_s / 60:.1f}-min rest")
            return shed
        relaxed.details.update(cost_min=relaxed_cost, shed_alternative_cost_min=None if np.isinf(shed_cost) else shed_cost)
        relaxed.solve_s += shed.solve_s
    response = (f"flying the lowest-peak schedule: rest {relaxed.schedule.added_rest_s / 60:.1f} min, move "
                f"{relaxed.schedule.displaced_Ah(problem.segments):.2f} A·h to the other generators")
    if relaxed.peak_C > limit_C:
        message = f"infeasible: no schedule keeps θ ≤ {limit_C:g} °C; {where}; {response}"
    else:
        message = (f"margin not kept: no schedule stays within the planning limit {problem.limit_C:.1f} °C; "
                   f"{where}, within θmax {limit_C:g} °C; {response}")
    relaxed.feasible = False
    relaxed.solve_s += result.solve_s + lowest.solve_s
    relaxed.warnings.append(message)
    relaxed.details.update(found, planned_peak_C=relaxed.peak_C, response=response)
    return relaxed


def _best_effort(problem: PlanningProblem, result: PlanResult, names, limit_C: float, where: str,
                 found: dict) -> PlanResult:
    """The scheduler's own plan ``result`` flown although it breaches θmax (``when_infeasible``
    ``best_effort``): every load served, the breach predicted and reported; ``details`` carry
    ``best_effort`` True and the plan's predicted peak."""
    rested = result.schedule.added_rest_s / 60.0
    moved_Ah = result.schedule.displaced_Ah(problem.segments)
    response = (f"best effort, no load shed: rest {rested:.1f} min, move {moved_Ah:.2f} "
                f"A·h to the other generators; predicted peak {result.peak_C:.1f} °C on {names[result.peak_generator]}, "
                f"{result.peak_C - limit_C:.1f} K above θmax {limit_C:g} °C")
    result.feasible = False
    result.warnings.append(f"infeasible: no schedule keeps θ ≤ {limit_C:g} °C; {where}; {response}")
    result.details.update(found, planned_peak_C=result.peak_C, response=response, best_effort=True)
    return result


def _flown_shed(problem: PlanningProblem, settings: PlannerSettings, previous, names, limit_C: float,
                where: str) -> PlanResult | None:
    """The optimal scheduler on the flown model with load allowed to go unserved
    (:func:`~genthermal.schedule.planning.optimal_nlp.flown_optimal_plan`, ``shed``); None when even that
    does not keep its prediction within θmax (the caller switches generators off)."""
    result = flown_optimal_plan(problem, settings.optimal.nonlinear, previous, shed=True)
    if not result.feasible:  # its own prediction, with its back-off, above θmax
        return None
    result = _within_budget(problem, result)
    shedding = _shedding_names(result.schedule, names)
    response = (f"shed load of {', '.join(shedding) or 'nobody'}: "
                f"{not_served_Ah(problem.segments, result.schedule):.2f} A·h not served, the least "
                f"that keeps every generator within θmax {limit_C:g} °C on the flown model with its back-off, after rest "
                f"{result.schedule.added_rest_s / 60:.1f} min and displacement")
    result.method, result.feasible = "shed", False
    result.warnings.append(f"infeasible: no schedule keeps θ ≤ {limit_C:g} °C; {where}; {response}")
    result.details.update(response=response, planned_peak_C=result.peak_C, shedding=shedding, switched_off=[])
    return result


def _shedding_names(schedule, names) -> list:
    """Names of the generators whose load ``schedule`` leaves partly unserved: a generator
    displacing load in a segment where the generators' displacements do not sum to zero (more than
    :data:`~genthermal.schedule.planning.shed.NOT_SERVED_TOLERANCE_A`)."""
    short = schedule.displaced_A.sum(axis=0) > NOT_SERVED_TOLERANCE_A
    return [name for name, displaced in zip(names, schedule.displaced_A)
            if np.any((displaced > NOT_SERVED_TOLERANCE_A) & short)]


def _own_or_shared_shed(problem: PlanningProblem, settings: PlannerSettings, shared: PlanResult,
                        flown: FlownPlanning, names, limit_C: float, where: str,
                        within_margin: bool = False, previous=None) -> PlanResult:
    """The optimal scheduler's shed plan: its own on the flown model ``flown`` (rest, displacement
    and load not served planned together, :func:`~genthermal.schedule.planning.optimal_shed.own_shed_plan`)
    when its prediction with the back-off keeps θmax and it costs less at the manager's price, else
    the shared ``shared`` (:func:`~genthermal.schedule.planning.optimal_shed.chosen_shed_plan`); never
    ``feasible``. ``details`` carry the comparison either way."""
    chosen, comparison = chosen_shed_plan(problem, shared, flown, limit_C, settings.optimal.nonlinear, previous)
    if chosen is shared:
        shared.details.update(comparison)
        shared.solve_s += comparison["own_shed_solve_s"]
        return shared
    chosen = _within_budget(on_flown_model(problem, flown, limit_C), chosen)  # judged on its own model if cut
    schedule = chosen.schedule
    shedding = _shedding_names(schedule, names)
    bound = f"the planning limit {problem.limit_C:.1f} °C" if within_margin else f"θmax {limit_C:g} °C"
    response = (f"shed load of {', '.join(shedding) or 'nobody'}: no rest within the rest budget and no displacement "
                f"keeps it within {bound}; the optimal scheduler's own plan on the flown model: rest "
                f"{schedule.added_rest_s / 60:.1f} min, {not_served_Ah(problem.segments, schedule):.2f} A·h not "
                f"served ({comparison['own_shed_cost_min']:.1f} min at the manager's price, the shared shed plan "
                f"{comparison['shared_shed_cost_min']:.1f} min), every generator within θmax {limit_C:g} °C with "
                f"the filters' back-off (predicted peak {chosen.peak_C:.1f} °C; "
                f"{comparison['own_shed_design_peak_C']:.1f} °C on the design model)")
    headline = (f"margin not kept: no schedule stays within the planning limit {problem.limit_C:.1f} °C"
                if within_margin else f"infeasible: no schedule keeps θ ≤ {limit_C:g} °C")
    chosen.method, chosen.feasible = "shed", False
    chosen.solve_s += shared.solve_s
    chosen.warnings.append(f"{headline}; {where}; {response}")
    chosen.details.update(comparison, response=response, planned_peak_C=chosen.peak_C, shedding=shedding,
                          switched_off=[])
    return chosen


def on_design_model(problem: PlanningProblem, settings: PlannerSettings, limit_C: float) -> PlanningProblem:
    """``problem`` as the affine planner poses it: on the design models (with the filters'
    disturbance heat flows), within θmax ``limit_C`` minus ``settings.margin_K``, with the rise
    back-off; ``problem`` itself when it already is.

    The shed plan (:func:`~.shed.shed_plan`) is computed on the design models; when the nonlinear
    planner's own shedding finds no plan (:func:`_flown_shed`) it must also be judged there.
    Judged on the flown model with its back-off instead, the design-model plan was above θmax on
    every generator in turn: on the robustness grid's case 15 (a k_flow 0.23 blockage with a +24 K
    inlet rise on gen2 of 3, identified 8 min after its onset, when the filter's disturbance states
    had just restarted) the manager switched all three generators off and left 25.7 A·h unserved.
    """
    if problem.flown is None:
        return problem
    return dataclasses.replace(problem, flown=None, limit_C=limit_C - settings.margin_K,
                               rise_backoff=settings.rise_backoff)


def _within_budget(problem: PlanningProblem, result: PlanResult) -> PlanResult:
    """``result`` with its rests cut to ``problem.rest_budget_s`` and the rest before the first
    segment to ``max_rest_s`` minus the rest already taken before it; re-evaluated when cut."""
    schedule = result.schedule.within_rest_budget(problem.rest_budget_s, first_rest_max_s(problem))
    if np.allclose(schedule.rest_before_s, result.schedule.rest_before_s, rtol=0.0, atol=1e-6):
        return result
    cut = evaluate(problem, schedule, result.method, result.solve_s, result.warnings)
    cut.feasible = cut.feasible and result.feasible
    cut.details = dict(result.details, rest_cut_to_budget_s=problem.rest_budget_s)
    cut.warnings.append(f"rests cut to the {problem.rest_budget_s / 60:.1f} min left of the flight's rest budget "
                        f"and {problem.max_rest_s / 60:g} min before one action")
    return cut


def first_rest_max_s(problem: PlanningProblem) -> float:
    """Rest still allowed before the first segment, s (:func:`~.plan.rest_available_s`)."""
    return rest_available_s(problem, 0)


def _shed(problem: PlanningProblem, already: np.ndarray, off: np.ndarray, names, limit_C: float,
          where: str, receiver_margin_K: float, within_margin: bool = False) -> PlanResult:
    """Shed load with ``off`` switched off (``already`` were off before) and, while the plan still
    breaches θmax on a generator still on, switch that one off too, after the rest the manager's
    price chooses; the :func:`~.shed.priced_shed_plan` result (receivers within
    ``receiver_margin_K`` more), never ``feasible``. ``within_margin``: θmax can be kept but the planning limit cannot (the messages
    say so)."""
    result = priced_shed_plan(problem, off, limit_C, receiver_margin_K)
    off = result.schedule.switched_off
    newly = [names[g] for g in np.flatnonzero(off & ~already)]
    shedding = [names[g] for g in result.details["shedding"]]
    if where:
        bound = f"the planning limit {problem.limit_C:.1f} °C" if within_margin else f"θmax {limit_C:g} °C"
        response = (f"shed load of {', '.join(shedding) or 'nobody'}: no rest within the rest budget and no "
                    f"displacement keeps it within {bound}; each generator carries at most what keeps "
                    "it within the planning limit, the others take what their limits allow, the rest is not served"
                    + (f"; rest {result.schedule.added_rest_s / 60:.1f} min first, at the manager's price "
                       f"({result.details['cost_min']:.1f} min with the load not served)"
                       if result.schedule.added_rest_s > 0 else "")
                    + (f"; switch off {', '.join(newly)} (too hot even carrying nothing)" if newly else ""))
        headline = (f"margin not kept: no schedule stays within the planning limit {problem.limit_C:.1f} °C"
                    if within_margin else f"infeasible: no schedule keeps θ ≤ {limit_C:g} °C")
        result.warnings.append(f"{headline}; {where}; {response}")
        result.details.update(response=response)
    elif newly:
        response = f"switch off {', '.join(newly)} (too hot even carrying nothing)"
        result.warnings.append(f"shed: {response}")
        result.details.update(response=response)
    result.feasible = False
    result.details.update(planned_peak_C=result.peak_C, shedding=shedding,
                          switched_off=[names[g] for g in np.flatnonzero(off)])
    return result


def planning_problem(frame: SystemFrame, settings: PlannerSettings, segments, x0, t_s: float, generators,
             rest_budget_s: float, rest_taken_s: float = 0.0, flown: FlownPlanning | None = None,
             inputs_C: dict | None = None, unexplained_rise_K=None) -> PlanningProblem:
    """The planning problem at ``t_s`` with ``rest_budget_s`` (s) of rest left to the flight and
    ``rest_taken_s`` (s) of rest already flown right before the first segment; with ``flown`` (the
    nonlinear planner) the limit is θmax itself and the back-off that of the filters' covariance.
    ``frame``: the power system's limits and currents (:meth:`PowerSystem.frame`); ``settings``: the
    planner's (its ``margin_K`` the scenario's when it gives one).
    ``inputs_C`` (input name → (n_gen, 1) readings at ``t_s``, °C): the measured inlet of each
    generator and the median measured ambient, held over the plan (default the mission's);
    ``unexplained_rise_K`` (n_generators, n_outputs), K: the last cycle's rise the filters did not
    explain (``PlanningProblem.unexplained_rise_K``)."""
    generator = frame.role
    inputs_C = inputs_C or {}
    inlet = np.array([float(inputs_C[generator.coolant_input][g, 0]) if generator.coolant_input in inputs_C
                      else float(frame.inlet_C(g, t_s)) for g in range(frame.n_generators)])
    ambient = float(np.median(inputs_C[generator.ambient_input][:, 0])) if generator.ambient_input in inputs_C \
        else frame.T_ambient_C
    budget = max(float(rest_budget_s), 0.0)
    # the longest rest before one action, the rest under way included: the budget left has that
    # rest taken off already, so bounding by the budget alone and then subtracting the rest under
    # way counted it twice (blockage_large, engineer: 30 min rested before landing with 30 of the
    # 60-min budget left, no more rest allowed; the manager shed gen1's load instead)
    longest_rest = min(settings.max_rest_s, budget + float(rest_taken_s))
    limit, rise_backoff = (frame.limit_C, 0.0) if flown is not None else \
        (frame.limit_C - settings.margin_K, settings.rise_backoff)
    return PlanningProblem(tuple(segments), generators, np.asarray(x0, dtype=float), inlet,
                           ambient, frame.rest_current_A, frame.current_limit_A,
                           limit, longest_rest, settings.dt_s,
                           rise_backoff, settings.cycle_s, budget, float(rest_taken_s), flown,
                           None if unexplained_rise_K is None else np.asarray(unexplained_rise_K, dtype=float))


def flight_segments(mission, settings: PlannerSettings, scheduler: str) -> tuple:
    """The segments of ``mission`` (a :class:`~genthermal.mission.Mission`); for the nonlinear
    planner cut into control intervals of one cycle, except for the thesis heuristic, which decides
    per K-condition (eq. 7.2) on either model."""
    segments = mission_segments(mission)
    split = settings.nonlinear and scheduler != "heuristic"
    return split_segments(segments, settings.cycle_s, settings.dt_s) if split else segments
