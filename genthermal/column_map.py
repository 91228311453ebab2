"""Read any logger's CSV: a column map says which column is which model input or sensor, in what unit.

:class:`ColumnMap` (from a machine file's ``COLUMN_MAP``, a YAML file given with ``--columns`` or a
dict) maps each column to a model ``input``, a ``sensor`` or an ``auxiliary`` quantity, with its
unit. :func:`read_logged` converts one file into
:class:`~genthermal.measurements.MeasurementData` in the machine's schema, with checks that name
the file, the column and the value; :func:`read_logged_set` reads several files with the same
columns. The YAML form: ``docs/tutorials/real_motor.md``.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pandas as pd

from .errors import InputError
from .machines.interface import InputKind, MachineInterface

#: Units accepted per kind, with the factor and offset to the model's unit (value * f + o).
UNITS = {
    "temperature": {"degC": (1.0, 0.0), "°C": (1.0, 0.0), "C": (1.0, 0.0), "K": (1.0, -273.15),
                    "degF": (5.0 / 9.0, -32.0 * 5.0 / 9.0)},
    "speed": {"rpm": (1.0, 0.0), "1/min": (1.0, 0.0), "rad/s": (60.0 / (2.0 * math.pi), 0.0), "Hz": (60.0, 0.0)},
    "current": {"A": (1.0, 0.0), "kA": (1000.0, 0.0), "mA": (1e-3, 0.0)},
    "torque": {"N m": (1.0, 0.0), "Nm": (1.0, 0.0), "N·m": (1.0, 0.0), "kN m": (1000.0, 0.0)},
    "electrical_power": {"W": (1.0, 0.0), "kW": (1000.0, 0.0)},
}
#: Auxiliary quantities a map may name.
AUXILIARIES = ("torque", "electrical_power")
#: A median above this in a °C column (or below it in a K column) contradicts the declared unit, °C.
KELVIN_SPLIT_C = 150.0
#: Longest run of missing samples accepted in a sensor column, samples.
MAX_NAN_RUN = 30
#: Electrical power per watt of torque x speed (``b`` of the fit P_ele = a i² + b T ω over a record)
#: outside these bounds, well determined, means the speed's unit is wrong: a motor takes 1-1.3 W
#: per mechanical W; rad/s read as rpm gives ~10, rpm read as rad/s ~0.1.
POWER_PER_MECHANICAL_RANGE = (0.15, 4.0)


@dataclasses.dataclass(frozen=True)
class MappedColumn:
    """One column of the logger's file.

    Attributes
    ----------
    column : str
        Name in the file.
    role : str
        ``"input"``, ``"sensor"`` or ``"auxiliary"``.
    target : str
        Model input name, sensor column name, or auxiliary quantity.
    unit : str
        Unit of the values in the file.
    """

    column: str
    role: str
    target: str
    unit: str


@dataclasses.dataclass(frozen=True)
class ColumnMap:
    """Which logger column is which input or sensor (module docstring).

    Attributes
    ----------
    columns : tuple of MappedColumn
    dt_s : float or None
        Sample period of files without a time column, s.
    time_column : str or None
        Name of the time column in seconds, when the files have one.
    """

    columns: tuple
    dt_s: float | None = None
    time_column: str | None = None

    @classmethod
    def from_dict(cls, mapping: dict, interface: MachineInterface, where: str = "column map") -> "ColumnMap":
        """Build and check a map against ``interface`` (every input and sensor column mapped once)."""
        if not isinstance(mapping, dict) or not isinstance(mapping.get("columns"), dict):
            raise InputError(where, mapping, "a column map is a mapping with a 'columns' mapping "
                             "(file column -> {input|sensor|auxiliary: name, unit: unit})")
        unknown = sorted(set(mapping) - {"columns", "dt_s", "time_column"})
        if unknown:
            raise InputError(f"{where}.{unknown[0]}", mapping[unknown[0]], "unknown key (keys: columns, dt_s, time_column)")
        dt_s = mapping.get("dt_s")
        if dt_s is not None and not (isinstance(dt_s, (int, float)) and math.isfinite(dt_s) and dt_s > 0):
            raise InputError(f"{where}.dt_s", dt_s, "the sample period must be a number of seconds > 0")
        columns = []
        for name, spec in mapping["columns"].items():
            field = f"{where}.columns.{name}"
            if not isinstance(spec, dict):
                raise InputError(field, spec, "give {input|sensor|auxiliary: name, unit: unit}")
            roles = [r for r in ("input", "sensor", "auxiliary") if r in spec]
            if len(roles) != 1:
                raise InputError(field, spec, "name exactly one of input, sensor, auxiliary")
            role, target, unit = roles[0], str(spec[roles[0]]), str(spec.get("unit", ""))
            kind = _kind(role, target, interface, field)
            if unit not in UNITS[kind]:
                raise InputError(f"{field}.unit", unit, f"not a {kind} unit; accepted: {', '.join(UNITS[kind])}")
            columns.append(MappedColumn(str(name), role, target, unit))
        result = cls(tuple(columns), None if dt_s is None else float(dt_s), mapping.get("time_column"))
        result._check_complete(interface, where)
        return result

    @classmethod
    def from_yaml(cls, path, interface: MachineInterface) -> "ColumnMap":
        """Read a map from a YAML file (module docstring)."""
        import yaml

        path = Path(path)
        if not path.is_file():
            raise InputError("--columns", str(path), "no such file")
        try:
            mapping = yaml.safe_load(path.read_text(encoding="utf-8"))
        except yaml.YAMLError as exc:
            raise InputError("--columns", str(path), f"not valid YAML: {exc}") from None
        return cls.from_dict(mapping, interface, str(path))

    def _check_complete(self, interface: MachineInterface, where: str) -> None:
        targets = [c.target for c in self.columns if c.role != "auxiliary"]
        twice = sorted({t for t in targets if targets.count(t) > 1})
        if twice:
            raise InputError(where, twice[0], "is mapped from more than one column")
        needed = [*interface.input_names, *interface.sensor_columns]
        missing = [n for n in needed if n not in targets]
        if missing:
            raise InputError(where, missing[0], "this input or sensor column of the machine is not mapped "
                             f"(needed: {', '.join(needed)})")

    def of_role(self, role: str) -> list:
        """The mapped columns of ``role``."""
        return [c for c in self.columns if c.role == role]


def _kind(role: str, target: str, interface: MachineInterface, field: str) -> str:
    if role == "sensor":
        if target not in (*interface.sensor_columns, *interface.optional_columns):
            raise InputError(field, target, f"not a sensor column of the machine ({', '.join(interface.sensor_columns)})")
        return "temperature"
    if role == "auxiliary":
        if target not in AUXILIARIES:
            raise InputError(field, target, f"unknown auxiliary quantity; known: {', '.join(AUXILIARIES)}")
        return target
    kinds = {i.name: i.kind for i in interface.inputs}
    if target not in kinds:
        raise InputError(field, target, f"not an input of the machine ({', '.join(kinds)})")
    return {InputKind.TEMPERATURE: "temperature", InputKind.SPEED: "speed", InputKind.CURRENT: "current"}[kinds[target]]


def _convert(values: np.ndarray, kind: str, unit: str) -> np.ndarray:
    factor, offset = UNITS[kind][unit]
    return values * factor + offset


def _longest_nan_run(values: np.ndarray) -> tuple[int, int]:
    """(length, first index) of the longest run of NaN in ``values``."""
    missing = np.concatenate([[0], np.isnan(values).astype(int), [0]])
    edges = np.flatnonzero(np.diff(missing))
    if edges.size == 0:
        return 0, -1
    starts, ends = edges[::2], edges[1::2]
    longest = int(np.argmax(ends - starts))
    return int(ends[longest] - starts[longest]), int(starts[longest])


def read_logged(path, column_map: ColumnMap, interface: MachineInterface, dt_s: float | None = None,
                rated_current_A: float | None = None):
    """Read one logger file into the machine's schema.

    Parameters
    ----------
    path : str or os.PathLike
        The logger's CSV.
    column_map : ColumnMap
    interface : MachineInterface
        The machine the data come from (``model.spec.interface``).
    dt_s : float, optional
        Sample period, s, for a file without a time column (overrides the map's).
    rated_current_A : float, optional
        For the current plausibility check; default the interface's.

    Returns
    -------
    genthermal.measurements.MeasurementData

    Raises
    ------
    InputError
        Naming the file, column and value: unreadable file, mapped column not in the file,
        non-numeric cell, a unit the data contradict, a negative speed, a run of more than
        :data:`MAX_NAN_RUN` missing samples in a sensor, or no sample period.
    """
    from .measurements import dataframe_to_measurements

    source = str(path)
    try:
        raw = pd.read_csv(path)
    except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise InputError("file", source, f"not a readable CSV table: {exc}") from None
    raw.columns = [str(c).strip() for c in raw.columns]
    for mapped in column_map.columns:
        if mapped.column not in raw.columns:
            raise InputError(f"{source}: column", mapped.column, f"named by the column map (as {mapped.role} "
                             f"{mapped.target}) but not in the file; its columns: {', '.join(raw.columns)}")
    values = {}
    for mapped in column_map.columns:
        numbers = pd.to_numeric(raw[mapped.column], errors="coerce").to_numpy(dtype=float)
        bad = np.flatnonzero(raw[mapped.column].notna().to_numpy() & ~np.isfinite(numbers))
        if bad.size:
            raise InputError(f"{source}: column {mapped.column}, data row {bad[0] + 1}",
                             raw[mapped.column].iloc[bad[0]], "not a number")
        values[mapped] = numbers
    _check_units_against_data(values, source)
    frame = {}
    for mapped, numbers in values.items():
        if mapped.role == "auxiliary":
            continue
        kind = "temperature" if mapped.role == "sensor" else _kind("input", mapped.target, interface, "")
        converted = _convert(numbers, kind, mapped.unit)
        if kind == "speed":
            negative = np.flatnonzero(converted < 0)
            if negative.size:
                raise InputError(f"{source}: column {mapped.column}, data row {negative[0] + 1}",
                                 float(numbers[negative[0]]), f"a negative speed: {interface.inputs[interface.input_names.index(mapped.target)].description}")
        if mapped.role == "sensor":
            run, start = _longest_nan_run(converted)
            if run > MAX_NAN_RUN:
                raise InputError(f"{source}: column {mapped.column}, data rows {start + 1}-{start + run}", "NaN",
                                 f"{run} missing samples in a row (more than {MAX_NAN_RUN}): the sensor was lost; "
                                 "cut the record there or drop the sensor from the map")
        frame[mapped.target] = converted
    frame = pd.DataFrame(frame)
    if column_map.time_column:
        if column_map.time_column not in raw.columns:
            raise InputError(f"{source}: time column", column_map.time_column, "not in the file")
        time_s = pd.to_numeric(raw[column_map.time_column], errors="coerce").to_numpy(dtype=float)
    else:
        period = dt_s if dt_s is not None else column_map.dt_s
        if period is None:
            raise InputError(f"{source}: time", "no time column", "give the sample period (--dt 1, or dt_s in "
                             "the column map) or a time_column")
        time_s = np.arange(len(frame)) * float(period)
    frame.insert(0, "time_s", time_s)
    return dataframe_to_measurements(frame, source, rated_current_A, interface)


def _check_units_against_data(values: dict, source: str) -> None:
    """Temperatures whose magnitude contradicts their unit; a speed whose unit makes the
    mechanical power an impossible share of the electrical power (with torque and power logged)."""
    for mapped, numbers in values.items():
        if not np.isfinite(numbers).any():
            continue
        median = float(np.nanmedian(numbers))
        field = f"{source}: column {mapped.column}"
        if mapped.unit in ("degC", "°C", "C") and median > KELVIN_SPLIT_C:
            raise InputError(field, f"median {median:g}", f"declared {mapped.unit} but the values look like kelvin "
                             "(declare unit: K, or subtract 273.15)")
        if mapped.unit == "K" and median < KELVIN_SPLIT_C:
            raise InputError(field, f"median {median:g}", "declared K but the values look like °C (declare unit: degC)")
    by_target = {m.target: (m, v) for m, v in values.items()}
    speeds = [(m, v) for m, v in values.items() if m.role == "input" and m.unit in UNITS["speed"]
              and m.target not in AUXILIARIES]
    if not (speeds and "torque" in by_target and "electrical_power" in by_target):
        return
    (speed_column, speed), (torque_column, torque) = speeds[0], by_target["torque"]
    power_column, power = by_target["electrical_power"]
    currents = [_convert(v, "current", m.unit) for m, v in values.items() if m.role == "input" and m.unit in UNITS["current"]]
    omega = _convert(speed, "speed", speed_column.unit) * 2.0 * math.pi / 60.0
    mechanical = _convert(torque, "torque", torque_column.unit) * omega
    electrical = _convert(power, "electrical_power", power_column.unit)
    current_squared = sum((c ** 2 for c in currents), np.zeros_like(electrical))
    valid = np.isfinite(mechanical) & np.isfinite(electrical) & np.isfinite(current_squared)
    if valid.sum() < 20:
        return
    design = np.column_stack([current_squared[valid], mechanical[valid]])
    coefficients, *_ = np.linalg.lstsq(design, electrical[valid], rcond=None)
    residual = electrical[valid] - design @ coefficients
    dof = max(int(valid.sum()) - 2, 1)
    information = design.T @ design
    if np.linalg.cond(information) > 1e14:
        return
    std = math.sqrt(float(residual @ residual) / dof * np.linalg.inv(information)[1, 1])
    per_mechanical = float(coefficients[1])
    low, high = POWER_PER_MECHANICAL_RANGE
    if (per_mechanical > high or per_mechanical < low) and std < 0.05 * abs(per_mechanical):
        likely = "rad/s declared as rpm" if per_mechanical > high else "rpm declared as rad/s or Hz"
        raise InputError(f"{source}: column {speed_column.column}", f"unit {speed_column.unit}",
                         f"with it the electrical power is {per_mechanical:.2f} W per W of torque x speed (fit "
                         f"P_ele = a i^2 + b T omega, b +- {std:.2f}); a motor takes 1-1.3: the speed unit is "
                         f"wrong ({likely}?)")


def read_logged_set(paths, column_map: ColumnMap, interface: MachineInterface, dt_s: float | None = None,
                    rated_current_A: float | None = None) -> list:
    """Read several logger files with one map; InputError when their column sets differ.

    Returns
    -------
    list of genthermal.measurements.MeasurementData
        One per file, in the order given.
    """
    paths = [str(p) for p in paths]
    if not paths:
        raise InputError("data", paths, "give at least one record")
    headers = {}
    for path in paths:
        try:
            headers[path] = [c.strip() for c in pd.read_csv(path, nrows=0).columns]
        except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
            raise InputError("file", path, f"not a readable CSV table: {exc}") from None
    first = paths[0]
    for path in paths[1:]:
        if set(headers[path]) != set(headers[first]):
            extra = sorted(set(headers[path]) - set(headers[first]))
            lacking = sorted(set(headers[first]) - set(headers[path]))
            what = f"has {extra[0]!r} that {first} lacks" if extra else f"lacks {lacking[0]!r} that {first} has"
            raise InputError(f"{path}: columns", extra[0] if extra else lacking[0],
                             f"the records of one call must have the same columns: {path} {what}")
    return [read_logged(p, column_map, interface, dt_s, rated_current_A) for p in paths]
