"""Joint search over pairs of effects: parameters and both onsets fitted together.

A greedy search lets the first effect absorb part of the second one's signature; :class:`PairSearch`
fits pairs of the best single effects as one model instead: a pool of pairs (with
:func:`residual_partners`), both onsets on a grid, coordinate descent over the onsets, a
Gauss-Newton polish on the full series, and member swaps when the best pair is near the answer.
A pair is chosen by :func:`genthermal.diagnose.discover.choose_pair`. Method:
``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from typing import Sequence

import numpy as np

from ..effects import combination_reason
from ..errors import InputError
from .search import (Candidate, EffectSearch, _indicator, _Problem, _regimes, _Structure,
                     parameter_scaling)
from .parallel import map_in_workers
from .residual import LEVEL_FACTOR, STRUCTURE_LEVEL_FACTOR
from .trajectory import ParametricSimulator

#: Single effects (best ΔBIC first) whose pairs are fitted.
PAIR_POOL = 4
#: The best single effect is also paired with each effect ranked below the pool up to this rank.
PARTNER_RANKS = 8
#: Onsets per effect in the coarse grid of a pair.
PAIR_GRID = 5
#: Levenberg-Marquardt iterations per grid point (warm-started: the grid only locates the basin).
_GRID_ITERATIONS = 2
#: Pairs (least RSS at their best starting point first) whose onsets are refined by the descent of
#: step 3; the others keep their best starting point (the grid and the onsets fitted alone).
DESCENDED_PAIRS = 3
#: Pairs (least RSS on the decimated series first) whose values are refitted on the full series.
POLISHED_PAIRS = 3
#: Replacements tried for each member of the best pair when it is near the answer (:meth:`PairSearch.swaps`).
SWAPS_PER_MEMBER = 2
#: Rounds of coordinate descent over the two onsets (the first over the whole record).
_DESCENT_ROUNDS = 3
#: Starting points of the descent kept (least RSS first) among the best grid point, both onsets
#: where each effect was fitted alone, and each of those with the other effect from the start.
_DESCENTS = 2


@dataclasses.dataclass
class JointCandidate:
    """Two effects fitted together.

    Attributes
    ----------
    effects : tuple of str
        The two effects, earlier onset first.
    values : dict
        Effect → fitted parameter values (model units).
    onsets_s : dict
        Effect → onset from the start of the record, s.
    onset_indices : dict
        Effect → onset sample index.
    rss : float
        Residual sum of squares, K².
    k : int
        Fitted parameters of both effects plus the two onsets.
    rmse_before, rmse_after : float
        RMSE without effects and with the pair, K.
    delta_bic : float
        ΔBIC against the model without effects.
    predicted : numpy.ndarray
        Model outputs with the pair, (n_outputs, N), °C.
    significant : bool
        Chosen by :func:`genthermal.diagnose.discover.choose_pair`.
    onset_profiles : list of OnsetProfile
        Set on the verdict: the criterion over each onset and the interval of onsets the data
        allow (:mod:`genthermal.diagnose.onset_profile`).
    """

    effects: tuple
    values: dict
    onsets_s: dict
    onset_indices: dict
    rss: float
    k: int
    rmse_before: float
    rmse_after: float
    delta_bic: float
    predicted: np.ndarray
    significant: bool = False
    onset_profiles: list = dataclasses.field(default_factory=list)

    def to_dict(self) -> dict:
        """The JSON entry of the pair ranking (with the onset intervals on the verdict)."""
        entry = {"effects": list(self.effects), "params": self.values, "onset_s": self.onsets_s,
                 "rmse_before": self.rmse_before, "rmse_after": self.rmse_after, "delta_ic": self.delta_bic,
                 "k": self.k, "significant": self.significant}
        if self.onset_profiles:
            entry["onset_interval_s"] = {p.effect: list(p.interval_s) for p in self.onset_profiles}
        return entry


def _start(scaling, value: float, parameter) -> float:
    """Start of a pair fit: the value fitted alone, or the typical value when that fit ended on a
    bound (the effect alone could not explain the record, and its value says nothing)."""
    at_bound = min(abs(value - parameter.lower), abs(value - parameter.upper)) <= 1e-6 * max(abs(value), 1.0)
    value = parameter.typical if at_bound and parameter.typical is not None else value
    return float(np.clip(value, scaling.lower, scaling.upper))


def _coarse_rows(search: EffectSearch, full: np.ndarray) -> np.ndarray:
    """``full`` (n_outputs, N) on the full series at the samples of the decimated series."""
    factor = int(round(search.coarse.dt_s / search.series.dt_s))
    return full[:, ::factor][:, :search.coarse.time_s.size]


def screen(residual: np.ndarray, candidates: Sequence[Candidate], directions: Sequence[np.ndarray] = ()) -> list:
    r"""``candidates`` ordered by how much of ``residual`` each removes to first order: orthogonal
    matching pursuit over their onset responses.

    With :math:`d_j` the change a candidate makes switched on at grid onset :math:`j`
    (:attr:`~genthermal.diagnose.search.Candidate.onset_responses`), made orthogonal to
    ``directions`` (what a refit of the effects already chosen absorbs), its score is
    :math:`\max_j (r\cdot d_j)^2 / (d_j\cdot d_j)`, the share of :math:`\lVert r\rVert^2` it
    removes. Effects alike in shape to a chosen one score high alone but low here. Candidates
    without onset responses come last, in their order.

    Parameters
    ----------
    residual : numpy.ndarray
        Measured minus modelled outputs on the decimated series, K, (n_outputs, N); NaN where a
        sensor has no sample.
    candidates : sequence of Candidate
    directions : sequence of numpy.ndarray
        Output changes (n_outputs, N) on the decimated series to make the responses orthogonal to.
    """
    valid = np.isfinite(residual)
    r = np.where(valid, residual, 0.0).ravel()
    basis = []
    for direction in directions:
        v = np.where(valid, np.nan_to_num(direction), 0.0).ravel()
        for u in basis:
            v = v - (v @ u) * u
        if np.linalg.norm(v) > 1e-12:
            basis.append(v / np.linalg.norm(v))

    def score(candidate: Candidate) -> float:
        if candidate.onset_responses is None:
            return -math.inf
        changes = np.where(valid[None], np.nan_to_num(candidate.onset_responses.changes), 0.0)
        changes = changes.reshape(changes.shape[0], -1)
        for u in basis:
            changes = changes - np.outer(changes @ u, u)
        norms = np.einsum("ij,ij->i", changes, changes)
        useful = norms > 1e-12 * max(float(norms.max()), 1e-300)
        return float(np.max(np.where(useful, (changes @ r) ** 2 / np.where(useful, norms, 1.0), 0.0)))

    return sorted(candidates, key=score, reverse=True)


def residual_partners(search: EffectSearch, best: Candidate, others: Sequence[Candidate], count: int) -> list:
    """The ``count`` effects of ``others`` that explain most of what ``best`` leaves (:func:`screen`
    on the decimated series, orthogonal to the change ``best`` makes from its nearest grid onset:
    a refit of ``best`` absorbs what lies along it): a forward-stepwise choice of its partners."""
    residual = _coarse_rows(search, search.series.outputs - best.predicted)
    directions = []
    if best.onset_responses is not None:
        factor = int(round(search.coarse.dt_s / search.series.dt_s))
        nearest = int(np.argmin(np.abs(best.onset_responses.onsets - best.onset_index // factor)))
        directions.append(best.onset_responses.changes[nearest])
    return screen(residual, others, directions)[:count]


class PairSearch:
    """Fit pairs of catalogue effects jointly on the series of a first-round :class:`EffectSearch`.

    Parameters
    ----------
    search : EffectSearch
        The first round (no effects found yet): its model, series, decimated series, initial state
        coefficients, cache and score before.
    """

    def __init__(self, search: EffectSearch):
        search._require_fitted()
        if search.found:
            raise InputError("search.found", [f.effect for f in search.found],
                             "a pair search starts from the model without found effects")
        self.search = search

    def _structure(self, pair: Sequence[str], series) -> _Structure:
        search = self.search
        effects = tuple(search.effect(name) for name in pair)
        key = ("pair model", search.model, effects)
        if key not in search._cache:
            model = search.model
            for name in pair:
                model = model.with_effect(search.effect(name))
            search._cache[key] = model
        model = search._cache[key]
        groups = [[p.name for p in search.effect(name).parameters] for name in pair]
        names = [n for group in groups for n in group]
        simulator_key = ("pair simulator", search.model, search.view, effects, series.time_s.size, series.dt_s)
        if simulator_key not in search._cache:
            regimes = _regimes([(g, {n: n for n in g}) for g in groups])
            search._cache[simulator_key] = ParametricSimulator(search.viewed(model), series.dt_s, series.input_matrix,
                                                               names, regimes)
        simulator = search._cache[simulator_key].with_inputs(series.input_matrix)
        scalings = [parameter_scaling(model, p.name, typical=p.typical)
                    for name in pair for p in search.effect(name).parameters]
        return _Structure(simulator, series, scalings)

    def _starts(self, single: Candidate):
        """(value fitted alone, EffectParameter) of each parameter of ``single``."""
        return [(single.values[p.name], p) for p in self.search.effect(single.effect).parameters]

    def _starting_points(self, first: Candidate, second: Candidate) -> list:
        """Step 2 on the decimated series: the starting points of the descent, least RSS first, as
        (coarse onset indices, z, coarse RSS)."""
        search = self.search
        coarse = self._structure((first.effect, second.effect), search.coarse)
        z = np.array([s.decision(_start(s, value, p)) for s, (value, p) in
                      zip(coarse.problem.scalings, [*self._starts(first), *self._starts(second)])])
        grid = self._onset_grid()
        best, z_alone = (math.inf, None, z), z
        for i, a in enumerate(grid):
            z_row = z
            for b in grid:
                z_row, rss = coarse.fit([int(a), int(b)], z_row, search.x0_coefficients, _GRID_ITERATIONS)
                if rss < best[0]:
                    best = (rss, (i, int(np.searchsorted(grid, b))), z_row)
        _, (i, j), z = best
        starts = [((int(grid[i]), int(grid[j])), z, best[0])]
        factor = int(round(search.coarse.dt_s / search.series.dt_s))
        alone = (first.onset_index // factor, second.onset_index // factor)
        for onsets in {alone, (alone[0], 0), (0, alone[1])} - {starts[0][0]}:
            starts.append((onsets, *coarse.fit(list(onsets), z_alone, search.x0_coefficients)))
        return sorted(starts, key=lambda start: start[2])

    def _onset_grid(self) -> np.ndarray:
        """Coarse onset indices of the pair grid (:data:`PAIR_GRID` per effect)."""
        n = self.search.coarse.time_s.size
        return np.unique(np.linspace(0, n - max(3, int(0.05 * n)), PAIR_GRID).round().astype(int))

    def _descents(self, pair: tuple, starts: Sequence) -> tuple:
        """Step 3 from the :data:`_DESCENTS` best ``starts``: (coarse onsets, z, coarse RSS) of least RSS."""
        coarse = self._structure(pair, self.search.coarse)
        grid = self._onset_grid()
        step = int(grid[1] - grid[0])
        return min((self._descend(coarse, list(onsets), z_start, step) for onsets, z_start, _ in starts[:_DESCENTS]),
                   key=lambda result: result[2])

    def _coarse_fit(self, first: Candidate, second: Candidate):
        """Steps 2-3 on the decimated series: (onsets as coarse indices, z, coarse RSS)."""
        return self._descents((first.effect, second.effect), self._starting_points(first, second))

    def _descend(self, coarse: _Structure, onsets: list, z, step: int, whole_record: bool = True):
        """Coordinate descent from ``onsets``: each onset searched over the whole record (grid, then
        golden section; not with ``whole_record`` False) with the values refitted, then within
        ± ``step`` samples until a round moves neither; returns (onsets, z, RSS)."""
        n, rss = coarse.series.time_s.size, math.inf
        for round_ in range(_DESCENT_ROUNDS):
            before = list(onsets)
            for position in range(2):
                bounds = ((None, None) if round_ == 0 and whole_record else
                          (max(onsets[position] - step, 0), min(onsets[position] + step, n - 1)))
                onsets[position], z, rss = coarse.search_onset(onsets, position, z, self.search.x0_coefficients,
                                                               *bounds)
            if onsets == before:
                break
        return onsets, z, rss

    def _finish(self, pair: tuple, onsets, z, polish: bool) -> JointCandidate:
        """Step 4 on the full series (``polish``), or the coarse values scored on it."""
        search = self.search
        factor = int(round(search.coarse.dt_s / search.series.dt_s))
        full = self._structure(pair, search.series)
        onsets = [o * factor for o in onsets]
        indicator = _indicator(search.series.time_s.size, onsets)
        problem = _Problem(full.problem.simulator, search.series, full.problem.scalings, exact=True,
                           fit_initial_state=True)
        z = np.concatenate([z, [0.0, 0.0]])
        if polish:
            z, _ = problem.gauss_newton(z, search.x0_coefficients, indicator)
        theta = problem.theta(z)
        predicted = problem.simulator.outputs(theta, problem.initial(z, search.x0_coefficients), indicator)
        rss = max(float(np.nansum((predicted - search.series.outputs) ** 2)), 1e-300)
        values, position = {}, 0
        for name in pair:
            names = [p.name for p in search.effect(name).parameters]
            values[name] = {p: float(theta[position + i]) for i, p in enumerate(names)}
            position += len(names)
        order = sorted(range(2), key=lambda m: onsets[m])
        effects = tuple(pair[m] for m in order)
        k = len(theta) + 2
        return JointCandidate(effects, {e: values[e] for e in effects},
                              {pair[m]: search.elapsed_s(onsets[m]) for m in order},
                              {pair[m]: int(onsets[m]) for m in order}, rss, k, search.rmse_before,
                              math.sqrt(rss / search.n_valid), search.criterion.delta(rss, search.rss_before, search.n_valid, k),
                              predicted)

    def fit(self, first: Candidate, second: Candidate, polish: bool = True) -> JointCandidate:
        """Fit the effects of two single candidates jointly (started from their single fits)."""
        onsets, z, _ = self._coarse_fit(first, second)
        return self._finish((first.effect, second.effect), onsets, z, polish)

    def refit(self, singles: Sequence[Candidate], starts: Sequence[tuple], workers: int = 1,
              progress=None) -> list[JointCandidate]:
        """Pairs fitted from known onsets (warm starts): for each ``(effect, onset s, effect, onset s)``
        of ``starts`` (e.g. a pair fitted to the same record on other sensors), the values of both
        effects fitted at those onsets from their single fits, the onsets refined within one grid
        step of the pair grid by coordinate descent (step 3 without the search over the whole
        record), then step 4; best ΔBIC first. Pairs of an effect not among ``singles`` are skipped.
        With ``workers`` > 1 the pairs are fitted in forked processes, with the same result;
        ``progress(done, total, label)`` is called after each."""
        search, by_name = self.search, {c.effect: c for c in singles}
        factor = int(round(search.coarse.dt_s / search.series.dt_s))
        grid = self._onset_grid()

        def fit_from(start):
            first, first_onset_s, second, second_onset_s = start
            coarse = self._structure((first, second), search.coarse)
            z = np.array([s.decision(_start(s, value, p)) for s, (value, p) in
                          zip(coarse.problem.scalings, [*self._starts(by_name[first]), *self._starts(by_name[second])])])
            onsets = [int(np.argmin(np.abs(search.series.time_s - search.series.time_s[0] - t))) // factor
                      for t in (first_onset_s, second_onset_s)]
            z, _ = coarse.fit(onsets, z, search.x0_coefficients)
            onsets, z, _ = self._descend(coarse, onsets, z, int(grid[1] - grid[0]), whole_record=False)
            return self._finish((first, second), onsets, z, polish=True)

        kept = [start for start in starts if start[0] in by_name and start[2] in by_name]
        ranked = map_in_workers(fit_from, kept, workers, progress and (
            lambda done, total, start: progress(done, total, f"{start[0]} + {start[2]} (refitted from its onsets)")))
        return sorted(ranked, key=lambda c: c.delta_bic)

    def member_changes(self, pair: JointCandidate) -> dict:
        """Effect → what it changes in the outputs of ``pair`` (the full series, K, at the pair's
        values and onsets; the initial state of the search)."""
        search = self.search
        full = self._structure(pair.effects, search.series)
        simulator = full.problem.simulator
        indicator = _indicator(search.series.time_s.size, [pair.onset_indices[e] for e in pair.effects])
        theta = [v for e in pair.effects for v in pair.values[e].values()]
        both = simulator.outputs(np.array(theta), search.x0_coefficients, indicator)
        changes, position = {}, 0
        for effect in pair.effects:
            without = list(theta)
            for i, parameter in enumerate(search.effect(effect).parameters):
                without[position + i] = parameter.neutral
            position += len(search.effect(effect).parameters)
            changes[effect] = both - simulator.outputs(np.array(without), search.x0_coefficients, indicator)
        return changes

    def _combinable(self, pairs: Sequence[tuple]) -> list:
        """The ``pairs`` of single candidates whose effects can be added to the model together (two
        forms of one loss cannot: :func:`~genthermal.effects.combination_reason`)."""
        search = self.search
        return [(a, b) for a, b in pairs
                if combination_reason(search.model, (search.effect(a.effect), search.effect(b.effect))) is None]

    def swaps(self, pair: JointCandidate, singles: Sequence[Candidate], count: int = SWAPS_PER_MEMBER) -> list:
        """Pairs with one member of ``pair`` replaced: for each member, the ``count`` other effects
        that best explain what it explained plus what the pair leaves (:func:`screen`, orthogonal to
        the kept member's change); a list of (kept single, new single)."""
        search = self.search
        by_name = {c.effect: c for c in singles}
        changes = self.member_changes(pair)
        others = [c for c in singles if c.effect not in pair.effects]
        swapped = []
        for member, kept in (pair.effects, pair.effects[::-1]):
            residual = _coarse_rows(search, search.series.outputs - pair.predicted + changes[member])
            swapped += [(by_name[kept], c) for c in
                        screen(residual, others, [_coarse_rows(search, changes[kept])])[:count]]
        return swapped

    def _fit(self, pairs: Sequence[tuple], workers: int, progress, stage: str = "") -> list[JointCandidate]:
        """Steps 2-4 for ``pairs`` of single candidates: every starting point, the descent for the
        :data:`DESCENDED_PAIRS` of least RSS there, the :data:`POLISHED_PAIRS` best polished.

        Three parallel maps: the starting points of each pair; the descent from each starting point
        kept (one item each: the descents of a pair are independent, and twice as many smaller
        items keep both workers busy to the end); the polish of the best pairs and the scoring of
        the others on the full series."""

        def start_pair(pair):
            starts = self._starting_points(*pair)[:_DESCENTS]
            onsets, z, rss = starts[0]
            names = (pair[0].effect, pair[1].effect)
            scored = self._finish(names, onsets, z, polish=False) if workers > 1 else None
            return starts, (list(onsets), z, rss, scored)

        grid = self._onset_grid()
        step = int(grid[1] - grid[0])

        def descend_from(item):
            names, (onsets, z_start, _) = item
            return self._descend(self._structure(names, self.search.coarse), list(onsets), z_start, step)

        def finish(item):
            names, onsets, z, polish = item
            return self._finish(names, onsets, z, polish)

        def report(what):
            """Progress of a map whose items start with the pair's names; ``what(item)`` says what was done."""
            return progress and (lambda done, total, item: progress(done, total, f"{stage}{' + '.join(item[0])} "
                                                                                 f"({what(item)})"))

        started = map_in_workers(start_pair, pairs, workers, progress and (
            lambda done, total, pair: progress(done, total, f"{stage}{pair[0].effect} + {pair[1].effect} "
                                                            "(onset grid)")))
        names = [(first.effect, second.effect) for first, second in pairs]
        order = sorted(range(len(pairs)), key=lambda m: started[m][1][2])[:DESCENDED_PAIRS]
        descents = [(m, start) for m in order for start in started[m][0]]
        refined = map_in_workers(descend_from, [(names[m], start) for m, start in descents], workers,
                                 report(lambda item: "onsets refined"))
        descended = {}
        for (m, _), (onsets, z, rss) in zip(descents, refined):  # least RSS, the first start on a tie
            if m not in descended or rss < descended[m][2]:
                descended[m] = (onsets, z, rss, None)
        coarse = []
        for m in range(len(pairs)):
            onsets, z, rss, scored = descended.get(m, started[m][1])
            coarse.append((names[m], onsets, z, rss, scored))
        coarse.sort(key=lambda item: item[3])
        unfinished = [rank for rank, item in enumerate(coarse) if rank < POLISHED_PAIRS or item[4] is None]
        finished = dict(zip(unfinished, map_in_workers(
            finish, [(*coarse[rank][:3], rank < POLISHED_PAIRS) for rank in unfinished], workers,
            report(lambda item: f"on the full series: {'polished' if item[3] else 'scored'}"))))
        return [finished.get(rank, item[4]) for rank, item in enumerate(coarse)]

    def rank(self, singles: Sequence[Candidate], pool: int = PAIR_POOL, progress=None,
             workers: int = 1) -> list[JointCandidate]:
        """Fit every pair of the ``pool`` best ``singles`` (ranked by ΔBIC) and the best single with
        the :data:`PARTNER_RANKS` − ``pool`` others that explain most of its residual
        (:func:`residual_partners`) on the decimated series, refine the onsets of the
        :data:`DESCENDED_PAIRS` most promising, polish the :data:`POLISHED_PAIRS` of least coarse
        RSS on the full series and score the others there at their coarse values. When the best
        pair leaves more than :data:`~genthermal.diagnose.residual.STRUCTURE_LEVEL_FACTOR` but at
        most :data:`~genthermal.diagnose.residual.LEVEL_FACTOR` times the noise (near the answer,
        not at it), its members are swapped for the effects that explain their part better
        (:meth:`swaps`) and those pairs fitted too. Best ΔBIC first.

        ``progress(done, total, label)`` is called after each pair when given. With ``workers`` > 1
        the pairs are fitted in forked processes (:mod:`genthermal.diagnose.parallel`); the result
        is the same."""
        ranked_singles = sorted(singles, key=lambda c: c.delta_bic)
        pairs = list(itertools.combinations(ranked_singles[:pool], 2))
        partners = residual_partners(self.search, ranked_singles[0], ranked_singles[pool:],
                                     max(PARTNER_RANKS - pool, 0))
        pairs = self._combinable(pairs + [(ranked_singles[0], other) for other in partners])
        ranked = sorted(self._fit(pairs, workers, progress), key=lambda c: c.delta_bic) if pairs else []
        noise = self.search.noise
        if ranked and STRUCTURE_LEVEL_FACTOR * noise < ranked[0].rmse_after <= LEVEL_FACTOR * noise:
            tried = {frozenset((a.effect, b.effect)) for a, b in pairs}
            swapped = [p for p in self.swaps(ranked[0], ranked_singles)
                       if frozenset((p[0].effect, p[1].effect)) not in tried]
            swapped = self._combinable(list({frozenset((a.effect, b.effect)): (a, b) for a, b in swapped}.values()))
            if swapped:
                ranked = sorted(ranked + self._fit(swapped, workers, progress, "swap: "), key=lambda c: c.delta_bic)
        return ranked
