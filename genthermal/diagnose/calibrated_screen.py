"""Sensor faults against physical effects on top of a calibration-level misfit.

On a plant the model misses by kelvins, every hypothesis (a sensor's or input sensor's bias or
drift, a physical effect from an onset) is fitted jointly with the model's linear sensitivities
to its uncertain parameters, an offset per sensor and the misfits present from the start
(:class:`CalibratedFrame`), and scored by ΔBIC on what is left. The best sensor hypothesis is
claimed when it passes the tests of :func:`~genthermal.diagnose.discover.passes_tests` and beats
the best physical effect. Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import math

import numpy as np

from ..simulate import simulate
from ..sensor_faults import SensorFault
from .sensor_faults import ONSET_GRID, SensorHypothesis, _onset_grid, output_columns, sensor_groups

#: Relative parameter step of the calibration sensitivities (finite difference).
RELATIVE_STEP = 0.05
#: Onsets of the hypotheses leave this share of the record before them: a fault from the first
#: minutes is a calibration offset (the record cannot tell them apart).
MIN_ONSET_FRACTION = 0.05
#: An input sensor's fault must show in its logged reading within this share of its size.
LOGGED_AGREEMENT = 0.5
#: Onsets of the first pass at most (a long record is searched on a coarser grid, then every
#: sample near the best): each costs a projection of the whole stacked record.
MAX_GRID_ONSETS = 200
#: Shapes of a sensor's fault fitted here (a frozen reading and a jump:
#: :mod:`~genthermal.diagnose.onset_signatures`).
CALIBRATED_KINDS = ("bias", "drift")


def calibration_sensitivities(model, inputs, output_names, parameters) -> np.ndarray:
    """Change of the outputs per relative change of each of ``parameters``, K.

    Parameters
    ----------
    model : ThermalModel
    inputs : pandas.DataFrame
        ``time_s`` and the model inputs.
    output_names : sequence of str
    parameters : sequence of str
        Parameters of ``model`` (others are skipped).

    Returns
    -------
    numpy.ndarray
        (n_parameters, n_outputs, N): outputs with the parameter times ``1 + RELATIVE_STEP``
        minus the outputs, over ``RELATIVE_STEP``.
    """
    base = simulate(model, inputs)
    rows = []
    for name in (p for p in parameters if p in model.parameters):
        value = float(model.parameters[name].value)
        changed = simulate(model.with_parameters(source="calibration sensitivity",
                                                 **{name: value * (1 + RELATIVE_STEP)}), inputs)
        rows.append(np.array([(changed[o].to_numpy(float) - base[o].to_numpy(float)) / RELATIVE_STEP
                              for o in output_names]))
    return np.array(rows).reshape(len(rows), len(output_names), len(inputs))


class CalibratedFrame:
    """The residual with the calibration nuisance projected off (module docstring).

    Parameters
    ----------
    residual : numpy.ndarray
        (n_outputs, N) measured minus model outputs, K.
    sensitivities : numpy.ndarray
        (n_terms, n_outputs, N): :func:`calibration_sensitivities` and any other misfit present
        from the first sample (:func:`misfit_from_start`).
    """

    def __init__(self, residual: np.ndarray, sensitivities: np.ndarray):
        sensitivities = np.asarray(sensitivities, float).reshape(-1, *residual.shape)
        self.shape = residual.shape
        self.valid = np.isfinite(residual).ravel()
        n_outputs = residual.shape[0]
        offsets = [np.repeat(np.eye(n_outputs)[i][:, None], residual.shape[1], axis=1) for i in range(n_outputs)]
        columns = [s.ravel() for s in sensitivities] + [o.ravel() for o in offsets]
        nuisance = np.column_stack(columns)[self.valid]
        nuisance = nuisance[:, np.isfinite(nuisance).all(axis=0) & (np.abs(nuisance).max(axis=0) > 0)]
        self.basis, _ = np.linalg.qr(nuisance / np.maximum(np.linalg.norm(nuisance, axis=0), 1e-300))
        self.target = self.project(np.nan_to_num(residual))
        self.rss = float(self.target @ self.target)
        self.n = int(self.valid.sum())

    def project(self, stacked: np.ndarray) -> np.ndarray:
        """The valid samples of ``stacked`` ((n_outputs, N) or (n_outputs·N,)) with the nuisance
        projected off."""
        vector = np.asarray(stacked, float).ravel()[self.valid]
        return vector - self.basis @ (self.basis.T @ vector)

    def fit(self, shapes) -> tuple[float, np.ndarray]:
        """Least-squares fit of the shapes (each (n_outputs, N)) on top of the nuisance: the RSS
        left, K², and their sizes."""
        design = np.column_stack([self.project(s) for s in shapes])
        sizes, *_ = np.linalg.lstsq(design, self.target, rcond=None)
        left = self.target - design @ sizes
        return float(left @ left), sizes

    def delta_bic(self, rss: float, k: int = 2) -> float:
        """:math:`N\\ln(RSS/RSS_\\perp) + k\\ln N`."""
        return self.n * math.log(max(rss, 1e-300) / max(self.rss, 1e-300)) + k * math.log(self.n)


def misfit_from_start(responses: dict, ranked, coarse_time_s, time_s) -> list:
    """Nuisance terms a calibration cannot tell from a fault present from the first sample.

    Parameters
    ----------
    responses : dict
        Input sensor → (n_outputs, N) response of the outputs to a 1-K offset of it.
    ranked : sequence of Candidate
        Physical effects with ``onset_responses`` (their change from onset 0, on the decimated
        grid ``coarse_time_s``, is one term).
    coarse_time_s, time_s : numpy.ndarray
        Times of the decimated grid and of the series, s.

    Returns
    -------
    list of numpy.ndarray
        (n_outputs, N) each.
    """
    terms = list(responses.values())
    for candidate in ranked:
        onset_responses = getattr(candidate, "onset_responses", None)
        if onset_responses is not None and onset_responses.onsets.size and onset_responses.onsets[0] == 0:
            terms.append(on_series_grid(onset_responses.changes[0], coarse_time_s, time_s))
    return terms


def on_series_grid(change: np.ndarray, coarse_time_s, time_s) -> np.ndarray:
    """(n_outputs, N_coarse) change on the decimated grid → (n_outputs, N) on the series grid."""
    return np.array([np.interp(time_s, coarse_time_s, row) for row in np.nan_to_num(change)])


def _first_onset(n: int) -> int:
    return max(1, int(MIN_ONSET_FRACTION * n))


def _best_onset(frame: CalibratedFrame, shape_at, n: int) -> tuple[float, int, float]:
    """(rss, onset, size) of the best onset of ``shape_at(onset)`` (grid, then every sample near
    the best)."""
    def scored(onset):
        rss, sizes = frame.fit([shape_at(onset)])
        return rss, float(sizes[0])

    spacing = max(ONSET_GRID, n // MAX_GRID_ONSETS)
    grid = _onset_grid(n, _first_onset(n))[::max(1, spacing // ONSET_GRID)]
    coarse = {int(o): scored(int(o)) for o in grid}
    centre = min(coarse, key=lambda o: coarse[o][0])
    near = range(max(_first_onset(n), centre - spacing), min(n - 3, centre + spacing + 1))
    results = {**coarse, **{o: scored(o) for o in near if o not in coarse}}
    onset = min(results, key=lambda o: results[o][0])
    return results[onset][0], onset, results[onset][1]


def sensor_hypotheses(frame: CalibratedFrame, readings, elapsed_s, output_names, columns, exclude=()) -> list:
    """The best bias and drift of every single-sensor output in the calibrated frame:
    (ΔBIC, rss, SensorHypothesis) each."""
    n, found = elapsed_s.size, []
    groups = sensor_groups(readings, columns)
    for i, output in enumerate(output_names):
        sensors = groups.get(output, [])
        if len(sensors) != 1 or sensors[0] in exclude:
            continue
        present = output_columns(readings, output, columns)
        for kind in CALIBRATED_KINDS:
            def shape_at(onset, kind=kind, i=i):
                shape = np.zeros(frame.shape)
                after = np.arange(n) >= onset
                shape[i] = after * ((elapsed_s - elapsed_s[onset]) / 3600.0 if kind == "drift" else 1.0)
                return shape

            rss, onset, value = _best_onset(frame, shape_at, n)
            sensor = present[0] if len(present) == 1 else output
            hypothesis = SensorHypothesis(SensorFault(sensor, kind, value, float(elapsed_s[onset])), onset,
                                          math.sqrt(frame.rss / frame.n), math.sqrt(rss / frame.n),
                                          frame.delta_bic(rss), "calibrated", value * shape_at(onset)[i],
                                          columns=tuple(present), output=output)
            found.append(hypothesis)
    return found


def logged_input_shows(logged, elapsed_s, kind: str, value: float, onset: int) -> bool:
    """Whether the logged input itself shows a fault of ``kind`` and size ``value`` from sample
    ``onset``: a bias is a jump of the reading (the largest one-sample change within
    :data:`~genthermal.diagnose.sensor_faults.ONSET_GRID` samples of the onset), a drift a change
    of its slope (least-squares lines before and after the onset), each within
    :data:`LOGGED_AGREEMENT` of ``value`` (K, K/h). A real change of the input at the same moment
    that hides the fault is not expected; without it, an error the reading does not show is not
    the sensor's (a better-cooled frame fits like a warmer ambient reading, but the ambient
    reading did not move)."""
    logged, elapsed_s = np.asarray(logged, float), np.asarray(elapsed_s, float)
    n = logged.size
    if kind == "bias":
        near = slice(max(1, onset - ONSET_GRID), min(n, onset + ONSET_GRID + 1))
        steps = np.diff(logged)[near.start - 1:near.stop - 1]
        shown = float(steps[np.argmax(np.abs(steps))]) if steps.size else 0.0
    else:
        before, after = slice(max(0, onset - max(onset // 2, 10)), onset), slice(onset, n)
        if before.stop - before.start < 2 or n - onset < 2:
            return False
        slope = [np.polyfit(elapsed_s[part] / 3600.0, logged[part], 1)[0] for part in (before, after)]
        shown = float(slope[1] - slope[0])
    return abs(shown - value) <= LOGGED_AGREEMENT * abs(value)


def input_hypotheses(frame: CalibratedFrame, responses: dict, elapsed_s, dt_s: float, inputs=None) -> list:
    """The best bias and drift of every input sensor in the calibrated frame (``responses``:
    input → (n_outputs, N) response to a 1-K step at the first sample); with ``inputs`` (the
    logged inputs), only those the logged reading shows (:func:`logged_input_shows`)."""
    n, found = elapsed_s.size, []
    for name, step in responses.items():
        shapes = {"bias": step, "drift": np.cumsum(step, axis=1) * dt_s / 3600.0}
        for kind, response in shapes.items():
            def shape_at(onset, response=response):
                shifted = np.zeros_like(response)
                shifted[:, onset:] = -response[:, :n - onset]
                return shifted

            rss, onset, value = _best_onset(frame, shape_at, n)
            if inputs is not None and not logged_input_shows(inputs[name].to_numpy(float), elapsed_s, kind, value,
                                                             onset):
                continue
            after = (np.arange(n) >= onset).astype(float)
            error = value * (after if kind == "bias" else after * (elapsed_s - elapsed_s[onset]) / 3600.0)
            found.append(SensorHypothesis(SensorFault(name, kind, value, float(elapsed_s[onset])), onset,
                                          math.sqrt(frame.rss / frame.n), math.sqrt(rss / frame.n),
                                          frame.delta_bic(rss), "input", error, columns=(name,), output=""))
    return found


def best_physical(frame: CalibratedFrame, ranked, coarse_time_s, time_s) -> tuple[float, str]:
    """The best physical effect of ``ranked`` (Candidates with ``onset_responses``) in the
    calibrated frame: (ΔBIC, effect name); (inf, "") when none has responses."""
    best = (math.inf, "")
    for candidate in ranked:
        responses = getattr(candidate, "onset_responses", None)
        if responses is None:
            continue
        on_grid = np.array([on_series_grid(change, coarse_time_s, time_s) for change in responses.changes])
        for k in range(1 if responses.onsets[0] == 0 else 0, on_grid.shape[0]):
            pair = [on_grid[k]] + ([on_grid[k + 1]] if k + 1 < on_grid.shape[0] else [])
            if not any(np.abs(s).max() > 0 for s in pair):
                continue
            rss, _ = frame.fit(pair)
            delta = frame.delta_bic(rss)
            if delta < best[0]:
                best = (delta, candidate.effect)
    return best
