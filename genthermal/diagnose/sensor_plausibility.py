"""Is a fitted sensor fault a plausible claim? Physical bounds and the record's own redundancy.

:func:`refusal` returns why a :class:`SensorHypothesis` is no claim: larger than a sensor of its
kind can be wrong (:data:`genthermal.sensor_faults.SENSOR_FAULT_BOUNDS`), smaller than
:data:`MIN_SIZE_OVER_FLOOR` discrepancy floors, or not shown by the record's redundant readings
(inlet and ambient, the three phases, outlet and energy balance, the other outputs). The rules
and their reasons: ``docs/guide/evidence.md``.
"""

from __future__ import annotations

import numpy as np

from ..sensor_faults import fault_bound_reason

#: A fault's error over the record must be this many discrepancy floors of its sensor.
MIN_SIZE_OVER_FLOOR = 3.0
#: Window before and after an onset over which a bias is read from a redundant difference, s.
WINDOW_S = 900.0
#: A redundant reading must show the fault within this share of its size.
AGREEMENT = 0.5
#: Evidence kinds that are observed in the reading itself, not fitted against the model.
OBSERVED = ("redundancy", "frozen", "noise")
#: Outlet air cooler than the inlet air by more than this, K, breaks the energy balance.
ENERGY_BALANCE_TOLERANCE_K = 0.5


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
            phase_columns: tuple = (), residuals: dict | None = None) -> str | None:
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
    if sensor in (coolant, ambient) and coolant in readings and ambient in readings:
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
