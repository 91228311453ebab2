"""The search behind the diagnosis: every candidate effect fitted with its onset.

:class:`EffectSearch` fits each effect's parameters on an onset grid over the decimated record
(Levenberg-Marquardt, warm starts), refines the onset by golden section, and refits the best
effects, the earlier ones and the initial state on the full series with the exact Jacobian
(:class:`Candidate`); :func:`noise_std` estimates the sensor noise from the data alone. Method:
``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Mapping, Sequence

import numpy as np
import pandas as pd

from ..effects import CATALOGUE, FROM_START_TOLERANCE_S, Effect, apply_effect
from ..errors import InputError
from ..model import ThermalModel
from .compare import MeasuredSeries, initial_coefficients
from .criterion import BIC
from .parallel import map_in_workers
from .trajectory import ParametricSimulator, Scaling, parameter_scaling

COARSE_ONSETS = 12
MIN_TAIL_FRACTION = 0.05
#: Sample period of the onset grid search, s (the data are decimated to it; fits at full rate).
GRID_DT_S = 60.0
#: Effects whose onset is refined and values refitted on the full series, best grid BIC first.
POLISHED_CANDIDATES = 3
#: With effects found earlier, their onsets are searched again within this share of the record.
REONSET_FRACTION = 0.25
#: Gauss-Newton iterations and relative RSS tolerance of each fit in the onset search.
_SEARCH_ITERATIONS = 4
_SEARCH_TOLERANCE = 1e-2
_DIFFERENCE_STEP = 1e-5


def noise_std(outputs: np.ndarray) -> float:
    r"""Sensor noise standard deviation (K) estimated from the data alone.

    For white noise of variance :math:`\sigma^2` on a smooth signal, the second difference
    :math:`y_{k+1} - 2y_k + y_{k-1}` has variance :math:`6\sigma^2`; a robust scale (1.4826 × MAD)
    ignores the few samples at load steps. Pooled over sensors as the root mean variance.
    """
    variances = []
    for series in np.atleast_2d(outputs):
        d2 = series[2:] - 2 * series[1:-1] + series[:-2]
        d2 = d2[np.isfinite(d2)]
        if d2.size >= 10:
            variances.append((1.4826 * np.median(np.abs(d2 - np.median(d2)))) ** 2 / 6.0)
    return float(math.sqrt(np.mean(variances))) if variances else float("nan")


@dataclasses.dataclass(frozen=True)
class FoundEffect:
    """An effect accepted in an earlier iteration: values and onset (s and sample index), and the
    interval of onsets the data allow when its onset was profiled
    (:mod:`genthermal.diagnose.onset_profile`; (earliest, latest) s, else None)."""

    effect: str
    values: dict
    onset_s: float
    onset_index: int
    onset_interval_s: tuple | None = None


@dataclasses.dataclass(frozen=True)
class OnsetResponses:
    """Change of the sensor outputs an effect makes when it switches on at each onset of a grid.

    Attributes
    ----------
    onsets : numpy.ndarray
        Onset sample indices on the decimated series (:data:`GRID_DT_S`), shape (n_onsets,).
    changes : numpy.ndarray
        Outputs with the effect at its typical value (the fitted one when it has none) minus the
        outputs without it, K, shape (n_onsets, n_outputs, N) on the decimated series; NaN where
        the sensor has no sample.
    """

    onsets: np.ndarray
    changes: np.ndarray


@dataclasses.dataclass
class Candidate:
    """One catalogue effect fitted to the data.

    Attributes
    ----------
    effect : str
    values : dict
        Fitted effect parameters (model units).
    onset_s, onset_index : float, int
        Fitted onset: time (s) and sample index.
    rss : float
        Residual sum of squares with the effect, K².
    k : int
        Fitted effect parameters including the onset.
    rmse_before, rmse_after : float
        RMSE over every valid sensor sample without and with the effect, K.
    delta_bic : float
    found_values : dict
        Refitted values of earlier found effects (effect → values).
    predicted : numpy.ndarray
        Model outputs with the effect, (n_outputs, N), °C.
    found_onsets : dict
        Re-searched onset indices of earlier found effects (effect → index).
    significant : bool
    onset_responses : OnsetResponses or None
        What the effect alone does to the sensors from each onset of the coarse grid (the residual
        screen of the pair search, :func:`genthermal.diagnose.joint.residual_partners`).
    onset_profiles : list of OnsetProfile
        Set on the verdict: the criterion over its onset and the interval of onsets the data
        allow (:mod:`genthermal.diagnose.onset_profile`).
    """

    effect: str
    values: dict
    onset_s: float
    onset_index: int
    rss: float
    k: int
    rmse_before: float
    rmse_after: float
    delta_bic: float
    found_values: dict
    predicted: np.ndarray
    found_onsets: dict = dataclasses.field(default_factory=dict)
    significant: bool = False
    onset_responses: "OnsetResponses | None" = None
    onset_profiles: list = dataclasses.field(default_factory=list)

    def to_dict(self) -> dict:
        """The JSON entry of the ranking (with the onset interval on the verdict)."""
        entry = {"effect": self.effect, "params": self.values, "onset_s": self.onset_s,
                 "rmse_before": self.rmse_before, "rmse_after": self.rmse_after, "delta_ic": self.delta_bic,
                 "k": self.k, "significant": self.significant}
        if self.onset_profiles:
            entry["onset_interval_s"] = {p.effect: list(p.interval_s) for p in self.onset_profiles}
        return entry


def model_with_effects(model: ThermalModel, found: Sequence[FoundEffect], extra: str | None = None,
                       neutral: bool = False, source: str = "",
                       catalogue: Mapping[str, Effect] = CATALOGUE) -> ThermalModel:
    """``model`` with the found effects at their fitted values (``neutral``: at neutral values,
    the structure only) and the effect ``extra`` at neutral; names are looked up in ``catalogue``."""
    for item in found:
        effect = catalogue[item.effect]
        model = (model.with_effect(effect) if neutral else
                 apply_effect(model, effect, provenance="fitted", source=source, **item.values))
    return model.with_effect(catalogue[extra]) if extra else model


def _regimes(groups: Sequence[tuple[list[str], dict]]) -> list[dict]:
    """Parameter overrides of every subset of the onset groups (bit j set = group j active).

    Each group is ``(parameter names, {name: fitted name or value})``."""
    regimes = []
    for mask in range(2 ** len(groups)):
        overrides = {}
        for j, (_, values) in enumerate(groups):
            if mask >> j & 1:
                overrides.update(values)
        regimes.append(overrides)
    return regimes


def _indicator(n_samples: int, onsets: Sequence[int]) -> np.ndarray:
    code = np.zeros(n_samples, dtype=int)
    for j, onset in enumerate(onsets):
        code[int(onset):] += 2 ** j
    S = np.zeros((2 ** len(onsets), n_samples))
    S[code, np.arange(n_samples)] = 1.0
    return S


class _Problem:
    """Residuals of one set of fitted parameters for a fixed model structure.

    The decision vector ``z`` holds the scaled parameters and, with ``fit_initial_state``, the
    shifts ``(Δa, Δc/10 K)`` of the initial-state coefficients (within ±1 and ±5 K).
    """

    def __init__(self, simulator: ParametricSimulator, series: MeasuredSeries, scalings: Sequence[Scaling],
                 exact: bool = False, fit_initial_state: bool = False):
        self.simulator, self.scalings, self.exact = simulator, list(scalings), exact
        self.fit_initial_state = fit_initial_state
        self.mask = np.isfinite(series.outputs)
        self.target = np.where(self.mask, series.outputs, 0.0)
        self.valid = self.mask.T.ravel()
        bounds = [s.bounds() for s in self.scalings] + ([(-1.0, 1.0), (-0.5, 0.5)] if fit_initial_state else [])
        self.lower, self.upper = np.array(bounds, dtype=float).reshape(-1, 2).T

    def theta(self, z) -> np.ndarray:
        return np.array([s.value(float(v)) for s, v in zip(self.scalings, z)])

    def initial(self, z, x0_coefficients) -> np.ndarray:
        """Initial-state coefficients ``(a, c)`` of ``z``."""
        shift = np.array([z[-2], 10.0 * z[-1]]) if self.fit_initial_state else 0.0
        return np.asarray(x0_coefficients, dtype=float) + shift

    def residual(self, z, x0_coefficients, indicator) -> np.ndarray:
        """Model minus measurement on the valid samples, K."""
        Y = self.simulator.outputs(self.theta(z), self.initial(z, x0_coefficients), indicator)
        return (Y - self.target).T.ravel()[self.valid]

    def evaluate(self, z, x0_coefficients, indicator):
        """Residual vector and its Jacobian w.r.t. ``z``: exact (AD through the horizon) when
        ``self.exact``, else by forward differences (one extra trajectory per entry, about five
        times cheaper, ample for the onset search)."""
        if self.exact:
            theta = self.theta(z)
            n = len(self.scalings)
            if self.fit_initial_state:
                Y, jac = self.simulator.outputs_and_jacobian(theta, self.initial(z, x0_coefficients), indicator)
            else:
                Y, jac = self.simulator.outputs_and_theta_jacobian(theta, x0_coefficients, indicator)
            dtheta_dz = np.array([t if s.kind == "log" else s.scale for s, t in zip(self.scalings, theta)])
            scale = np.concatenate([dtheta_dz, [1.0, 10.0][:jac.shape[1] - n]])
            return (Y - self.target).T.ravel()[self.valid], jac[self.valid] * scale
        r = self.residual(z, x0_coefficients, indicator)
        columns = []
        for i in range(len(z)):
            step = _DIFFERENCE_STEP if z[i] + _DIFFERENCE_STEP <= self.upper[i] else -_DIFFERENCE_STEP
            shifted = np.array(z, dtype=float)
            shifted[i] += step
            columns.append((self.residual(shifted, x0_coefficients, indicator) - r) / step)
        return r, np.column_stack(columns)

    def gauss_newton(self, z0, x0_coefficients, indicator, iterations: int = 10,
                     tolerance: float = 1e-6) -> tuple[np.ndarray, float]:
        """Levenberg-Marquardt within the bounds until the RSS improves by less than the relative
        ``tolerance``; returns (z, RSS)."""
        z = np.clip(np.asarray(z0, dtype=float), self.lower, self.upper)
        r, J = self.evaluate(z, x0_coefficients, indicator)
        rss, damping = float(r @ r), 1e-3
        for _ in range(iterations):
            H, g = J.T @ J, J.T @ r
            step = np.linalg.solve(H + damping * np.diag(np.diag(H)) + 1e-12 * np.eye(z.size), -g)
            trial = np.clip(z + step, self.lower, self.upper)
            r_trial, J_trial = self.evaluate(trial, x0_coefficients, indicator)
            rss_trial = float(r_trial @ r_trial)
            if rss_trial < rss:
                converged = rss - rss_trial < tolerance * rss
                z, r, J, rss, damping = trial, r_trial, J_trial, rss_trial, damping / 10
                if converged:
                    break
            else:
                damping *= 10
        return z, rss


def decimated(series: MeasuredSeries, dt_s: float) -> MeasuredSeries:
    """``series`` on a coarser grid of about ``dt_s`` (an integer multiple of its step).

    Currents are replaced by their RMS over each window (so :math:`I^2` losses are kept), the
    other inputs by their mean; outputs are the samples at the window starts.
    """
    factor = int(dt_s // series.dt_s)
    if factor <= 1:
        return series
    n = series.time_s.size
    starts = np.arange(0, n, factor)
    windows = np.minimum(np.arange(factor)[None, :] + starts[:, None], n - 1)
    frame = series.inputs
    columns = {"time_s": series.time_s[starts]}
    for name in frame.columns.drop("time_s"):
        values = frame[name].to_numpy(dtype=float)[windows]
        columns[name] = np.sqrt(np.mean(values ** 2, axis=1)) if name.startswith("I_") else values.mean(axis=1)
    return MeasuredSeries(series.time_s[starts], series.dt_s * factor, pd.DataFrame(columns),
                          series.outputs[:, starts], series.source)


class _Structure:
    """A candidate's model structure on one series: simulator, residuals, x0 coefficients."""

    def __init__(self, simulator, series, scalings):
        self.series = series
        self.problem = _Problem(simulator, series, scalings)

    def indicator(self, onsets):
        return _indicator(self.series.time_s.size, onsets)

    def fit(self, onsets, z0, x0_coefficients, iterations: int = _SEARCH_ITERATIONS):
        return self.problem.gauss_newton(z0, x0_coefficients, self.indicator(onsets), iterations, _SEARCH_TOLERANCE)

    def search_onset(self, onsets, position, z_start, x0_coefficients, low=None, high=None):
        """Best index for ``onsets[position]`` (the others held) with its (z, RSS): a grid over the
        record then golden section between the best point's neighbours, or golden section in
        ``[low, high]`` when given."""
        n = self.series.time_s.size
        cache = {}

        def rss_at(onset, z0):
            if onset not in cache:
                trial = list(onsets)
                trial[position] = onset
                cache[onset] = self.fit(trial, z0, x0_coefficients)
            return cache[onset][1]

        def nearest_z(onset):
            return cache[min(cache, key=lambda o: abs(o - onset))][0] if cache else z_start

        if low is None:
            last = n - max(3, int(MIN_TAIL_FRACTION * n))
            grid = np.unique(np.linspace(0, last, COARSE_ONSETS).round().astype(int))
            for onset in grid:
                rss_at(int(onset), nearest_z(onset))
            best = int(np.searchsorted(grid, min(cache, key=lambda o: cache[o][1])))
            low, high = int(grid[max(best - 1, 0)]), int(grid[min(best + 1, grid.size - 1)])
        ratio = (math.sqrt(5) - 1) / 2
        while high - low > 2:
            a, b = int(round(high - ratio * (high - low))), int(round(low + ratio * (high - low)))
            b = b if b > a else a + 1
            if rss_at(a, nearest_z(a)) <= rss_at(b, nearest_z(b)):
                high = b
            else:
                low = a
        for onset in range(low, high + 1):
            rss_at(onset, nearest_z(onset))
        best = min(cache, key=lambda o: cache[o][1])
        return best, cache[best][0], cache[best][1]


def _refine_onsets(structure: _Structure, onsets, positions, z, x0_coefficients):
    """One pass of coordinate descent: each onset at ``positions`` searched again (golden section
    within ±:data:`REONSET_FRACTION` of the record) with every value refitted; returns (onsets, z)."""
    onsets, n = list(onsets), structure.series.time_s.size
    span = int(REONSET_FRACTION * n)
    for position in positions:
        onsets[position], z, _ = structure.search_onset(onsets, position, z, x0_coefficients,
                                                        max(onsets[position] - span, 0),
                                                        min(onsets[position] + span, n - 1))
    return onsets, z


class EffectSearch:
    """Fit catalogue effects to one measured series, given the effects already found.

    Building one fits nothing; :meth:`fit_found` refits the found effects and scores the model
    with them, then :meth:`rank` fits the candidates.

    Parameters
    ----------
    model : ThermalModel
        The model without the found effects.
    series : MeasuredSeries
    found : sequence of FoundEffect
        Effects accepted earlier; their values are refitted with the best candidates.
    cache : dict, optional
        Memo of the models with effects at neutral values and their simulators, reused by
        searches on the same ``model`` and series length (building them takes most of a search's
        time). Keys hold the model and Effect objects themselves, never an ``id``.
    catalogue : mapping of str to Effect
        The effects to search (default the catalogue of :mod:`genthermal.effects`); the found
        effects are looked up in it too.
    criterion : BIC, AIC or compatible, optional
        Scores each candidate against the model with the found effects only
        (:mod:`genthermal.diagnose.criterion`; default :class:`~genthermal.diagnose.criterion.BIC`).
    view : callable, optional
        Applied to every model after its effects, before it is simulated against the series
        (:class:`~genthermal.diagnose.phase_winding.PhaseResolved`: one winding node per phase
        sensor); the series' outputs are the view's. Hashable: it is part of the memo keys.
    """

    def __init__(self, model: ThermalModel, series: MeasuredSeries, found: Sequence[FoundEffect] = (),
                 cache: dict | None = None, catalogue: Mapping[str, Effect] = CATALOGUE, criterion=None,
                 view=None):
        self.model, self.series, self.found = model, series, list(found)
        self.catalogue = catalogue
        self.criterion = BIC() if criterion is None else criterion
        self.view = view
        self._cache = {} if cache is None else cache
        self.coarse = decimated(series, GRID_DT_S)
        self.noise = noise_std(series.outputs)
        self._found_names = [n for f in self.found for n in f.values]
        self.n_valid = int(np.isfinite(series.outputs).sum())
        self._full: dict[str, _Structure] = {}
        self._fitted = False

    def fit_found(self) -> "EffectSearch":
        """Refit the found effects (onsets by coordinate descent, then values and the initial state
        together) and score the model with them: ``rss_before``, ``predicted_before``,
        ``found_values``; returns self. The constructor fits nothing; every search method needs
        this first."""
        series = self.series
        base = self.neutral_model()
        groups = [(list(f.values), {n: n for n in f.values}) for f in self.found]
        simulator = self.simulator(None, series, self._found_names, groups)
        self.x0_coefficients = initial_coefficients(self.viewed(self.model), series)
        scalings = [parameter_scaling(base, n, start=v) for f in self.found for n, v in f.values.items()]
        onsets, z = _refine_onsets(_Structure(simulator, series, scalings), [f.onset_index for f in self.found],
                                   range(len(self.found)), np.zeros(len(scalings)), self.x0_coefficients)
        self.found = [dataclasses.replace(f, onset_index=o, onset_s=self.elapsed_s(o)) for f, o in zip(self.found, onsets)]
        self._found_onsets = onsets
        indicator = _indicator(series.time_s.size, onsets)
        problem = _Problem(simulator, series, scalings, exact=True, fit_initial_state=True)
        z, self.rss_before = problem.gauss_newton(np.concatenate([z, [0.0, 0.0]]), self.x0_coefficients, indicator)
        theta = problem.theta(z)
        self.predicted_before = simulator.outputs(theta, problem.initial(z, self.x0_coefficients), indicator)
        values = iter(theta)
        self.found_values = {f.effect: {n: float(next(values)) for n in f.values} for f in self.found}
        self._fitted = True
        return self

    def _require_fitted(self) -> None:
        if not self._fitted:
            raise InputError("EffectSearch", "not fitted", "call fit_found() before searching")

    def effect(self, name: str) -> Effect:
        """The effect called ``name`` in this search's catalogue."""
        if name not in self.catalogue:
            raise InputError("effect", name, f"not in the catalogue searched: {', '.join(self.catalogue)}")
        return self.catalogue[name]

    def elapsed_s(self, index: int) -> float:
        """Time of sample ``index`` from the start of the record, s."""
        return float(self.series.time_s[index] - self.series.time_s[0])

    def _effects_key(self, extra: str | None) -> tuple:
        """Memo key part: the found effects and ``extra`` as Effect objects (compared by value), so
        that two catalogues with an effect of the same name never share an entry."""
        return (tuple(self.effect(f.effect) for f in self.found), extra and self.effect(extra))

    def viewed(self, model: ThermalModel) -> ThermalModel:
        """``model`` as simulated against the series: through :attr:`view` when there is one (memoised)."""
        if self.view is None:
            return model
        key = ("view", model, self.view)
        if key not in self._cache:
            self._cache[key] = self.view(model)
        return self._cache[key]

    def neutral_model(self, extra: str | None = None) -> ThermalModel:
        """The model with the found effects and ``extra`` at neutral values (cached)."""
        key = ("model", self.model, self._effects_key(extra))
        if key not in self._cache:
            self._cache[key] = model_with_effects(self.model, self.found, extra, neutral=True,
                                                  catalogue=self.catalogue)
        return self._cache[key]

    def simulator(self, extra: str | None, series: MeasuredSeries, fitted, groups) -> ParametricSimulator:
        """Simulator of :meth:`neutral_model` on ``series`` (cached by structure and length)."""
        regimes = _regimes(groups)
        key = ("simulator", self.model, self.view, self._effects_key(extra), tuple(fitted), repr(regimes),
               series.time_s.size, series.dt_s)
        if key not in self._cache:
            self._cache[key] = ParametricSimulator(self.viewed(self.neutral_model(extra)), series.dt_s,
                                                   series.input_matrix, fitted, regimes)
        return self._cache[key].with_inputs(series.input_matrix)

    @property
    def output_names(self) -> list[str]:
        """The sensors fitted (the view's outputs when there is a view)."""
        return self.viewed(self.model).output_names

    @property
    def rmse_before(self) -> float:
        """RMSE of the model with the found effects (refitted), K."""
        return math.sqrt(self.rss_before / self.n_valid)

    def candidates(self) -> list[str]:
        """Catalogue effects the model (with the found effects) can still take."""
        current = self.neutral_model()
        return [name for name, effect in self.catalogue.items() if effect.unavailable_reason(current) is None]

    def _structure(self, effect_name: str, series: MeasuredSeries) -> _Structure:
        effect = self.effect(effect_name)
        model = self.neutral_model(effect_name)
        names = [p.name for p in effect.parameters]
        groups = [(list(v), dict(v)) for v in self.found_values.values()] + [(names, {n: n for n in names})]
        scalings = [parameter_scaling(model, p.name, typical=p.typical) for p in effect.parameters]
        return _Structure(self.simulator(effect_name, series, names, groups), series, scalings)

    def search(self, effect_name: str) -> Candidate:
        """Fit ``effect_name`` and its onset on the coarse grid; score it on the full series."""
        self._require_fitted()
        effect = self.effect(effect_name)
        coarse = self._structure(effect_name, self.coarse)
        z_start = [s.decision(p.typical if p.typical is not None else p.neutral)
                   for s, p in zip(coarse.problem.scalings, effect.parameters)]
        factor = int(round(self.coarse.dt_s / self.series.dt_s))
        onsets = [o // factor for o in self._found_onsets] + [0]
        latest = self._latest_onset(effect, self.coarse)
        onset, z, _ = coarse.search_onset(onsets, len(onsets) - 1, z_start, self.x0_coefficients,
                                          *((0, latest) if latest is not None else ()))
        full = self._full[effect_name] = self._structure(effect_name, self.series) if factor > 1 else coarse
        onset *= factor
        theta = full.problem.theta(z)
        predicted = full.problem.simulator.outputs(theta, self.x0_coefficients,
                                                   full.indicator([*self._found_onsets, onset]))
        rss = float(np.nansum((predicted - self.series.outputs) ** 2))
        values = {p.name: float(v) for p, v in zip(effect.parameters, theta)}
        candidate = self._candidate(effect_name, values, onset, rss, predicted, dict(self.found_values))
        candidate.onset_responses = self._onset_responses(coarse, effect, z, onsets)
        return candidate

    @staticmethod
    def _latest_onset(effect: Effect, series: MeasuredSeries) -> int | None:
        """Latest onset index on ``series`` a :attr:`~genthermal.effects.Effect.from_start` effect
        may take (:data:`~genthermal.effects.FROM_START_TOLERANCE_S`), None for the others."""
        if not effect.from_start:
            return None
        return min(int(FROM_START_TOLERANCE_S // series.dt_s), series.time_s.size - 1)

    def _onset_responses(self, coarse: _Structure, effect: Effect, z, onsets) -> OnsetResponses:
        """What ``effect`` alone changes in the outputs from each onset of the coarse grid, at its
        typical value (fitted value ``z`` for a parameter without one); ``onsets`` are the coarse
        onsets of the found effects and the candidate's (last)."""
        problem = coarse.problem
        fitted = problem.theta(z)
        theta = np.array([p.typical if p.typical is not None else v for p, v in zip(effect.parameters, fitted)])
        n = self.coarse.time_s.size
        grid = np.unique(np.linspace(0, n - max(3, int(MIN_TAIL_FRACTION * n)), COARSE_ONSETS).round().astype(int))
        without = problem.simulator.outputs(theta, self.x0_coefficients, coarse.indicator([*onsets[:-1], n]))
        changes = np.stack([problem.simulator.outputs(theta, self.x0_coefficients,
                                                      coarse.indicator([*onsets[:-1], int(onset)])) - without
                            for onset in grid])
        return OnsetResponses(grid, np.where(problem.mask[None], changes, np.nan))

    def polish(self, candidate: Candidate) -> Candidate:
        """Refine the onset on the full series (±one grid step, values refitted), then refit the
        candidate's and the found effects' values and the initial state together by Gauss-Newton
        with the exact Jacobian."""
        effect = self.effect(candidate.effect)
        if candidate.effect not in self._full:  # searched in a worker process
            self._full[candidate.effect] = self._structure(candidate.effect, self.series)
        full = self._full[candidate.effect]
        factor = int(round(self.coarse.dt_s / self.series.dt_s))
        z = [s.decision(candidate.values[p.name]) for s, p in zip(full.problem.scalings, effect.parameters)]
        onset = candidate.onset_index
        if factor > 1:  # golden section on the full series, values refitted at each onset
            latest = self._latest_onset(effect, self.series)
            high = min(onset + factor, self.series.time_s.size - 1, *(() if latest is None else (latest,)))
            onset, z, _ = full.search_onset([*self._found_onsets, onset], len(self.found), z, self.x0_coefficients,
                                            min(max(onset - factor, 0), high), high)
        theta = full.problem.theta(z)
        names = self._found_names + [p.name for p in effect.parameters]
        groups = [(list(f.values), {n: n for n in f.values}) for f in self.found]
        groups.append(([p.name for p in effect.parameters], {p.name: p.name for p in effect.parameters}))
        model = self.neutral_model(candidate.effect)
        simulator = self.simulator(candidate.effect, self.series, names, groups)
        start = [*(v for f in self.found for v in self.found_values[f.effect].values()), *theta]
        scalings = [parameter_scaling(model, n, start=v) for n, v in zip(names, start)]
        onsets, z = [*self._found_onsets, onset], np.zeros(len(names))
        if self.found:
            onsets, z = _refine_onsets(_Structure(simulator, self.series, scalings), onsets, range(len(onsets)),
                                       z, self.x0_coefficients)
        problem = _Problem(simulator, self.series, scalings, exact=True, fit_initial_state=True)
        indicator = _indicator(self.series.time_s.size, onsets)
        z, rss = problem.gauss_newton(np.concatenate([z, [0.0, 0.0]]), self.x0_coefficients, indicator)
        if rss >= candidate.rss:
            return candidate
        values = dict(zip(names, (float(v) for v in problem.theta(z))))
        found_values = {f.effect: {n: values[n] for n in f.values} for f in self.found}
        predicted = simulator.outputs(problem.theta(z), problem.initial(z, self.x0_coefficients), indicator)
        polished = self._candidate(candidate.effect, {p.name: values[p.name] for p in effect.parameters},
                                   onsets[-1], rss, predicted, found_values,
                                   {f.effect: o for f, o in zip(self.found, onsets)})
        polished.onset_responses = candidate.onset_responses
        return polished

    def _candidate(self, name, values, onset, rss, predicted, found_values, found_onsets=None) -> Candidate:
        k = len(values) + 1
        rss = max(rss, 1e-300)
        found_onsets = found_onsets or {f.effect: f.onset_index for f in self.found}
        candidate = Candidate(name, values, self.elapsed_s(onset), int(onset),
                              rss, k, self.rmse_before, math.sqrt(rss / self.n_valid),
                              self.criterion.delta(rss, self.rss_before, self.n_valid, k), found_values, predicted,
                              found_onsets)
        return candidate

    def rank(self, effects: Sequence[str] | None = None, workers: int = 1) -> list[Candidate]:
        """Fit every candidate effect (or ``effects``), polish the best, rank by ΔBIC; with
        ``workers`` > 1 the candidates are searched, then the best polished, in forked processes
        (:mod:`genthermal.diagnose.parallel`), with the same result."""
        self._require_fitted()
        names = self.candidates() if effects is None else list(effects)
        ranked = sorted(map_in_workers(self.search, names, workers), key=lambda c: c.delta_bic)
        ranked[:POLISHED_CANDIDATES] = map_in_workers(self.polish, ranked[:POLISHED_CANDIDATES], workers)
        return sorted(ranked, key=lambda c: c.delta_bic)
