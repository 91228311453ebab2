"""The optimal scheduler's own load shedding on the model the manager flies, chosen against the
shared shed plan at the manager's price. Main objects: :func:`chosen_shed_plan`,
:func:`on_flown_model`.
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
