"""Units of a record checked, not assumed: time in s, currents in A, temperatures in °C.

:func:`checked_units` refuses, naming the column and the likely unit, a time column in ms or min,
currents in kA and temperatures in kelvin; :func:`stated_units` reads ``--unit COLUMN=UNIT``, which
converts a column or takes it as it is. The rules: ``docs/guide/safety.md``.
"""

from __future__ import annotations

import contextlib
import contextvars
from typing import Iterator, Mapping

import numpy as np
import pandas as pd

from .errors import InputError
from .machines.interface import InputKind, MachineInterface

#: Units a column may be stated in, by kind: name -> (factor, offset) to s, A or °C.
UNITS = {"time": {"s": (1.0, 0.0), "ms": (1e-3, 0.0), "min": (60.0, 0.0), "h": (3600.0, 0.0)},
         "current": {"A": (1.0, 0.0), "mA": (1e-3, 0.0), "kA": (1e3, 0.0)},
         "temperature": {"degC": (1.0, 0.0), "C": (1.0, 0.0), "K": (1.0, -273.15)}}
#: Names that state the unit of every column of a kind at once.
GROUPS = {"time": "time", "currents": "current", "temperatures": "temperature"}
#: Longest record accepted without a stated unit, s: longer is milliseconds read as seconds.
MAX_SPAN_S = 366 * 86400.0
#: Shortest median step accepted without a stated unit, s (shorter: hours or minutes read as seconds).
MIN_STEP_S = 0.05
#: Fastest sustained change of a measured temperature accepted, K/s: a winding at three times its
#: rated current heats by well under 1 K/s, and a PT100 in its slot responds slower still.
MAX_HEATING_RATE_K_PER_S = 1.0
#: Window over which that rate must be sustained, s (a median of 5 samples removes single spikes).
RATE_WINDOW_S = 10.0
#: A load current whose largest value is below this share of the rating is in kA, not A.
MIN_PEAK_CURRENT_SHARE = 0.005
#: Median temperatures above these (°C) are kelvin: inputs are air, sensors a machine whose
#: insulation fails near 200 °C.
KELVIN_MEDIAN_C = {"input": 150.0, "sensor": 200.0}
#: Sensor readings outside this range (°C, the rig's PT100 range) are missing, not a rate.
SENSOR_RANGE_C = (-50.0, 300.0)
_STATED: contextvars.ContextVar[dict] = contextvars.ContextVar("stated_units", default={})


@contextlib.contextmanager
def stated_units(units: Mapping[str, str]) -> Iterator[dict]:
    """Within the block, records are read with these units (column or group name -> unit).

    Raises
    ------
    InputError
        An unknown unit (the known ones are listed).
    """
    known = sorted({unit for table in UNITS.values() for unit in table})
    for column, unit in units.items():
        if unit not in known:
            raise InputError(f"--unit {column}", unit, f"unknown unit; known: {', '.join(known)}")
    token = _STATED.set({**_STATED.get(), **units})
    try:
        yield _STATED.get()
    finally:
        _STATED.reset(token)


def parse_unit_options(items: list[str]) -> dict[str, str]:
    """``["time_s=min", "currents=kA"]`` as a dict; InputError naming a malformed item."""
    units = {}
    for item in items:
        column, sep, unit = item.partition("=")
        if not sep or not column.strip() or not unit.strip():
            raise InputError("--unit", item, "expected COLUMN=UNIT, e.g. time_s=min, currents=kA, temperatures=K")
        units[column.strip()] = unit.strip()
    return units


def column_kinds(interface: MachineInterface, columns) -> dict[str, str]:
    """Kind (``time``, ``current``, ``temperature``) of every column of the record that has one."""
    kinds = {"time_s": "time"}
    kinds.update({name: "current" for name in interface.inputs_of_kind(InputKind.CURRENT)})
    kinds.update({name: "temperature" for name in interface.inputs_of_kind(InputKind.TEMPERATURE)})
    kinds.update({name: "temperature" for name in columns if name in interface.sensor_columns
                  or (interface.outlet_sensor is not None and name in interface.outlet_sensor.columns)})
    return {name: kind for name, kind in kinds.items() if name in columns}


def checked_units(frame: pd.DataFrame, interface: MachineInterface, rated_current_A: float | None = None,
                  units: Mapping[str, str] | None = None) -> pd.DataFrame:
    """``frame`` with stated units converted; refuse a column whose values contradict its unit.

    Parameters
    ----------
    frame : pandas.DataFrame
        Numeric record columns (``time_s``, inputs, sensors; NaN for a missing sample).
    interface : MachineInterface
        The schema: which columns are times, currents and temperatures.
    rated_current_A : float, optional
        Rated RMS load current, A; default the interface's.
    units : mapping, optional
        Column or group name -> unit; default the ones stated for the run (:func:`stated_units`).

    Returns
    -------
    pandas.DataFrame
        In s, A and °C.

    Raises
    ------
    InputError
        A unit given for a column of another kind, or a column that looks like another unit
        (the column and the likely unit are named).
    """
    units = dict(_STATED.get() if units is None else units)
    kinds = column_kinds(interface, frame.columns)
    stated = _stated_per_column(units, kinds)
    frame = frame.copy()
    for name, unit in stated.items():
        factor, offset = UNITS[kinds[name]][unit]
        frame[name] = frame[name].to_numpy(dtype=float) * factor + offset
    rated = float(rated_current_A) if rated_current_A is not None else interface.rated_current_A
    sensors = [name for name, kind in kinds.items() if kind == "temperature"
               and name not in interface.inputs_of_kind(InputKind.TEMPERATURE)]
    if "time_s" not in stated:
        _check_time(frame, sensors)
    _check_currents(frame, rated, [n for n in kinds if kinds[n] == "current" and n not in stated])
    for name in (n for n in kinds if kinds[n] == "temperature" and n not in stated):
        _check_kelvin(frame, name, "sensor" if name in sensors else "input")
    return frame


def _stated_per_column(units: Mapping[str, str], kinds: dict[str, str]) -> dict[str, str]:
    """Column -> stated unit; a column's own entry wins over its group's."""
    per_column = {}
    for given, unit in sorted(units.items(), key=lambda item: item[0] not in GROUPS):
        if given in GROUPS:
            columns = [name for name, kind in kinds.items() if kind == GROUPS[given]]
        elif given in kinds:
            columns = [given]
        else:
            continue  # a column of another machine's schema: not in this record
        for name in columns:
            if unit not in UNITS[kinds[name]]:
                raise InputError(f"--unit {given}", unit, f"{name} is a {kinds[name]}: give one of "
                                 f"{', '.join(UNITS[kinds[name]])}")
            per_column[name] = unit
    return per_column


def _refuse(column: str, shown, likely: str, fix: str, kind: str) -> InputError:
    return InputError(f"column {column}", shown, f"looks like {likely}, not {_SI[kind]}: {fix}; or state the "
                      f"unit with --unit {column}=UNIT ({', '.join(UNITS[kind])})")


_SI = {"time": "seconds", "current": "amperes", "temperature": "°C"}


def _check_time(frame: pd.DataFrame, sensors: list[str]) -> None:
    time_s = frame["time_s"].to_numpy(dtype=float)
    finite = time_s[np.isfinite(time_s)]
    if finite.size < 2:
        return
    span = float(finite.max() - finite.min())
    if span > MAX_SPAN_S * 1000.0:
        raise InputError("column time_s", f"span {span:.4g}", f"more than {MAX_SPAN_S * 1000 / 86400 / 365.25:.0f} "
                         "years even if in milliseconds: time_s must be in seconds")
    if span > MAX_SPAN_S:
        raise _refuse("time_s", f"span {span:.4g}", f"milliseconds ({span / 86400:.3g} days read as seconds)",
                      "divide it by 1000", "time")
    step = float(np.median(np.diff(finite)))
    if step <= 0:
        return  # not increasing: measurements names the row
    if step >= 100.0 and _whole(step / 50.0) and not _whole(step / 60.0):
        raise _refuse("time_s", f"median step {step:g}", f"milliseconds (logging every {step / 1000:g} s)",
                      "divide it by 1000", "time")
    if step < MIN_STEP_S:
        likely = "hours" if _whole(step * 3600.0) or step * 60.0 < MIN_STEP_S else "minutes or hours"
        raise _refuse("time_s", f"median step {step:.6g}", f"{likely} (no logger of a machine's temperatures "
                      f"samples every {step:.3g} s)", "multiply it by 3600 (hours) or 60 (minutes)", "time")
    if step < 1.0 and _whole(step * 60.0, 1e-3) and not _whole(step * 100.0, 1e-3):  # stamps rounded to 4 digits
        raise _refuse("time_s", f"median step {step:.6g}", f"minutes (logging every {step * 60:.3g} s)",
                      "multiply it by 60", "time")
    rate, column = _fastest_change(frame, sensors, time_s, step)
    if rate > MAX_HEATING_RATE_K_PER_S:
        raise _refuse("time_s", f"median step {step:.6g}", f"minutes or hours ({column} would change by "
                      f"{rate:.3g} K/s over {RATE_WINDOW_S:g} s; no machine heats that fast)",
                      "multiply it by 60 (minutes) or 3600 (hours)", "time")


def _whole(value, tolerance: float = 1e-6):
    return np.abs(np.asarray(value) - np.round(value)) <= tolerance * np.maximum(1.0, np.abs(value))


def _fastest_change(frame: pd.DataFrame, sensors: list[str], time_s: np.ndarray, step: float) -> tuple[float, str]:
    """The rate, K/s, that at least two sensors reach (the one sensor of a record with one), and
    which: the largest |change| / time over :data:`RATE_WINDOW_S` of each sensor's 5-sample running
    median. A time column in minutes or hours speeds every sensor up; an air sensor alone can jump
    when the flow changes (a blockage's outlet), so one fast sensor is not evidence of a unit."""
    lag = max(int(round(RATE_WINDOW_S / step)), 1)
    if time_s.size <= lag + 5:
        return 0.0, ""
    low, high = SENSOR_RANGE_C
    rates_per_sensor = []
    for name in sensors:
        values = frame[name].to_numpy(dtype=float)
        values = np.where((values >= low) & (values <= high), values, np.nan)  # what is dropped as missing
        smooth = pd.Series(values).rolling(5, center=True, min_periods=3).median()
        values = smooth.to_numpy()
        change = np.abs(values[lag:] - values[:-lag])
        elapsed = time_s[lag:] - time_s[:-lag]
        with np.errstate(invalid="ignore", divide="ignore"):
            rates = np.where(np.isfinite(change) & (elapsed > 0), change / elapsed, 0.0)
        rates_per_sensor.append((float(np.max(rates)) if rates.size else 0.0, name))
    if not rates_per_sensor:
        return 0.0, ""
    rates_per_sensor.sort(reverse=True)
    return rates_per_sensor[min(1, len(rates_per_sensor) - 1)]


def _check_currents(frame: pd.DataFrame, rated_A: float, unchecked: list[str]) -> None:
    """kA: every current of the record (load and excitation together: a generator at no load still
    carries its field current) below :data:`MIN_PEAK_CURRENT_SHARE` of the rating, and not all zero."""
    if not unchecked:
        return
    values = np.abs(frame[unchecked].to_numpy(dtype=float))
    peak = float(np.nanmax(values)) if np.isfinite(values).any() else 0.0
    if 0.0 < peak < MIN_PEAK_CURRENT_SHARE * rated_A:
        raise _refuse(unchecked[0], f"largest {peak:.4g}", f"kA (the largest current of the record is "
                      f"{peak:.3g} A, {peak / rated_A:.2%} of the rated {rated_A:g} A)",
                      "multiply the currents by 1000", "current")


def _check_kelvin(frame: pd.DataFrame, name: str, kind: str) -> None:
    values = frame[name].to_numpy(dtype=float)
    if np.isfinite(values).any() and np.nanmedian(values) > KELVIN_MEDIAN_C[kind]:
        raise _refuse(name, f"median {np.nanmedian(values):g}", "kelvin", "subtract 273.15", "temperature")
