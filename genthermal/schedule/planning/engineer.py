"""The engineer's heuristic, the fair baseline for the optimal scheduler: once a breach is
predicted, the generators that would breach shed as much load as the others can take, then all
rest in fine steps. Main objects: :func:`engineer_plan`, :class:`EngineerSettings`.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from .heuristic import SegmentResponse, receiver_room
from .plan import LIMIT_TOLERANCE_K, PlanningProblem, PlanResult, Schedule, evaluate, predict, rest_available_s


@dataclasses.dataclass(frozen=True)
class EngineerSettings:
    """Settings of the engineer's heuristic.

    Attributes
    ----------
    rest_step_s : float
        Resolution of the rest, s.
    """

    rest_step_s: float = 10.0


def _largest_displacement(problem: PlanningProblem, k: int, responses, violators) -> np.ndarray:
    """Displaced current per generator (A): the violators shed what the receivers can take."""
    low, high = problem.displacement_bounds(k)
    receivers = [g for g in range(problem.n_generators) if g not in violators]
    d = np.zeros(problem.n_generators)
    if not receivers:
        return d
    room = np.array([min(-low, receiver_room(responses[h], problem.limit_C)) for h in receivers])
    moved = min(float(np.sum(room)), high * len(violators))
    if moved <= 0:
        return d
    d[violators] = moved / len(violators)
    d[receivers] = -room * moved / np.sum(room)
    return d


def predicted_violators(problem: PlanningProblem) -> list[int]:
    """Generators whose prediction under the nominal schedule (back-off included) exceeds the
    planning limit anywhere in the rest of the mission."""
    prediction = predict(problem, Schedule.nominal(problem.n_generators, len(problem.segments)))
    future = prediction.future()
    return [g for g in range(problem.n_generators) if future[g].max() > problem.limit_C + LIMIT_TOLERANCE_K]


def _segment_decision(problem: PlanningProblem, k: int, x: np.ndarray, rest_s: float, shedding):
    """``(feasible, displaced, responses)`` of segment ``k`` after a rest of ``rest_s``; the
    generators in ``shedding`` shed load whether or not they breach in this segment."""
    responses = [SegmentResponse(problem, g, k, x[g], rest_s) for g in range(problem.n_generators)]
    limit = problem.limit_C + LIMIT_TOLERANCE_K
    violators = [g for g in range(problem.n_generators) if g in shedding or responses[g].peak(0.0) > limit]
    if not violators:
        return True, np.zeros(problem.n_generators), responses
    d = _largest_displacement(problem, k, responses, violators)
    feasible = all(responses[g].peak(d[g]) <= limit for g in range(problem.n_generators))
    return feasible, d, responses


def _shortest_rest(problem: PlanningProblem, k: int, x: np.ndarray, step_s: float, shedding, available_s: float):
    """Shortest rest on the grid of ``step_s`` up to ``available_s`` that makes segment ``k``
    feasible: ``(rest_s, displaced, responses, feasible)``; the longest rest if none does."""
    n_max = max(int(np.floor(available_s / step_s + 1e-9)), 0)
    decided = {}

    def decide(n):
        if n not in decided:
            decided[n] = _segment_decision(problem, k, x, n * step_s, shedding)
        return decided[n]

    if decide(0)[0] or n_max == 0:
        return (0.0, *decide(0)[1:], decide(0)[0])
    low, high = 0, 1
    while high < n_max and not decide(high)[0]:
        low, high = high, min(2 * high, n_max)
    if not decide(high)[0]:
        return (high * step_s, *decide(high)[1:], False)
    while high - low > 1:
        middle = (low + high) // 2
        low, high = (low, middle) if decide(middle)[0] else (middle, high)
    return (high * step_s, *decide(high)[1:], True)


def engineer_plan(problem: PlanningProblem, settings: EngineerSettings = EngineerSettings()) -> PlanResult:
    """Plan by the engineer's heuristic (module docstring) on the design model.

    Parameters
    ----------
    problem : PlanningProblem
    settings : EngineerSettings

    Returns
    -------
    PlanResult
        ``method`` ``engineer``; ``feasible`` False (and a warning naming the segment) when even
        the longest rest with the largest displacement leaves a segment above the limit.
    """
    started = time.perf_counter()
    n_seg, n_gen = len(problem.segments), problem.n_generators
    displaced, rests = np.zeros((n_gen, n_seg)), np.zeros(n_seg)
    x = problem.x0.copy()
    warnings = []
    shedding = predicted_violators(problem)
    for k in range(n_seg):
        available = rest_available_s(problem, k, float(np.sum(rests[:k])))
        rest, d, responses, feasible = _shortest_rest(problem, k, x, settings.rest_step_s, shedding, available)
        if not feasible:
            warnings.append(f"segment {k} ({problem.segments[k].label}): no rest up to "
                            f"{available / 60:g} min keeps it within {problem.limit_C:g} °C")
        displaced[:, k], rests[k] = d, rest
        x = np.array([responses[g].x_end0 + d[g] * responses[g].x_end_d for g in range(n_gen)])
    return evaluate(problem, Schedule(displaced, rests), "engineer", time.perf_counter() - started, warnings)
