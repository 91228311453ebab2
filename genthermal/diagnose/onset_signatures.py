"""Sensor faults told by what happens at their onset, not by the level of the misfit.

Three signatures no heat flow can make, each local in time: a jump of a sensor whose node has heat
capacity (:func:`inertial_outputs` says which), a reading that freezes after a noisy stretch
(:func:`frozen_tail`), and an input sensor's jump the machine does not follow. They decide only
when the whole-record comparison with the physical effects claimed no fault. Method:
``docs/guide/methods.md``.
"""

from __future__ import annotations

import math

import numpy as np

from ..sensor_faults import SensorFault
from .sensor_faults import SensorHypothesis, output_columns, sensor_groups

#: Half-width of the window of the local step fit, s (about the fastest winding mode of the
#: thesis model, 6.5 min: long enough to tell a step from noise, short enough that the misfit is
#: a smooth curve in it).
JUMP_WINDOW_S = 300.0
#: A jump is claimed from this size in noise standard deviations (:math:`z`). The largest
#: :math:`z` on the iron of healthy and physical-effect records of the model's own and the rig
#: plant was 6.2 (a coolant flow loss on the rig plant); a 1-K bias at the thesis noise gives
#: about 18.
JUMP_MIN_SIGMA = 12.0
#: ... and from this many times the largest one-sample change of the model's prediction of the
#: sensor over the record (a node with inertia changes no faster than its model says, give or
#: take the misfit).
JUMP_MIN_RATE_FACTOR = 5.0
#: A sensor has thermal inertia when its output's response to a 1-K coolant-inlet step reaches
#: less than this share of its largest value after one sample.
INERTIA_FRACTION = 0.05
#: An input sensor's fault: the residual's jump :math:`\hat v` must be within this share of the
#: logged input's own jump :math:`v_u`.
INPUT_JUMP_AGREEMENT = 0.35
#: A reading is frozen when it changes by less than this share of its noise standard deviation
#: from one sample to the next ...
FROZEN_TOLERANCE = 0.01
#: ... to the end of the record, for at least this long, s (a working PT100 with 0.1-K noise
#: read to 0.01 K repeats a value two or three samples in a row) ...
FROZEN_MIN_S = 300.0
#: ... and this many samples.
FROZEN_MIN_SAMPLES = 10
#: Input jumps looked at: one-sample changes of the logged input of at least this size, K.
INPUT_JUMP_MIN_K = 0.5


def _window(dt_s: float) -> int:
    return max(5, int(round(JUMP_WINDOW_S / dt_s)))


def _nuisance(width: int, local_prediction: np.ndarray | None) -> np.ndarray:
    t = np.arange(-width, width) / width
    after = (t >= 0).astype(float)
    columns = [np.ones(2 * width), t, t * t, t * after]
    if local_prediction is not None:
        centred = local_prediction - local_prediction.mean()
        if np.ptp(centred) > 0:
            columns.append(centred)
    return np.column_stack(columns)


def _step_gain(segment: np.ndarray, nuisance: np.ndarray, shape: np.ndarray) -> tuple[float, float]:
    """Least-squares size of ``shape`` on ``segment`` over the ``nuisance`` terms, and the RSS it
    removes (K²)."""
    ok = np.isfinite(segment)
    if ok.sum() < nuisance.shape[1] + 3:
        return 0.0, 0.0
    base, *_ = np.linalg.lstsq(nuisance[ok], segment[ok], rcond=None)
    rss0 = float(np.sum((segment[ok] - nuisance[ok] @ base) ** 2))
    design = np.column_stack([nuisance, shape])[ok]
    full, *_ = np.linalg.lstsq(design, segment[ok], rcond=None)
    rss1 = float(np.sum((segment[ok] - design @ full) ** 2))
    return float(full[-1]), max(rss0 - rss1, 0.0)


def local_jump(residual, predicted, dt_s: float, noise: float) -> tuple[float, int, float]:
    """Best step of ``residual`` in a window around each sample (module docstring).

    Parameters
    ----------
    residual : array_like
        Measured minus model output, K (N,).
    predicted : array_like
        The model output, °C (N,): a nuisance term of each window.
    dt_s : float
        Sample period, s.
    noise : float
        Sensor noise standard deviation, K.

    Returns
    -------
    (value_K, onset_index, z)
        The step's size, the first sample after it, and its size in noise units (0 when the
        record is shorter than two windows).
    """
    residual, predicted = np.asarray(residual, float), np.asarray(predicted, float)
    width, best = _window(dt_s), (0.0, 0, 0.0)
    if residual.size < 2 * width + 1 or not (noise > 0):
        return best
    step = np.r_[np.zeros(width), np.ones(width)]
    for onset in range(width, residual.size - width):
        window = slice(onset - width, onset + width)
        value, removed = _step_gain(residual[window], _nuisance(width, predicted[window]), step)
        z = math.sqrt(removed) / noise
        if z > best[2]:
            best = (value, onset, z)
    return best


def inertial_outputs(step_response: np.ndarray, output_names) -> set:
    """Outputs whose response to a 1-K coolant-inlet step (``step_response``, (n_outputs, N),
    :func:`~genthermal.diagnose.input_sensors.input_step_response`) reaches less than
    :data:`INERTIA_FRACTION` of its largest value after one sample."""
    peak = np.max(np.abs(step_response), axis=1)
    first = np.abs(step_response[:, 1]) if step_response.shape[1] > 1 else peak
    return {name for name, p, f in zip(output_names, peak, first) if p > 0 and f < INERTIA_FRACTION * p}


def screen_jumps(measured: np.ndarray, predicted: np.ndarray, readings: dict, dt_s: float, elapsed_s: np.ndarray,
                 output_names, columns, inertial: set, noise: float, exclude=()) -> SensorHypothesis | None:
    """The largest jump of a single sensor with thermal inertia, if it is a sensor's (module
    docstring).

    Parameters
    ----------
    measured, predicted : numpy.ndarray
        (n_outputs, N) measured and model outputs, °C.
    readings : dict
        Sensor column → reading (which outputs have a single sensor).
    dt_s : float
    elapsed_s : numpy.ndarray
    output_names : sequence of str
    columns : mapping
        :func:`~genthermal.diagnose.sensor_faults.sensor_columns`.
    inertial : set of str
        :func:`inertial_outputs`.
    noise : float
        Sensor noise, K.
    exclude : collection of str
        Sensors already explained.

    Returns
    -------
    SensorHypothesis or None
        A bias from the jump's sample, ``evidence`` ``"jump"``.
    """
    groups, best = sensor_groups(readings, columns), None
    for i, output in enumerate(output_names):
        sensors = groups.get(output, [])
        if output not in inertial or len(sensors) != 1 or sensors[0] in exclude:
            continue
        value, onset, z = local_jump(measured[i] - predicted[i], predicted[i], dt_s, noise)
        fastest = float(np.nanmax(np.abs(np.diff(predicted[i])))) if predicted.shape[1] > 1 else 0.0
        if z < JUMP_MIN_SIGMA or abs(value) < JUMP_MIN_RATE_FACTOR * fastest:
            continue
        if best is None or z > best[0]:
            present = output_columns(readings, output, columns)
            best = (z, value, onset, output, present)
    if best is None:
        return None
    z, value, onset, output, present = best
    signal = value * (np.arange(elapsed_s.size) >= onset)
    sensor = present[0] if len(present) == 1 else output
    return SensorHypothesis(SensorFault(sensor, "bias", float(value), float(elapsed_s[onset])), int(onset),
                            float("nan"), float("nan"), -z * z, "jump", signal,
                            f"a jump of {z:.0f} σ in one sample: no heat flow moves a node with inertia so fast",
                            columns=tuple(present), output=output)


def frozen_tail(reading) -> tuple[int, float, float]:
    """The stretch at the end of a reading over which it does not change, after a stretch where
    it is noisy.

    Returns
    -------
    (onset_index, held_C, noise_before_K)
        The first sample of the frozen stretch (the record's length when the last two samples
        differ), the value held, °C, and the noise standard deviation before it, K (from the
        second differences, :func:`~genthermal.diagnose.search.noise_std`).
    """
    from .search import noise_std

    reading = np.asarray(reading, float)
    finite = np.flatnonzero(np.isfinite(reading))
    if finite.size < 3:
        return reading.size, float("nan"), float("nan")
    values = reading[finite]
    noise = noise_std(values[None, :])
    tolerance = FROZEN_TOLERANCE * noise if np.isfinite(noise) else 0.0
    moved = np.flatnonzero(np.abs(np.diff(values)) > tolerance)
    if moved.size == 0:
        return 0, float(values[0]), float("nan")
    start = int(moved[-1]) + 1  # first finite sample of the frozen stretch
    if start >= values.size - 1:
        return reading.size, float("nan"), noise
    return int(finite[start]), float(values[start]), noise_std(values[None, :start + 1])


def screen_frozen(readings: dict, elapsed_s: np.ndarray, columns, exclude=()) -> list:
    """Sensors whose reading froze (module docstring): a stuck fault each, held at the mean of
    the reading from the onset, ``evidence`` ``"frozen"``."""
    found = []
    groups = sensor_groups(readings, columns)
    for output in columns:
        for name in groups[output]:
            if name in exclude:
                continue
            onset, held, noise = frozen_tail(readings[name])
            samples = int(np.isfinite(readings[name][onset:]).sum())
            long_enough = onset > 0 and samples * (elapsed_s[1] - elapsed_s[0]) >= FROZEN_MIN_S
            if long_enough and samples >= FROZEN_MIN_SAMPLES and noise > 0:
                fault = SensorFault(name, "stuck", held, float(elapsed_s[onset]))
                found.append(SensorHypothesis(fault, onset, float("nan"), float("nan"), float("nan"), "frozen",
                                              np.zeros(elapsed_s.size),
                                              f"{samples} equal samples after a noise of {noise:.2f} K: no heat "
                                              "flow stills a sensor", output=output))
    return found


def screen_input_jumps(inputs, residual: np.ndarray, responses: dict, dt_s: float, elapsed_s: np.ndarray,
                       noise: float) -> SensorHypothesis | None:
    """The input sensor whose logged jump the measured outputs did not follow (module docstring).

    Parameters
    ----------
    inputs : pandas.DataFrame
        The record's inputs on the diagnosis grid.
    residual : numpy.ndarray
        (n_outputs, N) measured minus model outputs, K.
    responses : dict
        Input name → (n_outputs, N) response of the outputs to a 1-K step of it at the first
        sample (:func:`~genthermal.diagnose.input_sensors.input_step_response`).
    dt_s : float
    elapsed_s : numpy.ndarray
    noise : float
        Sensor noise, K.

    Returns
    -------
    SensorHypothesis or None
        A bias of the input from the jump, ``evidence`` ``"input"``, ``signal`` the input error.
    """
    width, best = _window(dt_s), None
    if residual.shape[1] < 2 * width + 1 or not (noise > 0):
        return None
    nuisance = _nuisance(width, None)
    for name, response in responses.items():
        logged = inputs[name].to_numpy(float)
        jumps = np.flatnonzero(np.abs(np.diff(logged)) >= INPUT_JUMP_MIN_K) + 1
        for onset in jumps[(jumps >= width) & (jumps < logged.size - width)]:
            input_jump = float(logged[onset] - logged[onset - 1])
            window = slice(onset - width, onset + width)
            stacked_segment, stacked_nuisance, stacked_shape = [], [], []
            for j in range(residual.shape[0]):
                shape = np.r_[np.zeros(width), -response[j, :width]]
                stacked_segment.append(residual[j, window])
                stacked_shape.append(shape)
                block = np.zeros((2 * width, nuisance.shape[1] * residual.shape[0]))
                block[:, j * nuisance.shape[1]:(j + 1) * nuisance.shape[1]] = nuisance
                stacked_nuisance.append(block)
            value, removed = _step_gain(np.concatenate(stacked_segment), np.vstack(stacked_nuisance),
                                        np.concatenate(stacked_shape))
            z = math.sqrt(removed) / noise
            agrees = abs(value - input_jump) <= INPUT_JUMP_AGREEMENT * abs(input_jump)
            if z >= JUMP_MIN_SIGMA and agrees and (best is None or z > best[0]):
                best = (z, name, value, int(onset))
    if best is None:
        return None
    z, name, value, onset = best
    error = value * (np.arange(elapsed_s.size) >= onset)
    return SensorHypothesis(SensorFault(name, "bias", float(value), float(elapsed_s[onset])), onset,
                            float("nan"), float("nan"), -z * z, "input", error,
                            f"the logged {name} jumped by {value:+.2f} K and the machine did not follow ({z:.0f} σ)",
                            columns=(name,), output="")
