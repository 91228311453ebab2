"""Measured (or synthetic) rig data: one CSV schema, validated once, resampled onto a uniform grid.

Schema (thesis 3.3: the Genco RF201A rig logged by LabVIEW to CSV with a time stamp per sample)

================  =====  ==========================================================
column            unit   meaning
================  =====  ==========================================================
``time_s``        s      time stamp, strictly increasing
``I_u, I_v, I_w``  A     stator phase currents, RMS
``I_exc``         A      exciter winding current
``T_inlet``       °C     cooling-air inlet temperature
``T_ambient``     °C     ambient temperature
``T_winding_u``   °C     stator winding PT100, phase U (likewise ``_v``, ``_w``)
``T_iron``        °C     stator iron PT100
``T_outlet``      °C     optional: cooling-air outlet PT100
================  =====  ==========================================================

Any other column is ignored and reported in :attr:`MeasurementData.ignored_columns`.

*Inputs* (time, currents, inlet and ambient temperature) drive a model, so they must be known: an
empty cell, a negative current or a temperature outside the PT100 range is an
:class:`~genthermal.errors.InputError`. *Sensor* columns are what a model is compared with: an empty
cell means "no measurement at this sample", and a value outside the PT100 range of the rig
(−50…300 °C, thesis Table 3.4) is flagged and treated as no measurement (set to NaN).

Row numbers in messages count data rows from 1, the header excluded; for files the line of the file
(header = line 1) is given too, which is the row a spreadsheet shows.
"""

from __future__ import annotations

import difflib
import os
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .errors import InputError
from .losses import INPUT_NAMES, PHASE_CURRENTS

WINDING_SENSORS = ("T_winding_u", "T_winding_v", "T_winding_w")
SENSOR_COLUMNS = (*WINDING_SENSORS, "T_iron")
OPTIONAL_SENSOR_COLUMNS = ("T_outlet",)
REQUIRED_COLUMNS = ("time_s", *INPUT_NAMES, *SENSOR_COLUMNS)
INPUT_TEMPERATURES = ("T_inlet", "T_ambient")
#: Measuring range of the rig's PT100 channels, °C (thesis Table 3.4).
PT100_RANGE_C = (-50.0, 300.0)


@dataclass
class MeasurementData:
    """Validated rig data.

    Attributes
    ----------
    frame : pandas.DataFrame
        The schema columns (required, then ``T_outlet`` if present) as floats, index ``0..n-1``.
        Sensor columns may hold NaN (no measurement); input columns never do.
    source : str
        Where the data came from (file name, or a description for in-memory frames).
    missing_counts : dict[str, int]
        Per sensor column, the number of samples without a measurement (empty cells plus values
        discarded as out of range).
    flags : list[str]
        Human-readable warnings about the data (out-of-range sensor values, empty sensors).
    ignored_columns : list[str]
        Columns of the source that are not part of the schema.
    """

    frame: pd.DataFrame
    source: str
    missing_counts: dict[str, int] = field(default_factory=dict)
    flags: list[str] = field(default_factory=list)
    ignored_columns: list[str] = field(default_factory=list)

    @property
    def time_s(self) -> np.ndarray:
        """Sample times, s."""
        return self.frame["time_s"].to_numpy(dtype=float)

    @property
    def inputs(self) -> pd.DataFrame:
        """The model inputs ``I_u, I_v, I_w, I_exc`` (A) and ``T_inlet, T_ambient`` (°C)."""
        return self.frame[list(INPUT_NAMES)].copy()

    @property
    def winding(self) -> np.ndarray:
        """Stator winding temperature, °C: mean of the phase sensors that measured at each sample
        (NaN only where all three are missing)."""
        return self.frame[list(WINDING_SENSORS)].mean(axis=1, skipna=True).to_numpy(dtype=float)

    @property
    def iron(self) -> np.ndarray:
        """Stator iron temperature, °C (NaN where not measured)."""
        return self.frame["T_iron"].to_numpy(dtype=float)

    @property
    def sensors(self) -> pd.DataFrame:
        """The model outputs as measured: ``T_winding`` and ``T_iron``, °C."""
        return pd.DataFrame({"T_winding": self.winding, "T_iron": self.iron})

    def to_csv(self, path) -> None:
        """Write the schema columns to ``path`` (empty cells for missing sensor samples)."""
        self.frame.to_csv(path, index=False)


def load_measurements(path_or_buffer) -> MeasurementData:
    """Read and validate a rig CSV file (schema in the module docstring).

    Parameters
    ----------
    path_or_buffer : str, os.PathLike or file-like
        The CSV file, header on the first line.

    Returns
    -------
    MeasurementData

    Raises
    ------
    InputError
        Empty file, missing column, non-numeric value, unknown input, negative current, input
        temperature outside the PT100 range, or time not strictly increasing.
    """
    if isinstance(path_or_buffer, (str, os.PathLike)):
        source = str(path_or_buffer)
    else:
        source = str(getattr(path_or_buffer, "name", "<buffer>"))
    try:
        raw = pd.read_csv(path_or_buffer, dtype=str, skipinitialspace=True)
    except pd.errors.EmptyDataError:
        raise InputError("file", source, "the file is empty: expected a header line and data rows") from None
    return _validate(raw, source, from_file=True)


def dataframe_to_measurements(frame: pd.DataFrame, source: str = "<DataFrame>") -> MeasurementData:
    """Validate an in-memory frame exactly as :func:`load_measurements` validates a file."""
    return _validate(frame, source, from_file=False)


def _validate(raw: pd.DataFrame, source: str, from_file: bool) -> MeasurementData:
    raw = raw.reset_index(drop=True)
    raw.columns = [str(name).strip() for name in raw.columns]
    _require_columns(raw.columns, source)
    if len(raw) == 0:
        raise InputError("file" if from_file else "frame", source, "no data rows below the header")
    present_sensors = [*SENSOR_COLUMNS, *(c for c in OPTIONAL_SENSOR_COLUMNS if c in raw.columns)]
    columns = ["time_s", *INPUT_NAMES, *present_sensors]
    frame = pd.DataFrame({name: _numeric_column(raw[name], name, from_file) for name in columns})
    for name in ("time_s", *INPUT_NAMES):
        _check_input_column(frame[name].to_numpy(), name, from_file)
    _check_time_increasing(frame["time_s"].to_numpy(), from_file)
    flags = []
    for name in present_sensors:
        flags.extend(_discard_out_of_range(frame, name, from_file))
    missing_counts = {name: int(frame[name].isna().sum()) for name in present_sensors}
    flags.extend(f"{name}: no valid sample at all" for name, n in missing_counts.items() if n == len(frame))
    ignored = [name for name in raw.columns if name not in columns]
    return MeasurementData(frame, source, missing_counts, flags, ignored)


def _row_label(index: int, from_file: bool) -> str:
    """Name data row ``index`` (0-based) for messages: 1-based, plus the file line for files."""
    return f"data row {index + 1} (line {index + 2} of the file)" if from_file else f"data row {index + 1}"


def _require_columns(columns, source: str) -> None:
    present = list(columns)
    for name in REQUIRED_COLUMNS:
        if name in present:
            continue
        reason = f"required column missing in {source}"
        close = difflib.get_close_matches(name, [c for c in present if c not in REQUIRED_COLUMNS], n=1)
        if close:
            reason += f"; did you mean {close[0]!r}?"
        else:
            reason += f"; the header must contain {', '.join(REQUIRED_COLUMNS)}"
        raise InputError("column", name, reason)


def _numeric_column(raw: pd.Series, name: str, from_file: bool) -> np.ndarray:
    """Convert one column to floats (empty cells → NaN); raise InputError at the first bad cell."""
    if pd.api.types.is_numeric_dtype(raw) and not pd.api.types.is_bool_dtype(raw):
        values = raw.to_numpy(dtype=float, na_value=np.nan)
        given = ~np.isnan(values)
    else:
        text = raw.astype("string").str.strip().replace("", pd.NA)
        values = pd.to_numeric(text, errors="coerce").to_numpy(dtype=float, na_value=np.nan)
        given = text.notna().to_numpy()
    bad = np.flatnonzero(given & ~np.isfinite(values))
    if bad.size:
        row = int(bad[0])
        raise InputError(f"column {name}, {_row_label(row, from_file)}", raw.iloc[row],
                         "not a finite number")
    return values


def _check_input_column(values: np.ndarray, name: str, from_file: bool) -> None:
    """Inputs must be known and physical: no empty cell, no negative current, PT100 range."""
    empty = np.flatnonzero(np.isnan(values))
    if empty.size:
        raise InputError(f"column {name}, {_row_label(int(empty[0]), from_file)}", "",
                         "empty cell in an input column; only sensor columns may have missing samples")
    if name in PHASE_CURRENTS or name == "I_exc":
        bad, reason = np.flatnonzero(values < 0.0), "a current (A RMS) cannot be negative"
    elif name in INPUT_TEMPERATURES:
        low, high = PT100_RANGE_C
        bad = np.flatnonzero((values < low) | (values > high))
        reason = f"outside the PT100 range {low:g} to {high:g} °C of the rig; an input must be valid"
    else:
        return
    if bad.size:
        row = int(bad[0])
        raise InputError(f"column {name}, {_row_label(row, from_file)}", float(values[row]), reason)


def _check_time_increasing(time_s: np.ndarray, from_file: bool) -> None:
    bad = np.flatnonzero(np.diff(time_s) <= 0.0)
    if bad.size:
        row = int(bad[0]) + 1
        raise InputError(f"column time_s, {_row_label(row, from_file)}", float(time_s[row]),
                         f"time must be strictly increasing, but the previous row has {time_s[row - 1]:g} s "
                         f"and this row {time_s[row]:g} s")


def _discard_out_of_range(frame: pd.DataFrame, name: str, from_file: bool) -> list[str]:
    """Set sensor samples outside the PT100 range to NaN; return a flag describing them."""
    low, high = PT100_RANGE_C
    values = frame[name].to_numpy()
    bad = np.flatnonzero((values < low) | (values > high))
    if not bad.size:
        return []
    examples = ", ".join(f"{_row_label(int(i), from_file)}: {values[i]:g} °C" for i in bad[:3])
    more = f" and {bad.size - 3} more" if bad.size > 3 else ""
    frame.loc[bad, name] = np.nan
    return [f"{name}: {bad.size} sample(s) outside the PT100 range {low:g} to {high:g} °C treated as "
            f"missing ({examples}{more})"]


def resample(data: MeasurementData, dt_s: float) -> MeasurementData:
    """Put ``data`` on the uniform grid ``t0, t0 + dt, t0 + 2 dt, ...`` (``t0`` the first time).

    Inputs are held from the latest sample at or before each grid time (zero-order hold, as the
    simulation reads them). Sensor columns are interpolated linearly between valid samples; a grid
    time whose nearest valid sample is more than ``dt_s`` away gets NaN (no measurement) rather
    than an invented value.

    Parameters
    ----------
    data : MeasurementData
        Validated data at any, possibly irregular, sampling.
    dt_s : float
        Grid step, s; positive and not longer than the record.

    Returns
    -------
    MeasurementData
        Same schema on the grid, with recomputed ``missing_counts``.
    """
    time_s = data.time_s
    duration_s = time_s[-1] - time_s[0]
    try:
        dt_s = float(dt_s)
    except (TypeError, ValueError):
        raise InputError("dt_s", dt_s, "the resampling step must be a number of seconds") from None
    if not np.isfinite(dt_s) or dt_s <= 0.0:
        raise InputError("dt_s", dt_s, "the resampling step must be a positive number of seconds")
    if dt_s > duration_s:
        raise InputError("dt_s", dt_s, f"longer than the record ({duration_s:g} s from {data.source})")
    tolerance_s = 1e-9 * dt_s
    grid = time_s[0] + dt_s * np.arange(int(np.floor(duration_s / dt_s + 1e-9)) + 1)
    held = np.searchsorted(time_s, grid + tolerance_s, side="right") - 1
    columns = {"time_s": grid}
    columns.update({name: data.frame[name].to_numpy()[held] for name in INPUT_NAMES})
    sensors = [name for name in data.frame.columns if name not in columns]
    for name in sensors:
        columns[name] = _interpolate_valid(time_s, data.frame[name].to_numpy(), grid, dt_s + tolerance_s)
    frame = pd.DataFrame(columns)
    missing = {name: int(frame[name].isna().sum()) for name in sensors}
    return MeasurementData(frame, f"{data.source} resampled to {dt_s:g} s", missing,
                           list(data.flags), list(data.ignored_columns))


def _interpolate_valid(time_s, values, grid, max_gap_s) -> np.ndarray:
    """Linear interpolation through the finite samples; NaN where the nearest one is > max_gap_s."""
    valid = np.isfinite(values)
    if not valid.any():
        return np.full(grid.shape, np.nan)
    t_valid, v_valid = time_s[valid], values[valid]
    result = np.interp(grid, t_valid, v_valid)
    after = np.clip(np.searchsorted(t_valid, grid), 0, t_valid.size - 1)
    before = np.clip(after - 1, 0, t_valid.size - 1)
    nearest_s = np.minimum(np.abs(t_valid[after] - grid), np.abs(grid - t_valid[before]))
    result[nearest_s > max_gap_s] = np.nan
    return result
