"""The thesis heuristic's segment responses on the flown nonlinear model (``planner_model``
``nonlinear``, thesis 7.3.4): the least displacement by a bracketed search on the model. Main
object: :class:`FlownSegmentResponse`.
"""

from __future__ import annotations

import numpy as np

from .plan import LIMIT_TOLERANCE_K, PlanningProblem, Schedule, build_timeline, rest_then_segment

#: A least displacement (or a largest room) is accepted once the peak is within this of the limit
#: on its feasible side, K.
ROOT_TOLERANCE_K = 0.01
#: ... or once the bracket is this narrow, A.
ROOT_TOLERANCE_A = 1e-3
#: Most model runs of one bracketed search.
MAX_RUNS = 40


def _least_feasible(breach, low: float, high: float) -> float:
    """Smallest ``d`` in ``[low, high]`` with ``breach(d) <= 0``, given ``breach(low) > 0 >=
    breach(high)`` and ``breach`` decreasing (regula falsi, Illinois); returns a ``d`` on the
    feasible side within :data:`ROOT_TOLERANCE_K` or :data:`ROOT_TOLERANCE_A` of the boundary."""
    f_low, f_high = breach(low), breach(high)
    kept = 0
    for _ in range(MAX_RUNS):
        if f_high >= -ROOT_TOLERANCE_K or high - low <= ROOT_TOLERANCE_A:
            break
        d = high - f_high * (high - low) / (f_high - f_low)
        d = min(max(d, low + 0.01 * (high - low)), high - 0.01 * (high - low))
        f = breach(d)
        if f <= 0.0:
            high, f_high = d, f
            f_low = f_low / 2.0 if kept == -1 else f_low  # the same end kept twice: halve its weight
            kept = -1
        else:
            low, f_low = d, f
            f_high = f_high / 2.0 if kept == 1 else f_high
            kept = 1
    return high


class FlownSegmentResponse:
    """Temperatures of generator ``g`` over a rest of ``rest_s`` and segment ``k`` on the flown
    model from the filter state ``start`` (``(z, P, steps since the planning instant)``), for any
    displaced current; the interface of :class:`~genthermal.schedule.planning.heuristic.SegmentResponse`."""

    def __init__(self, problem: PlanningProblem, g: int, k: int, start: tuple, rest_s: float):
        self.problem, self.g, self.k, self.start = problem, g, k, start
        self.n_rest, self.nominal = rest_then_segment(problem.segments[k], rest_s, problem.rest_current_A, problem.dt_s)
        self._runs: dict = {}

    def _run(self, d: float):
        key = round(float(d), 9)
        if key not in self._runs:
            currents = self.nominal.copy()
            currents[self.n_rest:] -= d
            z, P, first = self.start
            outputs, backoff, end = self.problem.flown.run(self.problem, self.g, z, P, currents, first)
            self._runs[key] = (float(np.max((outputs + backoff)[:, 1:])), end)
        return self._runs[key]

    def peak(self, d: float) -> float:
        """Peak temperature with the back-off (°C) with displaced current ``d`` (A)."""
        return self._run(d)[0]

    def end(self, d: float) -> tuple:
        """``(z, P, steps)`` after the segment with displaced current ``d`` (A)."""
        return self._run(d)[1]

    def least_displacement(self, limit_C: float) -> float:
        """Smallest ``d >= 0`` up to the segment's lowest current keeping the peak within
        ``limit_C``; ``inf`` if none does."""
        if self.peak(0.0) <= limit_C + LIMIT_TOLERANCE_K:
            return 0.0
        high = self.problem.displacement_bounds(self.k)[1]
        if self.peak(high) > limit_C:
            return np.inf
        return _least_feasible(lambda d: self.peak(d) - limit_C, 0.0, high)

    def room(self, limit_C: float) -> float:
        """Largest extra current (A), up to the current limit, this generator can take keeping its
        peak within ``limit_C``; 0 when it is already at the limit."""
        most = -self.problem.displacement_bounds(self.k)[0]
        if self.peak(0.0) > limit_C + LIMIT_TOLERANCE_K or most <= 0.0:
            return 0.0
        if self.peak(-most) <= limit_C:
            return most
        return _largest_feasible(lambda e: self.peak(-e) - limit_C, 0.0, most)

    def later_room(self, limit_C: float) -> float:
        """Largest extra current (A), up to the current limit, this generator can take in this
        segment such that, carrying its own nominal load in the later segments (no rests), it
        stays within ``limit_C`` wherever it would without the extra current; ``inf`` after the
        last segment."""
        later = self.problem.segments[self.k + 1:]
        if not later:
            return np.inf
        currents = build_timeline(later, Schedule.nominal(1, len(later)), self.problem.rest_current_A,
                                  self.problem.dt_s).currents_A[0]

        def later_peaks(e):
            z, P, first = self.end(-e)
            outputs, backoff, _ = self.problem.flown.run(self.problem, self.g, z, P, currents, first)
            return (outputs + backoff)[:, 1:]
        without = later_peaks(0.0)
        kept = without <= limit_C + LIMIT_TOLERANCE_K
        if not kept.any():
            return np.inf
        most = -self.problem.displacement_bounds(self.k)[0]

        def excess(e):
            return float(np.max(later_peaks(e)[kept])) - limit_C
        if most <= 0.0 or excess(most) <= 0.0:
            return max(most, 0.0)
        return _largest_feasible(excess, 0.0, most)


def _largest_feasible(excess, low: float, high: float) -> float:
    """Largest ``e`` in ``[low, high]`` with ``excess(e) <= 0``, given ``excess`` increasing,
    ``excess(low) <= 0 < excess(high)``."""
    return -_least_feasible(lambda d: excess(-d), -high, -low)
