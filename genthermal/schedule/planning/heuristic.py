"""The load management heuristic of thesis chapter 7 (eqs. 7.1-7.5, Fig. 7.2): displacement first,
then rest, segment by segment. Main objects: :func:`heuristic_plan`, :class:`HeuristicSettings`,
:class:`SegmentResponse`.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from .heuristic_flown import FlownSegmentResponse
from .plan import (LIMIT_TOLERANCE_K, PlanningProblem, PlanResult, Schedule, affine_states, evaluate, predict,
                   rest_available_s, rest_then_segment, robust_outputs)


@dataclasses.dataclass(frozen=True)
class HeuristicSettings:
    """Settings of the thesis heuristic.

    Attributes
    ----------
    rest_step_s : float
        Increment by which a rest is extended, s (thesis Fig. 7.2: "a short rest ... extended").
    """

    rest_step_s: float = 300.0


class SegmentResponse:
    r"""Temperatures of generator ``g`` over a rest of ``rest_s`` and segment ``k`` from ``x_start``,
    affine in the displaced current: :math:`y = y_0 + d\,y_d`, :math:`x_{end} = x_0 + d\,x_d`.
    The rows of :math:`y` are the temperatures after each step and, below them, the same with the
    rise back-off of ``problem`` (:func:`~genthermal.schedule.planning.plan.robust_outputs`)."""

    def __init__(self, problem: PlanningProblem, g: int, k: int, x_start: np.ndarray, rest_s: float):
        self.problem, self.g, self.k = problem, g, k
        generator, dt = problem.generators[g], problem.dt_s
        segment = problem.segments[k]
        E, G = generator.step(dt)
        n_rest, current = rest_then_segment(segment, rest_s, problem.rest_current_A, dt)
        n_run = current.size - n_rest
        u = problem.inputs(g, current)
        x = np.vstack([x_start, affine_states(E, generator.forcing(u) @ G.T, x_start)])
        u_sample = np.vstack([u, u[-1:]])  # the input in force at each sample
        shed = np.zeros((n_rest + n_run, x_start.size))
        shed[n_rest:] = -(generator.B @ generator.e_I) @ G.T  # shedding 1 A during the segment
        dx = np.vstack([np.zeros_like(x_start), affine_states(E, shed, np.zeros_like(x_start))])
        du = np.zeros_like(u_sample)
        du[n_rest:] = -generator.e_I
        windows = np.concatenate([np.zeros(n_rest, dtype=int),
                                  n_rest + segment.window_start_steps(dt, problem.window_s)])
        samples = [generator.outputs(x, u_sample).T, (dx @ generator.Cy.T + du @ generator.Dy.T).T]
        self.y0, self.yd = (np.vstack([y[:, 1:], robust_outputs(y, windows, problem.rise_backoff)]) for y in samples)
        self.x_end0, self.x_end_d = x[-1], dx[-1]

    def peak(self, d: float) -> float:
        """Peak temperature (°C) with displaced current ``d`` (A)."""
        return float(np.max(self.y0 + d * self.yd))

    def end(self, d: float) -> np.ndarray:
        """State (°C) after the segment with displaced current ``d`` (A)."""
        return self.x_end0 + d * self.x_end_d

    def room(self, limit_C: float) -> float:
        """:func:`receiver_room` of this response."""
        return receiver_room(self, limit_C)

    def later_room(self, limit_C: float) -> float:
        """:func:`future_room` of this response."""
        return future_room(self.problem, self.g, self.k, self, limit_C)

    def least_displacement(self, limit_C: float) -> float:
        """Smallest ``d >= 0`` keeping the peak within ``limit_C``; ``inf`` if none does."""
        excess = self.y0 - limit_C
        over = excess > LIMIT_TOLERANCE_K
        if not over.any():
            return 0.0
        relief = -self.yd[over]
        if np.any(relief <= 1e-12):
            return np.inf
        return float(np.max(excess[over] / relief)) * (1.0 + 1e-9) + 1e-9


def receiver_room(response: SegmentResponse, limit_C: float) -> float:
    """Largest extra current (A) a receiver can take keeping its peak (back-off rows included)
    within ``limit_C``; 0 when it is already at the limit."""
    heating = -response.yd  # temperature rise per ampere taken on
    slack = limit_C - response.y0
    if np.any(slack < -LIMIT_TOLERANCE_K):
        return 0.0
    rising = heating > 1e-12
    return float(np.min(np.clip(slack[rising], 0.0, None) / heating[rising])) if rising.any() else np.inf


def future_room(problem: PlanningProblem, g: int, k: int, response: SegmentResponse, limit_C: float) -> float:
    """Largest extra current (A) generator ``g`` can take in segment ``k`` such that, carrying its
    own nominal load in the segments after ``k`` (no rests, back-off rows included), it stays
    within ``limit_C`` wherever it would without the extra current; ``inf`` after the last segment.

    The later temperatures are affine in the state at the end of segment ``k``, which is affine
    in the current taken (``response``), so two predictions give them for any current.
    """
    later = problem.segments[k + 1:]
    if not later:
        return np.inf
    # the design model's prediction, as ``response``'s states are the design model's: a problem
    # that also carries the flown models (the nonlinear planner's) would predict on every filter
    alone = dataclasses.replace(problem, segments=later, generators=[problem.generators[g]],
                                inlet_C=problem.inlet_C[[g]], x0=response.x_end0[None, :], flown=None,
                                unexplained_rise_K=None)
    nominal = Schedule.nominal(1, len(later))

    def future(x_end):
        prediction = predict(dataclasses.replace(alone, x0=x_end[None, :]), nominal)
        return np.maximum(prediction.outputs[0, :, 1:], robust_outputs(
            prediction.outputs[0], prediction.timeline.window_start, problem.rise_backoff))

    without = future(response.x_end0)
    heating = future(response.x_end0 - response.x_end_d) - without  # per ampere taken on (d = -1 A)
    kept = (without <= limit_C + LIMIT_TOLERANCE_K) & (heating > 1e-12)
    if not kept.any():
        return np.inf
    return float(np.min(np.clip(limit_C - without[kept], 0.0, None) / heating[kept]))


def _displacement(problem: PlanningProblem, k: int, responses, violators) -> np.ndarray | None:
    """Eq. 7.2 for segment ``k``: least displacement off each violator, shared equally by the others;
    None when displacement alone cannot keep every generator within the limit."""
    low, high = problem.displacement_bounds(k)
    receivers = [g for g in range(problem.n_generators) if g not in violators]
    if not receivers:
        return None
    d = np.zeros(problem.n_generators)
    for f in violators:
        d[f] = responses[f].least_displacement(problem.limit_C)
        if d[f] > high:
            return None
    d[receivers] = -np.sum(d) / len(receivers)
    if d[receivers[0]] < low:
        return None
    if any(responses[h].peak(d[h]) > problem.limit_C + LIMIT_TOLERANCE_K for h in receivers):
        return None
    return d


def heuristic_plan(problem: PlanningProblem, settings: HeuristicSettings = HeuristicSettings()) -> PlanResult:
    """Plan by the thesis heuristic (Fig. 7.2) on the design model, or on the flown model when
    ``problem.flown`` is set (:mod:`~genthermal.schedule.planning.heuristic_flown`).

    Parameters
    ----------
    problem : PlanningProblem
    settings : HeuristicSettings

    Returns
    -------
    PlanResult
        When no rest up to ``problem.max_rest_s`` (and what is left of ``problem.rest_budget_s``
        after the earlier segments' rests) makes a segment feasible, that segment gets the longest
        rest and the largest displacement off its violators that the receivers can take within the
        limit, and ``feasible`` is False.
    """
    started = time.perf_counter()
    n_seg, n_gen = len(problem.segments), problem.n_generators
    displaced, rests = np.zeros((n_gen, n_seg)), np.zeros(n_seg)
    if problem.flown is None:
        respond, x = SegmentResponse, list(problem.x0.copy())
    else:  # on the flown model: the filters' states and covariances, 0 steps from now
        respond, x = FlownSegmentResponse, [(problem.flown.z0[g], problem.flown.P0[g], 0) for g in range(n_gen)]
    warnings = []
    for k in range(n_seg):
        # the rest this segment may still take: the longest before one action (less what was rested
        # right before the first segment) and what is left of the flight's budget after the earlier
        # segments' rests; a displacement planned after a rest the budget then cuts would load the
        # receivers for a rest they never get
        available = rest_available_s(problem, k, float(np.sum(rests[:k])))
        rest = 0.0
        while True:
            responses = [respond(problem, g, k, x[g], rest) for g in range(n_gen)]
            violators = [g for g in range(n_gen) if responses[g].peak(0.0) > problem.limit_C + LIMIT_TOLERANCE_K]
            d = np.zeros(n_gen) if not violators else _displacement(problem, k, responses, violators)
            if d is not None:
                break
            if rest + settings.rest_step_s > available + 1e-9:
                d = _best_effort(problem, k, responses, violators)
                warnings.append(f"segment {k} ({problem.segments[k].label}): no rest up to "
                                f"{max(available, 0.0) / 60:g} min keeps it within {problem.limit_C:g} °C")
                break
            rest += settings.rest_step_s
        displaced[:, k], rests[k] = d, rest
        x = [responses[g].end(d[g]) for g in range(n_gen)]
    schedule = Schedule(displaced, rests)
    return evaluate(problem, schedule, "heuristic", time.perf_counter() - started, warnings)


def _best_effort(problem: PlanningProblem, k: int, responses, violators) -> np.ndarray:
    """Largest displacement off the violators that the receivers can take within their current
    limit and the planning limit, in this segment and, carrying their own load, in the later ones
    (:func:`future_room`), shared equally (eqs. 7.3-7.4): the receiver with the least room sets
    each one's share, so a healthy receiver is not planned past the limit."""
    low, high = problem.displacement_bounds(k)
    receivers = [g for g in range(problem.n_generators) if g not in violators]
    d = np.zeros(problem.n_generators)
    if receivers:
        share = min([-low] + [min(responses[h].room(problem.limit_C), responses[h].later_room(problem.limit_C))
                              for h in receivers])
        d[violators] = max(0.0, min(high, share * len(receivers) / len(violators)))
        d[receivers] = -np.sum(d[violators]) / len(receivers)
    return d
