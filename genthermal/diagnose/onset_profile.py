"""Onsets of the verdict refined on their profile, and the interval of onsets the data allow.

For each effect of the verdict, the criterion is profiled over its onset (every other value and
the initial state refitted at each onset); an onset the profile rejects moves to the profile's
minimum, and the onset interval is the range the criterion does not reject by more than its
evidence limit. Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Sequence

import numpy as np

from ..effects import FROM_START_TOLERANCE_S
from ..errors import InputError
from .search import _indicator, _Problem, _Structure

#: Levenberg-Marquardt iterations per profile point (warm-started from its neighbour).
PROFILE_ITERATIONS = 3
#: Rounds of the joint refinement (profile of each effect in turn, onsets moved to its minimum).
MAX_ROUNDS = 3


@dataclasses.dataclass(frozen=True)
class OnsetProfile:
    """The criterion over one effect's onset, the other parameters refitted at each.

    Attributes
    ----------
    effect : str
    onsets_s : tuple of float
        Onsets profiled, s from the start of the record, ascending.
    delta_ic : tuple of float
        Criterion change of each against the best onset of the profile.
    onset_s : float
        Onset of least RSS of the profile, s (the verdict keeps the search's onset when the
        profile does not reject it).
    interval_s : (float, float)
        Onsets the data allow, s: from one sample period before the earliest onset sample with
        ``delta_ic`` within ``threshold`` (not before the start) to the latest.
    threshold : float
        Criterion change that bounds the interval.
    """

    effect: str
    onsets_s: tuple
    delta_ic: tuple
    onset_s: float
    interval_s: tuple
    threshold: float

    def to_dict(self) -> dict:
        """JSON entry: the onset, its interval and the profile."""
        return {"effect": self.effect, "onset_s": self.onset_s, "interval_s": list(self.interval_s),
                "threshold": self.threshold,
                "profile": {"onset_s": list(self.onsets_s), "delta_ic": [round(d, 3) for d in self.delta_ic]}}


class OnsetProfiler:
    """Profile and refine the onsets of effects fitted together on one (decimated) series.

    Parameters
    ----------
    structure : _Structure
        The effects' simulator and parameter scalings on the series (every effect's parameters,
        in the order of ``onsets``' effects).
    x0_coefficients : array-like
        Initial-state coefficients of the search; the profile refits a shift of them.
    criterion : BIC, AIC or compatible
        Gives the criterion change of an RSS ratio.
    threshold : float, optional
        Criterion change that bounds the interval; default the magnitude of the criterion's
        evidence limit.
    """

    def __init__(self, structure: _Structure, x0_coefficients, criterion, threshold: float | None = None):
        self.series = structure.series
        self.problem = _Problem(structure.problem.simulator, structure.series, structure.problem.scalings,
                                fit_initial_state=True)
        self.x0_coefficients = np.asarray(x0_coefficients, dtype=float)
        self.criterion = criterion
        self.threshold = abs(criterion.evidence_limit) if threshold is None else float(threshold)
        if not (math.isfinite(self.threshold) and self.threshold > 0):
            raise InputError("threshold", threshold, "must be a criterion change > 0")
        self.n_valid = int(self.problem.mask.sum())

    def _delta(self, rss: float, best: float) -> float:
        return self.criterion.delta(max(rss, 1e-300), max(best, 1e-300), self.n_valid, 0)

    def _fit(self, onsets: Sequence[int], z) -> tuple[np.ndarray, float]:
        indicator = _indicator(self.series.time_s.size, onsets)
        return self.problem.gauss_newton(z, self.x0_coefficients, indicator, PROFILE_ITERATIONS, 1e-4)

    def profile(self, onsets: Sequence[int], position: int, z) -> dict:
        """Onset index → (z, RSS) for ``onsets[position]`` walked out from its value until the
        criterion change against the least RSS so far exceeds the threshold on each side."""
        n = self.series.time_s.size
        start = int(onsets[position])
        points = {start: self._fit(onsets, z)}
        for step in (-1, 1):
            onset, z_near = start, points[start][0]
            while 0 <= onset + step <= n - 2:
                onset += step
                trial = list(onsets)
                trial[position] = onset
                points[onset] = self._fit(trial, z_near)
                z_near = points[onset][0]
                best = min(rss for _, rss in points.values())
                if self._delta(points[onset][1], best) > self.threshold:
                    break
        return points

    def refine(self, effects: Sequence[str], onsets: Sequence[int], z) -> tuple[list, np.ndarray, float, list]:
        """Joint refinement of ``onsets`` (module docstring) from the values ``z`` (decision
        variables, without the initial state).

        Returns
        -------
        onsets : list of int
            Refined onset indices on the series.
        z : numpy.ndarray
            Values at those onsets (decision variables, without the initial state).
        rss : float
            Their RSS on the series, K².
        profiles : list of OnsetProfile
            The last profile of each effect, in the order of ``effects``.
        """
        if len(effects) != len(onsets):
            raise InputError("onsets", list(onsets), f"need one per effect {list(effects)}")
        onsets = [int(o) for o in onsets]
        z = np.concatenate([np.asarray(z, dtype=float), [0.0, 0.0]])
        last: dict[int, dict] = {}
        for _ in range(MAX_ROUNDS):
            moved = False
            for position in range(len(onsets)):
                points = last[position] = self.profile(onsets, position, z)
                best = min(points, key=lambda o: points[o][1])
                current = onsets[position]
                if self._delta(points[current][1], points[best][1]) > self.threshold:
                    moved, onsets[position] = True, best
                z = points[onsets[position]][0]
            if not moved:
                break
        rss = self._fit(onsets, z)[1]
        profiles = [self._profile_of(effect, last[position]) for position, effect in enumerate(effects)]
        return onsets, z[:-2], rss, profiles

    def _profile_of(self, effect: str, points: dict) -> OnsetProfile:
        """The :class:`OnsetProfile` of ``points`` (onset index → (z, RSS))."""
        order = sorted(points)
        best = min(rss for _, rss in points.values())
        delta = [self._delta(points[o][1], best) for o in order]
        elapsed = [float(self.series.time_s[o] - self.series.time_s[0]) for o in order]
        inside = [t for t, d in zip(elapsed, delta) if d <= self.threshold]
        onset = elapsed[int(np.argmin(delta))]
        interval = (max(min(inside) - self.series.dt_s, 0.0), max(inside))
        return OnsetProfile(effect, tuple(elapsed), tuple(delta), onset, interval, self.threshold)


def refine_verdict(search, chosen, pool: list):
    """``chosen`` (the first round's verdict: a Candidate or a JointCandidate of ``search``) with
    its onsets refined on their profile (kept when the refit on the full series fits better) and
    its :class:`OnsetProfile` list set; the entry of ``pool`` (the ranking it came from) that is
    ``chosen`` is replaced by the result, which is returned."""
    from .joint import JointCandidate, PairSearch

    if search.found:
        raise InputError("search.found", [f.effect for f in search.found], "onsets are profiled in the first round")
    factor = int(round(search.coarse.dt_s / search.series.dt_s))
    if isinstance(chosen, JointCandidate):
        pairs = PairSearch(search)
        effects = list(chosen.effects)
        structure = pairs._structure(effects, search.coarse)
        values = [chosen.values[e][p.name] for e in effects for p in search.effect(e).parameters]
    else:
        effects = [chosen.effect]
        structure = search._structure(chosen.effect, search.coarse)
        values = [chosen.values[p.name] for p in search.effect(chosen.effect).parameters]
    z = [s.decision(float(np.clip(v, s.lower, s.upper))) for s, v in zip(structure.problem.scalings, values)]
    onsets = [(chosen.onset_indices[e] if isinstance(chosen, JointCandidate) else chosen.onset_index) // factor
              for e in effects]
    profiler = OnsetProfiler(structure, search.x0_coefficients, search.criterion)
    refined_onsets, z, _, profiles = profiler.refine(effects, onsets, z)
    result = chosen
    # a design property (Effect.from_start) keeps its onset in the first minutes: one the profile
    # moves later is no finding (Effect.implausible), so the verdict's own onset stays
    late = any(search.effect(e).from_start and search.elapsed_s(k * factor) > FROM_START_TOLERANCE_S
               for e, k in zip(effects, refined_onsets))
    if refined_onsets != onsets and not late:
        if isinstance(chosen, JointCandidate):
            moved = pairs._finish(tuple(effects), refined_onsets, z, polish=True)
        else:
            theta = structure.problem.theta(z)
            moved = search.polish(dataclasses.replace(
                chosen, values={p.name: float(v) for p, v in zip(search.effect(chosen.effect).parameters, theta)},
                onset_index=refined_onsets[0] * factor, onset_s=search.elapsed_s(refined_onsets[0] * factor),
                rss=math.inf))
        if moved.rss < chosen.rss:
            moved.significant = chosen.significant
            if hasattr(chosen, "onset_responses"):
                moved.onset_responses = chosen.onset_responses
            result = moved
    result.onset_profiles = profiles
    pool[:] = [result if entry is chosen else entry for entry in pool]
    return result
