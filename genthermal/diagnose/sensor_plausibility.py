"""Is a fitted sensor fault a plausible claim? Physical bounds and the record's own redundancy.

:func:`refusal` returns why a :class:`SensorHypothesis` is no claim: larger than a sensor of its
kind can be wrong (:data:`genthermal.sensor_faults.SENSOR_FAULT_BOUNDS`), smaller than
:data:`MIN_SIZE_OVER_FLOOR` discrepancy floors, not shown by the record's redundant readings
(inlet and ambient, the three phases, outlet and energy balance, the other outputs), or a bias
of a lone sensor its reading does not show as a step (:func:`lone_bias_refusal`: then model
error and offset are not distinguishable). :func:`noise_refusal` asks a noise claim for the
reading's own roughness. The rules and their reasons: ``docs/guide/evidence.md``.
"""

from __future__ import annotations

import numpy as np

from ..sensor_faults import MIN_NOISE_FACTOR, fault_bound_reason

#: A fault's error over the record must be this many discrepancy floors of its sensor.
MIN_SIZE_OVER_FLOOR = 3.0
#: Window before and after an onset over which a bias is read from a redundant difference, s.
WINDOW_S = 900.0
#: A redundant reading must show the fault within this share of its size.
AGREEMENT = 0.5
#: Evidence kinds that are observed in the reading itself, not fitted against the model.
OBSERVED = ("redundancy", "frozen", "noise")
#: Evidence kinds fitted against the model's residual over the record (a local step, ``jump``,
#: is already read against the reading's own change).
FITTED_AGAINST_MODEL = ("model", "calibrated")
#: Outlet air cooler than the inlet air by more than this, K, breaks the energy balance.
ENERGY_BALANCE_TOLERANCE_K = 0.5
#: Half-width of the windows over which a lone sensor's step is read, s (as
#: :data:`~genthermal.diagnose.onset_signatures.JUMP_WINDOW_S`: about the fastest winding mode of
#: the thesis model, over which the heat of a load step bends a node's curve smoothly).
STEP_WINDOW_S = 300.0
#: Samples needed in each window (the median of fewer is no level).
STEP_MIN_SAMPLES = 3
#: What a noise growth of :data:`MIN_NOISE_FACTOR` on one of two equally noisy sensors does to the
#: roughness of their difference: :math:`\sqrt{(F^2 + 1)/2}` (the partner's noise unchanged).
PARTNER_NOISE_FACTOR = float(np.sqrt((MIN_NOISE_FACTOR ** 2 + 1.0) / 2.0))


def robust_scale(values) -> float:
    """Standard deviation of ``values`` from their median absolute deviation (× 1.4826: exact for
    Gaussian samples), in their unit; NaN when there are none."""
    values = np.asarray(values, float)
    if values.size == 0:
        return float("nan")
    return float(1.4826 * np.median(np.abs(values - np.median(values))))


def window_steps(signal: np.ndarray, elapsed_s: np.ndarray) -> np.ndarray:
    """At each sample, the step of ``signal`` there over a smooth local curve (K): least squares on
    the samples within :data:`STEP_WINDOW_S` before and after it of an offset, a slope, a change of
    slope at the sample (what heat switched on or off does to a node with inertia) and a step
    there; NaN where either side has fewer than :data:`STEP_MIN_SAMPLES` finite samples."""
    signal, elapsed_s = np.asarray(signal, float), np.asarray(elapsed_s, float)
    steps = np.full(signal.size, np.nan)
    starts = np.searchsorted(elapsed_s, elapsed_s - STEP_WINDOW_S, side="left")
    ends = np.searchsorted(elapsed_s, elapsed_s + STEP_WINDOW_S, side="left")
    for k in range(signal.size):
        window = slice(starts[k], ends[k])
        values, local = signal[window], (elapsed_s[window] - elapsed_s[k]) / STEP_WINDOW_S
        ok = np.isfinite(values)
        after = local >= 0
        if (ok & ~after).sum() < STEP_MIN_SAMPLES or (ok & after).sum() < STEP_MIN_SAMPLES:
            continue
        design = np.column_stack([np.ones(local.size), local, local * after, after.astype(float)])
        coefficients, *_ = np.linalg.lstsq(design[ok], values[ok], rcond=None)
        steps[k] = coefficients[-1]
    return steps


def lone_bias_refusal(fault, reading: np.ndarray, elapsed_s: np.ndarray, onset: int,
                      predicted: np.ndarray | None = None) -> str | None:
    """Why a bias of a sensor with no redundant reading is no finding, or None when its reading
    shows it as a step.

    Against the model alone, an offset of a lone sensor from ``onset`` and the model's own error
    on that node from then (a misfit that a load change starts) are the same residual. The reading
    tells them apart only by a step at the onset over its smooth local curve
    (:func:`window_steps`: heat switched on changes the slope of a node with thermal inertia, an
    offset its level at once) that agrees with the fitted value within :data:`AGREEMENT` and is
    larger than every such step elsewhere in the record (at least one window from the onset). With
    the model's prediction of the node, the steps are read on the reading minus it: a node with a
    fast mode (a winding sampled once a minute) steps at a load step too, and the model, which
    knows the load, steps with it; a misfit the load change starts grows with the node's inertia
    and is no step. A bias from the record's start has no window before it and is never shown.

    Parameters
    ----------
    fault : SensorFault
        The fitted bias (K).
    reading : numpy.ndarray
        The sensor's reading on the diagnosis grid, °C.
    elapsed_s : numpy.ndarray
        Time of each sample from the start, s.
    onset : int
        Sample of the onset.
    predicted : numpy.ndarray, optional
        The model's prediction of the sensor's node on the same grid, °C (None: the reading's own
        steps).
    """
    steps = window_steps(reading if predicted is None else reading - predicted, elapsed_s)
    step = steps[onset]
    away = np.abs(elapsed_s - elapsed_s[onset]) >= STEP_WINDOW_S
    elsewhere = float(np.nanmax(np.abs(steps[away]))) if np.isfinite(steps[away]).any() else 0.0
    if np.isfinite(step) and abs(step - fault.value) <= AGREEMENT * abs(fault.value) and abs(step) > elsewhere:
        return None
    what = "its reading" if predicted is None else "its reading minus the model"
    shown = (f"{what} steps by {step:+.2f} K there over its local curve, against up to {elsewhere:.2f} K "
             "elsewhere" if np.isfinite(step) else
             f"no {STEP_WINDOW_S / 60:.0f}-min window of its reading lies before the onset")
    return (f"model error or sensor offset: not distinguishable: {fault.describe()} is fitted against the "
            f"model on a sensor with no redundant reading, and {shown}")


def roughness_change(signal: np.ndarray, onset: int) -> float:
    """Robust scale of the second differences of ``signal`` after sample ``onset`` over the one
    before (:func:`robust_scale`); NaN when either side has
    fewer than 10 of them or no roughness before."""
    signal = np.asarray(signal, float)
    d2 = signal[2:] - 2 * signal[1:-1] + signal[:-2]
    before, after = d2[:max(onset - 1, 0)], d2[max(onset - 1, 0):]
    before, after = before[np.isfinite(before)], after[np.isfinite(after)]
    if before.size < 10 or after.size < 10:
        return float("nan")
    scale = robust_scale(before)
    return robust_scale(after) / scale if scale > 0 else float("nan")


def noise_refusal(hypothesis, readings: dict, groups: dict) -> str | None:
    """Why a noise increase of a sensor is no claim, or None: the reading must roughen where no
    shared temperature can make it.

    On a coarse grid a load change roughens the second differences of every reading near the heat
    (:func:`roughness_change`); a sensor's own noise is its own. So the reading must roughen
    :data:`MIN_NOISE_FACTOR` times more than the median of the record's other sensors, and, with
    partners (other distinct sensors of its output), its difference to their mean must roughen by
    :data:`PARTNER_NOISE_FACTOR`. A record with no other sensor cannot check it (None).

    Parameters
    ----------
    hypothesis : SensorHypothesis
        A ``noise`` fault.
    readings : dict
        Sensor column → reading on the diagnosis grid, °C.
    groups : dict
        Output → its distinct sensors
        (:func:`~genthermal.diagnose.sensor_faults.sensor_groups`).
    """
    fault, onset = hypothesis.fault, int(hypothesis.onset_index)
    group = next((names for names in groups.values() if fault.sensor in names), [fault.sensor])
    partners = [name for name in group if name != fault.sensor and name in readings]
    if partners:
        difference = readings[fault.sensor] - np.mean([readings[name] for name in partners], axis=0)
        shown = roughness_change(difference, onset)
        if not (np.isfinite(shown) and shown >= PARTNER_NOISE_FACTOR):
            return (f"{fault.describe()}: but its difference to {', '.join(partners)} on the same node roughens "
                    f"only {shown:.2f}× there (a noise growth of {MIN_NOISE_FACTOR:g}× would give "
                    f"{PARTNER_NOISE_FACTOR:.2f}×): the temperature both read changed faster, not the sensor")
    others = [name for names in groups.values() for name in names if name != fault.sensor and name in readings]
    changes = [roughness_change(readings[name], onset) for name in others]
    changes = [c for c in changes if np.isfinite(c)]
    if not changes:
        return None
    own, common = roughness_change(readings[fault.sensor], onset), float(np.median(changes))
    if np.isfinite(own) and own >= MIN_NOISE_FACTOR * max(common, 1.0):
        return None
    return (f"{fault.describe()}: but the record's other sensors roughen {common:.2f}× there too (median; "
            f"its own reading {own:.2f}×): the temperatures changed faster, not its noise")


def shown_change(signal: np.ndarray, elapsed_s: np.ndarray, kind: str, onset: int) -> float:
    """What ``signal`` shows of a fault of ``kind`` from sample ``onset``: a bias as the median over
    :data:`WINDOW_S` after the onset minus before (K), a drift as the change of the least-squares
    slope after the onset against before (K/h); NaN when either side has fewer than 3 samples."""
    signal, elapsed_s = np.asarray(signal, float), np.asarray(elapsed_s, float)
    ok = np.isfinite(signal)
    if kind == "bias":
        before = ok & (elapsed_s < elapsed_s[onset]) & (elapsed_s >= elapsed_s[onset] - WINDOW_S)
        after = ok & (elapsed_s >= elapsed_s[onset]) & (elapsed_s < elapsed_s[onset] + WINDOW_S)
        if before.sum() < 3 or after.sum() < 3:
            return float("nan")
        return float(np.median(signal[after]) - np.median(signal[before]))
    start = max(0, onset - max(onset // 2, 10))
    before = ok & (np.arange(signal.size) >= start) & (np.arange(signal.size) < onset)
    after = ok & (np.arange(signal.size) >= onset)
    if before.sum() < 3 or after.sum() < 3:
        return float("nan")
    slopes = [np.polyfit(elapsed_s[part] / 3600.0, signal[part], 1)[0] for part in (before, after)]
    return float(slopes[1] - slopes[0])


def _shows(signal, elapsed_s, kind, onset, value) -> bool:
    shown = shown_change(signal, elapsed_s, kind, onset)
    return bool(np.isfinite(shown) and abs(shown - value) <= AGREEMENT * abs(value))


def refusal(hypothesis, readings: dict, elapsed_s: np.ndarray, floors: dict, pooled_floor: float | None,
            coolant: str | None = None, ambient: str | None = None, outlet: str | None = "T_outlet",
            phase_columns: tuple = (), residuals: dict | None = None, same_air: bool = True,
            predicted: dict | None = None) -> str | None:
    """Why ``hypothesis`` (a SensorHypothesis) is no claim (module docstring), or None.

    Parameters
    ----------
    hypothesis : SensorHypothesis
    readings : dict
        Column name → reading on the diagnosis grid, °C: the sensors and the logged inputs.
    elapsed_s : numpy.ndarray
        Time of each sample from the start, s.
    floors : dict
        Output name → discrepancy floor of its sensor, K (empty without an error model).
    pooled_floor : float or None
        The floor over every sensor, K (for the input sensors, which are no output).
    coolant, ambient, outlet : str or None
        Columns of the coolant inlet, ambient and outlet air readings.
    phase_columns : tuple of str
        The phase winding sensor columns (``T_winding_u/v/w``).
    residuals : dict, optional
        Output name → measured minus model (K) before the fault: a fault of one output's sensor
        must not come with the same change in the other outputs' residuals.
    same_air : bool
        The coolant inlet and the ambient read the same air (the machine's ``coolant_medium`` is
        ``"room_air"``): each is the other's redundant reading. Otherwise (a water circuit) each
        is a lone reading, and a bias fitted through the model (``"input"`` evidence too) needs
        its reading's own step (:func:`lone_bias_refusal`).
    predicted : dict, optional
        Output name → the model's prediction of it on the grid, °C, against which a lone sensor's
        step is read (:func:`lone_bias_refusal`).
    """
    fault = hypothesis.fault
    reason = fault_bound_reason(fault)
    if reason:
        return reason
    if hypothesis.evidence in OBSERVED or fault.kind in ("stuck", "noise"):
        return None
    onset = int(hypothesis.onset_index)
    floor = floors.get(hypothesis.output) if hypothesis.output else None
    floor = pooled_floor if floor is None else floor
    if floor is not None and fault.kind in ("bias", "drift"):
        size = abs(fault.value) * (1.0 if fault.kind == "bias" else (elapsed_s[-1] - elapsed_s[onset]) / 3600.0)
        if size < MIN_SIZE_OVER_FLOOR * floor:
            return (f"{fault.describe()}: its error ({size:.2f} K over the record) is below "
                    f"{MIN_SIZE_OVER_FLOOR:g}× the discrepancy floor of the sensor ({floor:.3f} K)")
    if fault.kind not in ("bias", "drift"):
        return None
    sensor = fault.sensor
    paired_input = same_air and sensor in (coolant, ambient)
    lone = not paired_input and not ({sensor, *hypothesis.columns} & set(phase_columns))
    through_model = hypothesis.evidence in FITTED_AGAINST_MODEL or \
        (hypothesis.evidence == "input" and sensor in (coolant, ambient))
    if fault.kind == "bias" and through_model and lone:
        present = [c for c in hypothesis.columns if c in readings]
        reading = np.mean([readings[c] for c in present], axis=0) if present else np.full(elapsed_s.size, np.nan)
        curve = (predicted or {}).get(hypothesis.output) if present else None
        reason = lone_bias_refusal(fault, reading, elapsed_s, onset, curve)
        if reason:
            return reason
    if paired_input and coolant in readings and ambient in readings:
        other = ambient if sensor == coolant else coolant
        difference = readings[sensor] - readings[other]
        if not _shows(difference, elapsed_s, fault.kind, onset, fault.value):
            shown = shown_change(difference, elapsed_s, fault.kind, onset)
            return (f"{fault.describe()}: but the {sensor} and {other} readings of the same air move apart by "
                    f"only {shown:+.2f} {fault.unit} there")
        if sensor == coolant and outlet in readings:
            rise = readings[outlet] - readings[coolant]
            followed = shown_change(rise, elapsed_s, fault.kind, onset)
            if np.isfinite(followed) and abs(followed) < AGREEMENT * abs(fault.value):
                return (f"{fault.describe()}: the outlet air follows the inlet reading (outlet minus inlet "
                        "unchanged): warmer intake air, not the inlet sensor")
    if sensor in phase_columns:
        others = [c for c in phase_columns if c != sensor and c in readings]
        if others and sensor in readings:
            difference = readings[sensor] - np.mean([readings[c] for c in others], axis=0)
            if not _shows(difference, elapsed_s, fault.kind, onset, fault.value):
                return (f"{fault.describe()}: but it does not move against the other phase sensors "
                        f"({', '.join(others)})")
    if len([c for c in hypothesis.columns if c in phase_columns]) > 1:
        return (f"{fault.describe()}: one fault on the phase sensors {', '.join(hypothesis.columns)} alike "
                "would be several sensors failing the same way")
    if hypothesis.output and residuals and hypothesis.output in residuals and sensor not in phase_columns:
        on_the_phases = hypothesis.output in phase_columns or bool(set(hypothesis.columns) & set(phase_columns))
        for name, residual in residuals.items():
            if name == hypothesis.output or (on_the_phases and name in phase_columns):
                continue  # the same quantity: the phase sensors of the winding the fault is on
            moved = shown_change(residual, elapsed_s, fault.kind, onset)
            if np.isfinite(moved) and abs(moved) >= AGREEMENT * abs(fault.value) and moved * fault.value > 0:
                return (f"{fault.describe()}: but {name} leaves the model by {moved:+.2f} {fault.unit} at the same "
                        "time: the machine changed, not one sensor")
    if sensor == outlet and coolant in readings and outlet in readings:
        corrected = readings[outlet] - hypothesis.signal
        if np.nanmin(corrected - readings[coolant]) < -ENERGY_BALANCE_TOLERANCE_K:
            return (f"{fault.describe()}: corrected, the outlet air would be cooler than the inlet air, which "
                    "the energy balance forbids")
    return None
