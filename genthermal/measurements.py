"""Measured (or synthetic) rig data: one CSV schema, validated once, resampled onto a uniform grid.

:func:`load_measurements` reads a CSV in the machine's schema (``time_s``, its inputs, its sensor
columns) into :class:`MeasurementData`: inputs must be known (an empty or impossible value is an
:class:`~genthermal.errors.InputError` naming row and column), sensors may be missing, suspect
units and gaps are refused or flagged (:class:`DataWarning`). The schema and the checks:
``docs/guide/estimation.md`` and ``docs/guide/safety.md``.
"""

from __future__ import annotations

import difflib
import io
import os
import re
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .errors import InputError
from .input_limits import MAX_RECORD_BYTES, read_bounded
from .machines import MACHINES, DEFAULT_MACHINE
from .machines.interface import InputKind, MachineInterface
from .resources import shipped_data_file
from .sizes import check_grid
from .unit_checks import checked_units

#: Schema of the default machine (a machine's own: :func:`required_columns`).
DEFAULT_INTERFACE = MACHINES[DEFAULT_MACHINE].interface
#: The default machine's sensor columns of its first (limited) sensor: the winding PT100s.
WINDING_SENSORS = DEFAULT_INTERFACE.sensors[0].columns


def required_columns(interface: MachineInterface) -> tuple:
    """``time_s``, the inputs and the sensor columns of a machine's CSV schema."""
    return ("time_s", *interface.input_names, *interface.sensor_columns)


REQUIRED_COLUMNS = required_columns(DEFAULT_INTERFACE)
#: Measuring range of the rig's PT100 channels, °C (thesis Table 3.4).
PT100_RANGE_C = (-50.0, 300.0)
#: A phase or field current above this multiple of the machine's rated phase current is refused (no
#: generator of this kind carries it for longer than a fault clears; the model's losses are not
#: valid there; its exciter needs about 1 A of field current at rated load).
MAX_CURRENT_FACTOR = 3.0
#: Median temperatures above these (°C) mean the column is in kelvin: inputs are cooling air,
#: sensors a machine whose insulation fails near 200 °C.
KELVIN_MEDIAN_C = {"input": 150.0, "sensor": 200.0}
#: Median sample periods accepted, s: outside them ``time_s`` is not in seconds (milliseconds give
#: periods of hours for a logger at seconds; hours give milliseconds). The thesis rig logs at 10 s;
#: at more than an hour per sample the fastest slow mode (6.5 min) is not resolved at all.
SAMPLE_PERIOD_RANGE_S = (0.05, 3600.0)
#: A time step longer than this multiple of the median step is a gap, flagged.
GAP_FACTOR = 5.0
#: A sensor with more than this share of its samples outside the PT100 range is an error, not a flag.
MAX_OUT_OF_RANGE_SHARE = 0.5
_DECIMAL_COMMA = re.compile(r"^\s*[-+]?\d+,\d+(?:[eE][-+]?\d+)?\s*$")


class DataWarning(UserWarning):
    """Something about the data the user must know (missing samples, gaps, values dropped)."""


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
    interface : MachineInterface
        The machine whose schema the data follow (default: the default machine's).
    """

    frame: pd.DataFrame
    source: str
    missing_counts: dict[str, int] = field(default_factory=dict)
    flags: list[str] = field(default_factory=list)
    ignored_columns: list[str] = field(default_factory=list)
    interface: MachineInterface = DEFAULT_INTERFACE

    @property
    def time_s(self) -> np.ndarray:
        """Sample times, s."""
        return self.frame["time_s"].to_numpy(dtype=float)

    @property
    def inputs(self) -> pd.DataFrame:
        """The model inputs of the machine (units in ``interface.inputs``)."""
        return self.frame[list(self.interface.input_names)].copy()

    def output(self, name: str) -> np.ndarray:
        """Measured model output ``name``, °C: the mean of its sensor columns that measured at each
        sample (NaN only where all are missing)."""
        columns = list(self.interface.sensor(name).columns)
        return self.frame[columns].mean(axis=1, skipna=True).to_numpy(dtype=float)

    @property
    def winding(self) -> np.ndarray:
        """The first sensor's temperature (the winding, whose limit is protected), °C."""
        return self.output(self.interface.output_names[0])

    @property
    def iron(self) -> np.ndarray:
        """The second sensor's temperature (the iron), °C (NaN where not measured)."""
        return self.output(self.interface.output_names[1])

    @property
    def sensors(self) -> pd.DataFrame:
        """The model outputs as measured, one column per sensor output, °C."""
        return pd.DataFrame({name: self.output(name) for name in self.interface.output_names})

    def to_csv(self, path) -> None:
        """Write the schema columns to ``path`` (empty cells for missing sensor samples)."""
        self.frame.to_csv(path, index=False)


def load_measurements(path_or_buffer, rated_current_A: float | None = None,
                      interface: MachineInterface | None = None) -> MeasurementData:
    """Read and validate a rig CSV file (schema and accepted formats in the module docstring).

    Parameters
    ----------
    path_or_buffer : str, os.PathLike or file-like
        The CSV file, header on the first line.
    rated_current_A : float, optional
        Rated RMS phase current of the machine the data come from (``model.spec.rated_current_A``);
        default: the interface's.
    interface : MachineInterface, optional
        Schema of the machine the data come from (``model.spec.interface``); default: the
        default built-in machine's.

    Returns
    -------
    MeasurementData

    Raises
    ------
    InputError
        Not a text file, ragged rows, empty file, missing column, non-numeric value, unknown
        input, negative current, a current far above the rating, temperatures in kelvin, input
        temperature outside the PT100 range, or time not strictly increasing.
    """
    if isinstance(path_or_buffer, (str, os.PathLike)):
        path_or_buffer = shipped_data_file(str(path_or_buffer), ".csv") or path_or_buffer  # a shipped record by name
        source = str(path_or_buffer)
        content = read_bounded(path_or_buffer, "data file", MAX_RECORD_BYTES)  # no device, no endless pipe
    else:
        source = str(getattr(path_or_buffer, "name", "<buffer>"))
        content = path_or_buffer.read()
    text, notes = _decode(content, source)
    delimiter = _delimiter(text)
    header = text.lstrip().split("\n", 1)[0]
    if header.strip():
        names = [cell.strip().strip('"') for cell in header.split(delimiter)]
        _require_columns(names, source, interface or DEFAULT_INTERFACE)
        twice = sorted({name for name in names if names.count(name) > 1 and name})
        if twice:
            raise InputError("column", twice[0], f"appears more than once in the header of {source}")
    _check_row_lengths(text, delimiter)
    try:
        raw = pd.read_csv(io.StringIO(text), sep=delimiter, dtype=str, skipinitialspace=True)
    except pd.errors.EmptyDataError:
        raise InputError("file", source, "the file is empty: expected a header line and data rows") from None
    except pd.errors.ParserError as exc:
        raise InputError("file", source, f"not a readable CSV table: {str(exc).strip()}") from None
    if delimiter != "," and _has_decimal_commas(raw):
        raw = raw.apply(lambda column: column.str.replace(",", ".", regex=False))
        notes.append(f"read as {_DELIMITER_NAMES[delimiter]}-separated with decimal commas")
    return _validate(raw, source, from_file=True, rated_current_A=rated_current_A, notes=notes,
                     interface=interface)


def dataframe_to_measurements(frame: pd.DataFrame, source: str = "<DataFrame>",
                              rated_current_A: float | None = None,
                              interface: MachineInterface | None = None) -> MeasurementData:
    """Validate an in-memory frame exactly as :func:`load_measurements` validates a file."""
    return _validate(frame, source, from_file=False, rated_current_A=rated_current_A, interface=interface)


_DELIMITER_NAMES = {",": "comma", ";": "semicolon", "\t": "tab"}


def _decode(content, source: str) -> tuple[str, list[str]]:
    """The text of a CSV file and notes on how it was decoded; InputError for a binary file."""
    if isinstance(content, str):
        return content, []
    if content.startswith((b"\xff\xfe", b"\xfe\xff")):
        return content.decode("utf-16"), []
    if b"\x00" in content[:4096]:
        raise InputError("file", source, "is not a text CSV file (it holds binary data)")
    try:
        return content.decode("utf-8-sig"), []
    except UnicodeDecodeError:
        return content.decode("latin-1"), ["not UTF-8: decoded as Latin-1"]


def _delimiter(text: str) -> str:
    """The cell separator the header line uses: comma, semicolon or tab (most frequent)."""
    header = text.lstrip().split("\n", 1)[0]
    counts = {delimiter: header.count(delimiter) for delimiter in _DELIMITER_NAMES}
    best = max(counts, key=counts.get)
    return best if counts[best] > 0 else ","


def _check_row_lengths(text: str, delimiter: str) -> None:
    """Every non-blank line must have as many cells as the header (unquoted files)."""
    if '"' in text:
        return  # quoted cells may hold separators; the CSV parser checks those files
    lines = text.splitlines()
    numbered = [(n, line) for n, line in enumerate(lines, start=1) if line.strip()]
    if not numbered:
        return
    expected = numbered[0][1].count(delimiter)
    for number, line in numbered[1:]:
        cells = line.count(delimiter)
        if cells == expected:
            continue
        hint = "every row needs one cell per header column (leave a cell empty for a missing sensor sample)"
        if delimiter == "," and "." not in line and cells > expected:
            hint = ("decimal commas in a comma-separated file? write decimals with '.' or separate the cells "
                    "with ';'")
        raise InputError(f"line {number} of the file", line if len(line) <= 80 else line[:77] + "...",
                         f"has {cells + 1} cells but the header has {expected + 1}; {hint}")


def _has_decimal_commas(raw: pd.DataFrame) -> bool:
    first = raw.head(20).astype("string")
    return bool(first.apply(lambda column: column.str.match(_DECIMAL_COMMA).fillna(False)).to_numpy().any())


def _validate(raw: pd.DataFrame, source: str, from_file: bool, rated_current_A: float | None = None,
              notes: list[str] | None = None, interface: MachineInterface | None = None) -> MeasurementData:
    interface = interface or DEFAULT_INTERFACE
    raw = raw.reset_index(drop=True)
    raw.columns = [str(name).strip() for name in raw.columns]
    _require_columns(raw.columns, source, interface)
    if len(raw) == 0:
        raise InputError("file" if from_file else "frame", source, "no data rows below the header")
    present_sensors = [*interface.sensor_columns, *(c for c in interface.optional_columns if c in raw.columns)]
    columns = ["time_s", *interface.input_names, *present_sensors]
    frame = pd.DataFrame({name: _numeric_column(raw[name], name, from_file) for name in columns})
    frame = checked_units(frame, interface, rated_current_A)  # s, A and °C, or the column is named
    for name in ("time_s", *interface.input_names):
        _check_input_column(frame[name].to_numpy(), name, from_file, interface)
    _check_time_increasing(frame["time_s"].to_numpy(), from_file)
    _check_sample_period(frame["time_s"].to_numpy())
    rated = float(rated_current_A) if rated_current_A is not None else interface.rated_current_A
    _check_units(frame, present_sensors, from_file, rated, interface)
    flags = [f"{source}: {note}" for note in notes or []]
    flags.extend(_gap_flags(frame["time_s"].to_numpy(), from_file))
    for name in present_sensors:
        flags.extend(_discard_out_of_range(frame, name, from_file))
    missing_counts = {name: int(frame[name].isna().sum()) for name in present_sensors}
    flags.extend(f"{name}: no valid sample at all" for name, n in missing_counts.items() if n == len(frame))
    ignored = [name for name in raw.columns if name not in columns]
    for flag in flags:
        warnings.warn(flag, DataWarning, stacklevel=3)
    return MeasurementData(frame, source, missing_counts, flags, ignored, interface)


def _check_units(frame: pd.DataFrame, sensors, from_file: bool, rated_current_A: float,
                 interface: MachineInterface) -> None:
    """Temperatures in kelvin and currents far above the rating are errors with the likely fix."""
    limit = MAX_CURRENT_FACTOR * rated_current_A
    for name in interface.inputs_of_kind(InputKind.CURRENT):
        values = frame[name].to_numpy()
        above = np.flatnonzero(values > limit)
        if above.size:
            row = int(above[0])
            hint = (" The currents look like mA: divide by 1000." if np.nanmedian(values) / 1000.0 <= limit
                    and np.nanmedian(values) > limit else "")
            raise InputError(f"column {name}, {_row_label(row, from_file)}", float(values[row]),
                             f"more than {MAX_CURRENT_FACTOR:g} x the rated {rated_current_A:g} A RMS of the "
                             f"machine ({above.size} sample(s)); the model is not valid there.{hint}")
    temperatures = interface.inputs_of_kind(InputKind.TEMPERATURE)
    for name, kind in [*((n, "input") for n in temperatures), *((n, "sensor") for n in sensors)]:
        values = frame[name].to_numpy()
        if np.isfinite(values).any() and np.nanmedian(values) > KELVIN_MEDIAN_C[kind]:
            raise InputError(f"column {name}", f"median {np.nanmedian(values):g}",
                             "temperatures must be in °C; these look like kelvin: subtract 273.15")


def _check_sample_period(time_s: np.ndarray) -> None:
    """Refuse a median sample period outside :data:`SAMPLE_PERIOD_RANGE_S`: time not in seconds."""
    if time_s.size < 2:
        return
    period = float(np.median(np.diff(time_s)))
    low, high = SAMPLE_PERIOD_RANGE_S
    if low <= period <= high:
        return
    hint = ("if time_s is in milliseconds, divide it by 1000" if period > high else
            "if time_s is in hours or minutes, multiply it by 3600 or 60")
    raise InputError("column time_s", f"median step {period:g}", f"the sample period must be {low:g} to "
                     f"{high:g} s: time_s must be in seconds ({hint})")


def _gap_flags(time_s: np.ndarray, from_file: bool) -> list[str]:
    """Flag steps longer than GAP_FACTOR median steps (the sensors are missing across them)."""
    steps = np.diff(time_s)
    if steps.size < 2:
        return []
    median = float(np.median(steps))
    gaps = np.flatnonzero(steps > GAP_FACTOR * median)
    if not gaps.size:
        return []
    longest = int(gaps[np.argmax(steps[gaps])])
    return [f"time_s: {gaps.size} gap(s) longer than {GAP_FACTOR:g} sample periods ({median:g} s); the longest "
            f"is {steps[longest]:g} s after {_row_label(longest, from_file)} (t = {time_s[longest]:g} s): "
            "inputs are held across a gap and the sensors count as missing there"]


def _row_label(index: int, from_file: bool) -> str:
    """Name data row ``index`` (0-based) for messages: 1-based, plus the file line for files."""
    return f"data row {index + 1} (line {index + 2} of the file)" if from_file else f"data row {index + 1}"


def _require_columns(columns, source: str, interface: MachineInterface) -> None:
    present = list(columns)
    required = required_columns(interface)
    for name in required:
        if name in present:
            continue
        reason = f"required column missing in {source}"
        close = difflib.get_close_matches(name, [c for c in present if c not in required], n=1)
        same_letters = [c for c in present if c.lower() == name.lower()]
        if same_letters:
            reason += f"; column names are case-sensitive: rename {same_letters[0]!r} to {name!r}"
        elif close:
            reason += f"; did you mean {close[0]!r}?"
        else:
            reason += f"; the header must contain {', '.join(required)}"
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
        hint = "; write decimals with '.'" if _DECIMAL_COMMA.match(str(raw.iloc[row])) else ""
        raise InputError(f"column {name}, {_row_label(row, from_file)}", raw.iloc[row],
                         f"not a finite number{hint}")
    return values


def _check_input_column(values: np.ndarray, name: str, from_file: bool, interface: MachineInterface) -> None:
    """Inputs must be known and physical: no empty cell, no negative current, PT100 range."""
    empty = np.flatnonzero(np.isnan(values))
    if empty.size:
        raise InputError(f"column {name}, {_row_label(int(empty[0]), from_file)}", "",
                         "empty cell in an input column; only sensor columns may have missing samples")
    if name in interface.rms_currents:
        bad, reason = np.flatnonzero(values < 0.0), "a current (A RMS) cannot be negative"
    elif name in interface.inputs_of_kind(InputKind.SPEED):
        bad, reason = np.flatnonzero(values < 0.0), "a speed (rpm) cannot be negative"
    elif name in interface.inputs_of_kind(InputKind.TEMPERATURE):
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
    given = int(np.isfinite(values).sum())
    if bad.size > MAX_OUT_OF_RANGE_SHARE * given:
        raise InputError(f"column {name}", f"{bad.size} of {given} samples",
                         f"outside the PT100 range {low:g} to {high:g} °C: wrong unit or wrong column?")
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
    check_grid(duration_s, dt_s, "dt_s", dt_s)
    tolerance_s = 1e-9 * dt_s
    grid = time_s[0] + dt_s * np.arange(int(np.floor(duration_s / dt_s + 1e-9)) + 1)
    held = np.searchsorted(time_s, grid + tolerance_s, side="right") - 1
    columns = {"time_s": grid}
    columns.update({name: data.frame[name].to_numpy()[held] for name in data.interface.input_names})
    sensors = [name for name in data.frame.columns if name not in columns]
    for name in sensors:
        columns[name] = _interpolate_valid(time_s, data.frame[name].to_numpy(), grid, dt_s + tolerance_s)
    frame = pd.DataFrame(columns)
    missing = {name: int(frame[name].isna().sum()) for name in sensors}
    return MeasurementData(frame, f"{data.source} resampled to {dt_s:g} s", missing,
                           list(data.flags), list(data.ignored_columns), data.interface)


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
