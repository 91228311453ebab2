r"""The optimal scheduler's own load shedding, on the model the manager flies.

When no schedule within the flight's rest budget keeps θmax, every scheduler has the shared shed
plan (:func:`~genthermal.schedule.planning.shed.priced_shed_plan`): on the design models with the filters'
disturbance heat flows, within θmax minus the manager's margin (2.5 K) and with the rise back-off,
going forward through the segments each generator sheds the least constant load that keeps it
within that limit, the others take what their room allows, after the one rest (now or right before
the first shedding segment) that the manager's price (:mod:`~genthermal.schedule.planning.price`) finds
worth its minutes. That plan is the baselines' (the thesis heuristic has no shedding; the
engineer's heuristic is defined without it). Its forecast is pessimistic on the robustness grid's
blockages: on case 50 each re-plan predicted 1.3-2.5 A·h unserved, and the flight left 0.90.

The optimal scheduler also plans the same decision as one problem on the model it identified in
flight (:func:`own_shed_plan`): the nonlinear planner's transcription on the flown model
(:func:`~genthermal.schedule.planning.optimal_nlp.flown_optimal_plan` with ``shed``, the extended Kalman
filters' models with their disturbance states), every generator, the healthy ones included, held
below θmax with the back-off of the filters' covariance instead of the fixed margin, on the same
segments, rest budget and current limits, with the objective rest (min) plus
:data:`~genthermal.schedule.planning.price.SHED_PRICE_MIN_PER_AH` per A·h not served.

**Which plan is flown** (:func:`chosen_shed_plan`): the own plan whenever its prediction on the
flown model with the back-off stays within θmax on every generator (``feasible`` of
:func:`~genthermal.schedule.planning.optimal_nlp.flown_optimal_plan`); otherwise the shared plan. Both
costs at the manager's price (:func:`~genthermal.schedule.planning.price.schedule_cost_min`: rest plus the
load each leaves unserved) are reported beside the choice, and each plan's forecast on the other's
model too, so that a saving bought by the flown model's smaller back-off is visible. Either way the
plan sheds load and is reported ``feasible: false``
(:func:`~genthermal.schedule.flight.replanning.plan_with`).

Until this rule, the cheaper of the two at the price was flown. The two costs are forecasts on
different models, and on the robustness grid's blockages the design model's is the pessimistic
one: the choice flipped from cycle to cycle. On case 10 the own plans, resting 4.0-5.4 min, took
turns with shared plans resting 40-60 min, and the flight rested the whole 74.8-min budget with
0.06 A·h unserved. Flying the own plan whenever it holds θmax on its forecast, the same flight
rests 23.0 min with 0.07 A·h unserved (``genthermal sweep --cases 60 --only 10 --schedulers
optimal``). The thesis heuristic on the flown model, which sheds with the nonlinear planner alone,
had rested 43.7 min there.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ...errors import InputError
from .flown import FlownPlanning
from .optimal_nlp import NonlinearSettings, flown_optimal_plan
from .plan import PlanningProblem, PlanResult, Schedule, predict
from .price import schedule_cost_min


def shed_guess(problem: PlanningProblem, initial: Schedule | None) -> Schedule | None:
    """Initial guess of the own shed plan from ``initial`` (the shared shed plan): a generator it
    switches off sheds its whole lowest load in each segment instead (the transcription has no
    switching off), displacements within the bounds; None without one of the right shape."""
    n_seg = len(problem.segments)
    if initial is None or initial.displaced_A.shape != (problem.n_generators, n_seg):
        return None
    displaced = np.array(initial.displaced_A, dtype=float)
    for k in range(n_seg):
        low, high = problem.displacement_bounds(k)
        displaced[initial.switched_off, k] = high
        displaced[:, k] = np.clip(displaced[:, k], low, high)
    return Schedule(displaced, np.array(initial.rest_before_s, dtype=float))


def on_flown_model(problem: PlanningProblem, flown: FlownPlanning, limit_C: float) -> PlanningProblem:
    """``problem`` (on the design models) posed on the flown model: ``flown`` the filters, the
    limit θmax ``limit_C`` itself (the back-off is the covariance's), no rise back-off, as
    :func:`~genthermal.schedule.flight.replanning.planning_problem` poses it for the nonlinear planner."""
    if not isinstance(flown, FlownPlanning):
        raise InputError("flown", type(flown).__name__, "must be the filters' FlownPlanning")
    if not np.isfinite(limit_C):
        raise InputError("limit_C", limit_C, "must be θmax in °C")
    return dataclasses.replace(problem, flown=flown, limit_C=float(limit_C), rise_backoff=0.0)


def own_shed_plan(problem: PlanningProblem, flown: FlownPlanning, limit_C: float,
                  settings: NonlinearSettings = NonlinearSettings(), initial: Schedule | None = None,
                  previous: Schedule | None = None) -> PlanResult:
    """Rest, displacement and load not served planned together on the flown model at the
    manager's price (module docstring).

    The transcription is not convex (the free rest lengths enter the exponential decay), and
    IPOPT's local optimum depends on its start: it is solved from ``initial``, from ``initial``
    without its rests and from ``previous``, and the best plan kept (within θmax first, then the
    cheapest). Measured on the robustness grid's case 35 (``genthermal sweep --only 35``): started
    from the shared plan alone, the re-plan at 150 min found a plan costing 149 min where the
    shared plan, judged on its own forecast, cost 96.

    Parameters
    ----------
    problem : PlanningProblem
        The design-model problem (its segments, state, inputs, rest budget, current limits).
    flown : FlownPlanning
        The filters the manager flies, their states and covariances.
    limit_C : float
        θmax, °C.
    settings : NonlinearSettings
    initial : Schedule, optional
        Warm start, typically the shared shed plan (:func:`shed_guess` converts it).
    previous : Schedule, optional
        Another warm start: the plan flown until now (the closed loop's remaining schedule).

    Returns
    -------
    PlanResult
        Judged on the flown model: ``feasible`` when its prediction with the back-off stays within
        θmax; ``details["cost_min"]``: :func:`~genthermal.schedule.planning.price.schedule_cost_min`.
    """
    posed = on_flown_model(problem, flown, limit_C)
    starts = [shed_guess(problem, initial), shed_guess(problem, previous)]
    if starts[0] is not None and starts[0].added_rest_s > 0:
        starts.append(Schedule(starts[0].displaced_A, np.zeros_like(starts[0].rest_before_s)))
    starts = [start for start in starts if start is not None] or [None]
    best, solve_s = None, 0.0
    for start in starts:
        result = flown_optimal_plan(posed, settings, start, shed=True)
        result.details["cost_min"] = schedule_cost_min(problem.segments, result.schedule)
        solve_s += result.solve_s
        if best is None or (result.feasible, -result.details["cost_min"]) > (best.feasible, -best.details["cost_min"]):
            best = result
    best.solve_s = solve_s
    return best


def chosen_shed_plan(problem: PlanningProblem, shared: PlanResult, flown: FlownPlanning, limit_C: float,
                     settings: NonlinearSettings = NonlinearSettings(),
                     previous: Schedule | None = None) -> tuple[PlanResult, dict]:
    """The optimal scheduler's choice between the shared shed plan ``shared`` and its own
    (:func:`own_shed_plan`, warm-started from ``shared``): its own whenever that keeps θmax on its
    forecast (module docstring).

    Parameters
    ----------
    problem : PlanningProblem
        The design-model problem ``shared`` was planned on.
    shared : PlanResult
        The shared shed plan (:func:`~genthermal.schedule.planning.shed.priced_shed_plan`).
    flown : FlownPlanning
    limit_C : float
        θmax, °C.
    settings : NonlinearSettings
    previous : Schedule, optional
        The plan flown until now, a further warm start of the own plan.

    Returns
    -------
    tuple
        ``(plan, comparison)``: ``plan`` is the own plan when it is flown, else ``shared`` itself;
        ``comparison``: ``shared_shed_cost_min``, ``own_shed_cost_min`` (None when the own plan does
        not keep θmax on its forecast), ``own_shed_peak_C`` (flown model, with the back-off),
        ``own_shed_design_peak_C`` (the own schedule on the shared plan's design-model forecast,
        rise back-off included), ``shared_shed_flown_peak_C`` (the shared schedule on the flown
        model with the back-off), ``own_shed_solve_s`` and ``shed_plan_flown`` (``own`` or ``shared``).
    """
    if shared.schedule.displaced_A.shape != (problem.n_generators, len(problem.segments)):
        raise InputError("shared", shared.schedule.displaced_A.shape,
                         f"the shared shed plan must be a plan of the problem's {problem.n_generators} generators and "
                         f"{len(problem.segments)} segments")
    if problem.flown is not None:
        raise InputError("problem.flown", type(problem.flown).__name__,
                         "the shared shed plan is planned on the design model: pass that problem")
    own = own_shed_plan(problem, flown, limit_C, settings, shared.schedule, previous)
    shared_cost = schedule_cost_min(problem.segments, shared.schedule)
    own_cost = own.details["cost_min"]
    flown_own = own.feasible  # its forecast is the flown model's: not priced against the design model's (module docstring)
    comparison = dict(shared_shed_cost_min=shared_cost, own_shed_cost_min=own_cost if own.feasible else None,
                      own_shed_peak_C=own.peak_C, own_shed_design_peak_C=predict(problem, own.schedule).peak()[0],
                      shared_shed_flown_peak_C=predict(on_flown_model(problem, flown, limit_C),
                                                       shared.schedule).peak()[0],
                      own_shed_solve_s=own.solve_s, shed_plan_flown="own" if flown_own else "shared")
    return (own if flown_own else shared), comparison
