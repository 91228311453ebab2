"""Hindsight plan of a faulty flight: the least added rest with the true plant and its fault known
from the onset, the reference the schedulers' rests are compared with. Main object:
:func:`hindsight_plan`.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ...errors import InputError
from ...estimation.ekf import ExtendedKalmanFilter
from ...simulate import simulate
from ..planning.flown import FlownPlanning
from ..planning.optimal_nlp import NonlinearSettings, flown_optimal_plan
from ..planning.plan import (LIMIT_TOLERANCE_K, PlanningProblem, Schedule, build_timeline, generator_inputs,
                   mission_segments, remaining_after, split_segments)


@dataclasses.dataclass(frozen=True)
class HindsightResult:
    """The hindsight plan of one flight.

    Attributes
    ----------
    onset_s : float
        Mission time of the first fault's onset, where the plan starts, s.
    rest_s : float
        Added rest of the plan, s.
    not_served_Ah : float
        Load the plan leaves unserved, A·h (0 unless no schedule serving all load keeps θmax).
    peak_C : float
        Highest temperature of the plan on the true plant, °C.
    served_all : bool
        True when a schedule serving all load keeps every generator within θmax.
    method : str
        The planner's answer (``optimal``, ``shed`` or a fallback named by its origin).
    """

    onset_s: float
    rest_s: float
    not_served_Ah: float
    peak_C: float
    served_all: bool
    method: str


def _true_state_at(system, t_s: float, dt_s: float) -> np.ndarray:
    """(n_generators, n_states) true-plant node temperatures at ``t_s`` after the nominal mission
    from a cold machine (every node at the ambient temperature), °C; raises if the healthy plant
    leaves θmax before ``t_s`` (a scheduler would have acted before the fault)."""
    segments = mission_segments(system.mission)
    timeline = build_timeline(segments, Schedule.nominal(system.n_generators, len(segments)),
                              system.rest_current_A, dt_s)
    n = int(round(t_s / dt_s))
    head = timeline.head(n)
    states = []
    for g in range(system.n_generators):
        model = system.plant_model(g)
        frame = generator_inputs(head, g, 0.0, lambda t, g=g: system.inlet_C(g, t), system.mission.T_ambient_C,
                                 system.mission.power_factor, system.rated_current_A, model.spec.interface.generator)
        run = simulate(model, frame, x0=np.full(model.n_states, system.mission.T_ambient_C))
        peak = float(run[list(model.output_names)].to_numpy().max())
        if peak > system.limit_C + LIMIT_TOLERANCE_K:
            raise InputError("faults", [f.describe(system.generator_names) for f in system.faults],
                             f"the healthy plant reaches {peak:.1f} °C on the nominal mission before the first "
                             "fault's onset: a hindsight plan from the onset does not apply")
        states.append(run[[f"T_{name}" for name in model.state_names]].to_numpy()[-1])
    return np.array(states)


def hindsight_problem(system, cycle_s: float = 300.0, dt_s: float = 10.0, rest_budget_s: float | None = None,
                      max_rest_s: float = 3600.0, margin_K: float = 0.0) -> PlanningProblem:
    """The planning problem of :func:`hindsight_plan` (module docstring) at the first fault's onset.

    Parameters
    ----------
    system : PowerSystem
        With at least one fault.
    cycle_s : float
        Control interval (the management cycle), s.
    dt_s : float
        Plant step, s.
    rest_budget_s : float, optional
        Rest the flight may add, s; default the closed loop's (a quarter of the mission).
    max_rest_s : float
        Longest rest before one interval, s.
    margin_K : float
        Plan to θmax minus this, K (default 0: with everything known no margin is needed; the
        affine closed loop's 2.5 K shows what its margin costs).
    """
    from ..flight.manager_settings import DEFAULT_REST_BUDGET_FRACTION
    from ..state_estimator import FLIGHT_EKF_SETTINGS

    if not system.faults:
        raise InputError("faults", [], "a hindsight plan needs a faulty flight")
    if not (np.isfinite(margin_K) and margin_K >= 0):
        raise InputError("margin_K", margin_K, "must be a number of kelvin >= 0")
    onset = min(f.onset_s for f in system.faults)
    onset = float(np.ceil(onset / dt_s - 1e-9) * dt_s)
    budget = DEFAULT_REST_BUDGET_FRACTION * system.mission.duration_s if rest_budget_s is None else float(rest_budget_s)
    x0 = _true_state_at(system, onset, dt_s)
    segments = mission_segments(system.mission)
    nominal = Schedule.nominal(system.n_generators, len(segments))
    timeline = build_timeline(segments, nominal, system.rest_current_A, dt_s)
    remaining, _ = remaining_after(segments, nominal, timeline, int(round(onset / dt_s)))
    faults = tuple(range(len(system.faults)))
    filters = [ExtendedKalmanFilter(system.plant_model(g, faults), dt_s, **FLIGHT_EKF_SETTINGS)
               for g in range(system.n_generators)]
    z0 = np.array([np.concatenate([x0[g], np.zeros(len(f.disturbance_names))]) for g, f in enumerate(filters)])
    P0 = np.zeros((system.n_generators, z0.shape[1], z0.shape[1]))
    flown = FlownPlanning(filters, z0, P0, confidence_sigmas=0.0)
    later = onset + 3600.0 * 24  # every fault started, its inlet rise complete
    inlet = np.array([float(system.inlet_C(g, later)) for g in range(system.n_generators)])
    generators = [system.design_generator(g, faults) for g in range(system.n_generators)]
    x_design = np.array([[dict(zip(system.plant_model(g).state_names, x0[g]))[name]
                          for name in generators[g].model.state_names] for g in range(system.n_generators)])
    return PlanningProblem(split_segments(remaining, cycle_s, dt_s), generators, x_design, inlet,
                           system.mission.T_ambient_C, system.rest_current_A, system.current_limit_A,
                           system.limit_C - margin_K, min(max_rest_s, budget), dt_s, 0.0, cycle_s, budget, 0.0, flown)


def hindsight_schedule(problem: PlanningProblem, settings: NonlinearSettings = NonlinearSettings()):
    """The hindsight plan of ``problem`` (:func:`hindsight_problem`): the optimal scheduler on the
    flown model serving all load, or, when that does not keep θmax, the one that may leave load
    unserved; a :class:`~genthermal.schedule.planning.plan.PlanResult`."""
    result = flown_optimal_plan(problem, settings)
    return result if result.feasible else flown_optimal_plan(problem, settings, shed=True)


def hindsight_plan(system, settings: NonlinearSettings = NonlinearSettings(), **problem_options) -> HindsightResult:
    """The hindsight plan of ``system``'s flight (module docstring).

    Parameters
    ----------
    system : PowerSystem
        With at least one fault.
    settings : NonlinearSettings
        Of the transcription.
    **problem_options
        Passed to :func:`hindsight_problem`.

    Returns
    -------
    HindsightResult
    """
    problem = hindsight_problem(system, **problem_options)
    result = hindsight_schedule(problem, settings)
    durations = np.array([s.duration_s for s in problem.segments])
    not_served = np.clip(result.schedule.displaced_A.sum(axis=0), 0.0, None)
    return HindsightResult(float(min(f.onset_s for f in system.faults)), result.schedule.added_rest_s,
                           float(np.sum(not_served * durations) / 3600.0), float(result.peak_C),
                           result.method != "shed", result.method)
