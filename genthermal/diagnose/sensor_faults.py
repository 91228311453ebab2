"""Sensor faults as hypotheses: fitted like effects, but they change the measurement, not the model.

Every kind of :mod:`genthermal.sensor_faults` is a shape of a sensor's reference signal, fitted at
every onset of a grid and scored by ΔBIC like an effect. Redundant sensors (the phase PT100s) are
screened on their disagreement without a model (:func:`screen_redundant`); single sensors on the
model residual against the physical effects (:func:`screen_against_model`), which a fault must
beat by :data:`PREFERENCE_BIC`; :func:`screen_noise` finds a noise increase. Method:
``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Mapping, Sequence

import numpy as np

from ..sensor_faults import MIN_NOISE_FACTOR, SensorFault
from .search import noise_std
from .sensor_plausibility import robust_scale

#: Onset grid of the shape fits, samples between grid points (then every sample near the best).
ONSET_GRID = 10
#: Onsets leave at least this share of the record after them.
MIN_TAIL_FRACTION = 0.03
#: A sensor fault must beat the best other explanation (heat flow) by this ΔBIC (as
#: :data:`genthermal.diagnose.discover.AMBIGUITY_BIC`: closer is "cannot tell").
PREFERENCE_BIC = 10.0
#: The second differences of white noise are correlated (lag 1: -4/6, lag 2: 1/6), so a variance
#: estimated from n of them varies as one from n / (1 + 2 (16 + 1) / 36) independent samples
#: (Bartlett's formula): the likelihood ratio of a noise change is divided by this factor. Without
#: it, chance alone passed the ΔBIC threshold on 12-20 samples at the end of healthy 60-s records.
D2_VARIANCE_INFLATION = 1.0 + 2.0 * (16.0 + 1.0) / 36.0
#: Time constants of the local heat-flow alternative of a phase sensor, s (the fastest winding
#: mode of the thesis model is 6.5 min; the slowest about an hour).
HEAT_TIME_CONSTANTS_S = (300.0, 900.0, 2700.0)
#: Shapes fitted, simplest first: a later kind must beat an earlier one of the same sensor by
#: :data:`PREFERENCE_BIC` (a gain error on a steady temperature looks like a bias).
SHAPE_KINDS = ("bias", "drift", "stuck", "gain")


@dataclasses.dataclass
class SensorHypothesis:
    """A sensor fault fitted to a record.

    Attributes
    ----------
    fault : SensorFault
    onset_index : int
        Sample of the onset.
    rmse_before, rmse_after : float
        RMSE of the scored signal without and with the fault, K (redundant sensors: the
        disagreement; single sensors: all model outputs).
    delta_bic : float
    evidence : str
        ``"redundancy"`` (disagreement with the other sensors of its output), ``"model"`` (model
        residual, compared with the physical effects), ``"noise"`` (variance change), ``"input"``
        (an input sensor, through the model's response to it), ``"jump"`` (a step no heat flow
        can make) or ``"frozen"`` (the reading's noise vanished:
        :mod:`~genthermal.diagnose.onset_signatures`).
    signal : numpy.ndarray
        Fitted :math:`f_c(t)`, K (what the fault adds to the reading).
    alternative : str
        The best other explanation tried and its ΔBIC.
    columns : tuple of str
        Record columns the reading comes from (several when one value is logged in the three
        phase columns); default the sensor's own.
    output : str
        Model output the sensor is read for.
    """

    fault: SensorFault
    onset_index: int
    rmse_before: float
    rmse_after: float
    delta_bic: float
    evidence: str
    signal: np.ndarray
    alternative: str = ""
    columns: tuple = ()
    output: str = ""

    def __post_init__(self):
        self.columns = tuple(self.columns) or (self.fault.sensor,)

    @property
    def drops_reading(self) -> bool:
        """True when the sensor's reading is dropped from the onset rather than corrected: it is
        stuck or noisy and its output has other sensors, or it froze (what it should read after
        the onset is not in the record)."""
        return self.fault.kind in ("stuck", "noise") and self.evidence in ("redundancy", "frozen")

    def to_dict(self) -> dict:
        """JSON entry."""
        return {**self.fault.to_dict(), "evidence": self.evidence, "rmse_before": self.rmse_before,
                "rmse_after": self.rmse_after, "delta_ic": self.delta_bic, "alternative": self.alternative}


def _bic(rss_after: float, rss_before: float, n: int, k: int) -> float:
    return n * math.log(max(rss_after, 1e-300) / max(rss_before, 1e-300)) + k * math.log(n)


def _onset_grid(n: int, first: int) -> np.ndarray:
    last = n - max(3, int(MIN_TAIL_FRACTION * n))
    return np.arange(first, max(last, first + 1), ONSET_GRID)


def _least_squares(target: np.ndarray, design: np.ndarray) -> tuple[np.ndarray, float]:
    coefficients, *_ = np.linalg.lstsq(design, target, rcond=None)
    residual = target - design @ coefficients
    return coefficients, float(residual @ residual)


def _shape_column(kind: str, onset: int, elapsed_s: np.ndarray, truth: np.ndarray) -> np.ndarray:
    step = (np.arange(elapsed_s.size) >= onset).astype(float)
    if kind == "drift":
        return step * (elapsed_s - elapsed_s[onset]) / 3600.0
    if kind == "gain":
        return step * truth
    return step  # bias; stuck (target shifted by the truth, see fit_shape)


def fit_shape(kind: str, reference, truth, elapsed_s, baseline=None, onsets=None):
    """Best onset and value of one shape on ``reference`` (NaN samples ignored).

    Parameters
    ----------
    kind : {"bias", "drift", "stuck", "gain"}
    reference : array_like
        What the sensor read minus what it should read, K.
    truth : array_like
        Estimate of the sensor's true temperature, °C (gain and stuck).
    elapsed_s : array_like
        Time from the start, s.
    baseline : array_like, optional
        (N, m) terms always fitted (offset, unbalance), with and without the fault.
    onsets : array_like, optional
        Onsets to try (default: the grid, then every sample near its best).

    Returns
    -------
    (value, onset_index, rss_before, rss_after, signal)
        ``value`` in the unit of the kind (K, K/h, °C, relative); ``signal`` the fitted
        :math:`f_c(t)`, K.
    """
    reference, truth = np.asarray(reference, float), np.asarray(truth, float)
    elapsed_s = np.asarray(elapsed_s, float)
    n = reference.size
    ok = np.isfinite(reference) & np.isfinite(truth)
    base = np.zeros((n, 0)) if baseline is None else np.asarray(baseline, float).reshape(n, -1)
    if base.shape[1]:
        _, rss_before = _least_squares(reference[ok], base[ok])
    else:
        rss_before = float(reference[ok] @ reference[ok])

    def rss_at(onset):
        column = _shape_column(kind, onset, elapsed_s, truth)
        target = reference + truth * column if kind == "stuck" else reference
        coefficients, rss = _least_squares(target[ok], np.column_stack([base, column])[ok])
        return rss, float(coefficients[-1])

    first = 0 if kind == "drift" else 1
    if kind == "gain" and onsets is None:
        onsets = (0,)  # a scale error is there from the start
    if onsets is None:
        grid = _onset_grid(n, first)
        coarse = {int(o): rss_at(int(o)) for o in grid}
        best = min(coarse, key=lambda o: coarse[o][0])
        fine = range(max(first, best - ONSET_GRID), min(n - 3, best + ONSET_GRID + 1))
        results = {**coarse, **{o: rss_at(o) for o in fine if o not in coarse}}
    else:
        results = {int(o): rss_at(int(o)) for o in onsets}
    onset = min(results, key=lambda o: results[o][0])
    rss_after, value = results[onset]
    column = _shape_column(kind, onset, elapsed_s, truth)
    signal = (value - truth) * column if kind == "stuck" else value * column
    return value, onset, rss_before, rss_after, signal


def fit_noise_increase(reading, elapsed_s) -> tuple[float, int, float]:
    """Variance change-point of a sensor's noise.

    Returns
    -------
    (factor, onset_index, delta_bic)
        Noise standard deviation after the onset over the one before (robust scales of the second
        differences), and the ΔBIC of the change (likelihood ratio of two Gaussian variances over
        :data:`D2_VARIANCE_INFLATION`, two parameters).
    """
    reading = np.asarray(reading, float)
    d2 = reading[2:] - 2 * reading[1:-1] + reading[:-2]
    valid = np.flatnonzero(np.isfinite(d2))
    d2 = d2[valid]
    n = d2.size
    if n < 40:
        return 1.0, 0, 0.0

    best = (0.0, 0, 1.0)
    for k in _onset_grid(n, 20):
        before, after = robust_scale(d2[:k]) ** 2 + 1e-12, robust_scale(d2[k:]) ** 2 + 1e-12
        pooled = (k * before + (n - k) * after) / n
        statistic = k * math.log(pooled / before) + (n - k) * math.log(pooled / after)
        if statistic > best[0]:
            best = (statistic, int(k), math.sqrt(after / before))
    statistic, k, factor = best
    onset = int(valid[min(k, valid.size - 1)]) + 1
    return factor, onset, -statistic / D2_VARIANCE_INFLATION + 2 * math.log(n)


def fit_local_heat(reference, response, decay: float, baseline) -> tuple[float, float]:
    r"""Best fit of a heat flow switched on at an onset: the first-order response
    :math:`s_k = a\,s_{k-1} + (1-a)\,x_k H(k-k_0)` to a load regressor :math:`x` (``response`` is
    the response to :math:`x` from the start, so :math:`s = \text{response} - a^{k-k_0+1}\,
    \text{response}_{k_0-1}` from the onset), scaled by a fitted gain. Returns (RSS without, RSS
    with), K²."""
    reference, response = np.asarray(reference, float), np.asarray(response, float)
    n = reference.size
    ok = np.isfinite(reference)
    base = np.asarray(baseline, float).reshape(n, -1)
    _, rss_before = _least_squares(reference[ok], base[ok])
    index = np.arange(n)
    best = rss_before
    for onset in np.r_[0, _onset_grid(n, 1)]:
        column = np.where(index >= onset, response - (response[onset - 1] if onset else 0.0)
                          * decay ** (index - onset + 1), 0.0)
        _, rss = _least_squares(reference[ok], np.column_stack([base, column])[ok])
        best = min(best, rss)
    return rss_before, best


def _lowpass(signal: np.ndarray, dt_s: float, tau_s: float) -> np.ndarray:
    a = math.exp(-dt_s / tau_s)
    out, state = np.empty_like(signal), 0.0
    for i, value in enumerate(signal):
        state = a * state + (1 - a) * value
        out[i] = state
    return out


def mean_of_finite(rows) -> np.ndarray:
    """Sample-wise mean of the finite values of ``rows`` (sequence of equal-length arrays); NaN
    where none is finite (a gap in every sensor of an output), without numpy's empty-slice warning."""
    stacked = np.asarray(rows, dtype=float)
    finite = np.isfinite(stacked)
    count = finite.sum(axis=0)
    total = np.where(finite, stacked, 0.0).sum(axis=0)
    return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def sensor_columns(interface) -> dict:
    """Model output → the record columns it is read from (the machine's sensor schema)."""
    return {sensor.output: tuple(sensor.columns) for sensor in interface.sensors}


def sensor_groups(readings: Mapping[str, np.ndarray], columns: Mapping[str, Sequence[str]]) -> dict:
    """Output → the distinct sensors read for it (sensors identical to another are one sensor: a
    record that logs one winding value in the three phase columns has one winding sensor).
    ``columns``: :func:`sensor_columns`."""
    groups = {}
    for output in columns:
        distinct = []
        for name in output_columns(readings, output, columns):
            if not any(np.array_equal(readings[name], readings[other], equal_nan=True) for other in distinct):
                distinct.append(name)
        groups[output] = distinct
    return groups


def output_columns(readings: Mapping[str, np.ndarray], output: str, columns: Mapping[str, Sequence[str]]) -> list:
    """The record columns of ``readings`` that ``output`` is read from."""
    return [s for s in columns.get(output, (output,)) if s in readings]


def screen_redundant(readings: dict, inputs, elapsed_s: np.ndarray, dt_s: float, columns: Mapping,
                     phase_inputs: Sequence[str] = ()) -> list:
    """Sensor faults visible as one sensor disagreeing with the others of its output (module
    docstring), at most one per output (two sensors left cannot tell which is wrong).

    Parameters
    ----------
    readings : dict
        Sensor column → reading on the series grid, °C.
    inputs : pandas.DataFrame
        The series inputs (phase currents, A).
    elapsed_s : numpy.ndarray
    dt_s : float
    columns : mapping
        :func:`sensor_columns`.
    phase_inputs : sequence of str
        Per-phase current inputs, in the order of a redundant output's columns (a phase's own
        extra :math:`I^2` is in the baseline); empty: the baseline is the offset alone.

    Returns
    -------
    list of SensorHypothesis
    """
    from .discover import passes_tests

    found = []
    groups = sensor_groups(readings, columns)
    currents = [p for p in phase_inputs if p in inputs]
    mean_square = np.mean([inputs[p].to_numpy(float) ** 2 for p in currents], axis=0) if currents else \
        np.zeros(elapsed_s.size)
    heat = {tau: _lowpass(mean_square, dt_s, tau) for tau in HEAT_TIME_CONSTANTS_S}
    for output, names in groups.items():
        if len(names) < 3:
            continue
        best = None
        for name in names:
            others = mean_of_finite([readings[o] for o in names if o != name])
            disagreement = readings[name] - others
            position = list(columns[output]).index(name)
            phase = currents[position] if len(currents) == len(columns[output]) else None
            own = (inputs[phase].to_numpy(float) ** 2 - mean_square) if phase else np.zeros_like(mean_square)
            baseline = np.column_stack([np.ones_like(own), _lowpass(own, dt_s, HEAT_TIME_CONSTANTS_S[1])])
            noise = noise_std(disagreement[None, :])
            for kind in SHAPE_KINDS:
                value, onset, before, after, signal = fit_shape(kind, disagreement, others, elapsed_s, baseline)
                n = int(np.isfinite(disagreement).sum())
                delta = _bic(after, before, n, 2)
                if best is None or delta < best[0] - (PREFERENCE_BIC if best[1] == name else 0):
                    best = (delta, name, kind, value, onset, before, after, signal, noise, disagreement,
                            others, baseline, n)
        delta, name, kind, value, onset, before, after, signal, noise, disagreement, others, baseline, n = best
        rmse_before, rmse_after = math.sqrt(before / n), math.sqrt(after / n)
        if not passes_tests(rmse_before, rmse_after, delta, noise):
            continue
        alternatives = []
        for tau, response in heat.items():
            b, a = fit_local_heat(disagreement, response, math.exp(-dt_s / tau), baseline)
            alternatives.append((_bic(a, b, n, 2), tau))
        heat_bic, heat_tau = min(alternatives)
        if heat_bic <= delta + PREFERENCE_BIC:
            continue
        fault = SensorFault(name, kind, float(value), float(elapsed_s[onset]))
        found.append(SensorHypothesis(fault, int(onset), rmse_before, rmse_after, delta, "redundancy", signal,
                                      f"local heat flow (τ = {heat_tau / 60:.0f} min) ΔBIC {heat_bic:.0f}",
                                      output=output))
    return found


def screen_noise(readings: dict, elapsed_s: np.ndarray, columns: Mapping) -> list:
    """Sensors whose noise grew by at least :data:`MIN_NOISE_FACTOR` from an onset (``columns``:
    :func:`sensor_columns`)."""
    found = []
    groups = sensor_groups(readings, columns)
    for output in columns:
        for name in groups[output]:
            factor, onset, delta = fit_noise_increase(readings[name], elapsed_s)
            if factor >= MIN_NOISE_FACTOR and delta < -PREFERENCE_BIC:
                fault = SensorFault(name, "noise", float(factor), float(elapsed_s[onset]))
                found.append(SensorHypothesis(fault, onset, float("nan"), float("nan"), delta,
                                              "redundancy" if len(groups[output]) > 1 else "noise",
                                              np.zeros(elapsed_s.size), "", output=output))
    return found


def screen_against_model(measured: np.ndarray, predicted: np.ndarray, readings: dict, elapsed_s: np.ndarray,
                         output_names, columns: Mapping, exclude=(), outputs=None,
                         onsets=None) -> SensorHypothesis | None:
    """The best sensor fault of a single-sensor output, scored on the RSS over all outputs.

    Parameters
    ----------
    measured, predicted : numpy.ndarray
        (n_outputs, N) measured and model outputs, °C.
    readings : dict
        Sensor column → reading, °C (which outputs have a single sensor: :func:`sensor_groups`).
    elapsed_s : numpy.ndarray
    output_names : sequence of str
    columns : mapping
        :func:`sensor_columns`.
    exclude : collection of str
        Sensors already explained.
    outputs : collection of str, optional
        Only faults of the sensors of these outputs (a detector already says which sensor moved).
    onsets : array_like, optional
        Onset sample indices to try (default: the whole record).
    """
    residual = measured - predicted
    valid = np.isfinite(residual)
    n = int(valid.sum())
    rss_before = float(np.nansum(residual ** 2))
    groups, best = sensor_groups(readings, columns), None
    for i, output in enumerate(output_names):
        sensors = groups.get(output, [])
        if len(sensors) != 1 or sensors[0] in exclude or (outputs is not None and output not in outputs):
            continue
        for kind in SHAPE_KINDS:
            value, onset, before, after, signal = fit_shape(kind, residual[i], predicted[i], elapsed_s, onsets=onsets)
            rss_after = rss_before - before + after
            delta = _bic(rss_after, rss_before, n, 2)
            if best is None or delta < best.delta_bic - (PREFERENCE_BIC if best.output == output else 0):
                present = output_columns(readings, output, columns)
                sensor = present[0] if len(present) == 1 else output
                best = SensorHypothesis(SensorFault(sensor, kind, float(value), float(elapsed_s[onset])), onset,
                                        math.sqrt(rss_before / n), math.sqrt(rss_after / n), delta, "model", signal,
                                        columns=tuple(present), output=output)
    return best


def corrected_readings(readings: dict, hypotheses: Sequence[SensorHypothesis]) -> dict:
    """``readings`` with the faults removed: the fitted signal subtracted, or the sensor dropped
    (NaN) from the onset when it is stuck or noisy and its output has other sensors."""
    corrected = {name: np.array(values, dtype=float) for name, values in readings.items()}
    for hypothesis in hypotheses:
        for name in (c for c in hypothesis.columns if c in corrected):
            if hypothesis.drops_reading:
                corrected[name][hypothesis.onset_index:] = np.nan
            elif hypothesis.fault.kind != "noise":
                corrected[name] = corrected[name] - hypothesis.signal
    return corrected


def outputs_from(readings: dict, output_names, columns: Mapping) -> np.ndarray:
    """Model outputs from sensor readings: the mean of each output's sensors (NaN-aware)."""
    rows = []
    for output in output_names:
        names = output_columns(readings, output, columns)
        rows.append(mean_of_finite([readings[s] for s in names]))
    return np.array(rows)
