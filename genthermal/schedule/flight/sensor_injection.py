"""Sensor faults of a flight scenario (the ``sensor_faults`` key: bias, drift, stuck) and what they
do to the readings. Main objects: :func:`parse_sensor_faults`, :class:`SensorFaultInjector`; the
key's format: docs/guide/flight-reference.md.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ...conditions import checked_number, reject_unknown_keys
from ...errors import InputError
from ...sensor_faults import SENSOR_FAULT_KINDS, SensorFault

SCENARIO_KEY = "sensor_faults"


@dataclasses.dataclass(frozen=True)
class FlightSensorFault:
    """A sensor fault of one generator: ``fault.onset_s`` is the time since the mission start.

    Attributes
    ----------
    generator : int
    fault : SensorFault
    row : int or None
        Row of the measurement vector the sensor reads; None for an input sensor.
    """

    generator: int
    fault: SensorFault
    row: int | None

    @property
    def on_input(self) -> bool:
        """True for a sensor of a model input (inlet, ambient)."""
        return self.row is None


def parse_sensor_faults(entries, names, outputs, inputs=()) -> tuple[FlightSensorFault, ...]:
    """The ``sensor_faults`` scenario key (module docstring); InputError names the bad field.

    Parameters
    ----------
    entries : list or None
    names : sequence of str
        Generator names.
    outputs : sequence of str
        The flown model's outputs (the measurement vector's rows).
    inputs : sequence of str
        The flown model's measured temperature inputs (inlet, ambient).
    """
    if entries is None:
        return ()
    if not isinstance(entries, list):
        raise InputError(SCENARIO_KEY, entries, "must be a list of sensor faults")
    faults = []
    for i, entry in enumerate(entries):
        path = f"{SCENARIO_KEY}[{i}]"
        if not isinstance(entry, dict):
            raise InputError(path, entry, "must be a mapping with generator, sensor, kind, onset_min, value")
        reject_unknown_keys(entry, ("generator", "sensor", "kind", "onset_min", "value"), prefix=f"{path}.")
        generator = entry.get("generator")
        if isinstance(generator, int) and not isinstance(generator, bool) and 1 <= generator <= len(names):
            index = generator - 1
        elif isinstance(generator, str) and generator in names:
            index = names.index(generator)
        else:
            raise InputError(f"{path}.generator", generator,
                             f"must be a generator number 1..{len(names)} or a name among {', '.join(names)}")
        sensor = entry.get("sensor")
        if sensor not in outputs and sensor not in inputs:
            raise InputError(f"{path}.sensor", sensor, f"must be one of {', '.join([*outputs, *inputs])}")
        kind = entry.get("kind")
        if kind not in SENSOR_FAULT_KINDS:
            raise InputError(f"{path}.kind", kind, f"must be one of {', '.join(SENSOR_FAULT_KINDS)}")
        if kind == "noise" and sensor in inputs:
            raise InputError(f"{path}.kind", kind, f"{sensor} is an input, logged without noise: use bias, drift, "
                             "stuck or gain")
        if "onset_min" not in entry:
            raise InputError(f"{path}.onset_min", None, "missing: give the onset (min since the mission start)")
        onset = checked_number(entry["onset_min"], f"{path}.onset_min", "a number of minutes")
        if not (math.isfinite(onset) and onset >= 0):
            raise InputError(f"{path}.onset_min", entry["onset_min"], "must be >= 0 min")
        if "value" not in entry and kind != "stuck":
            raise InputError(f"{path}.value", None, f"missing: give the size of the {kind} "
                             f"({SENSOR_FAULT_KINDS[kind]})")
        value = checked_number(entry.get("value", 0.0), f"{path}.value", f"a number ({SENSOR_FAULT_KINDS[kind]})")
        if kind == "noise" and not value >= 1.0:
            raise InputError(f"{path}.value", entry["value"], "is the factor on the noise standard deviation: >= 1")
        faults.append(FlightSensorFault(index, SensorFault(sensor, kind, float(value), 60.0 * float(onset)),
                                        list(outputs).index(sensor) if sensor in outputs else None))
    return tuple(faults)


class SensorFaultInjector:
    """Applies the scenario's sensor faults to the sensed outputs and inputs, cycle after cycle.

    Parameters
    ----------
    faults : sequence of FlightSensorFault
    noise_std_K : array_like
        Usual noise standard deviation of each output, K.
    seed : int
    """

    def __init__(self, faults, noise_std_K, seed: int = 0):
        self.faults, self.noise_std_K = tuple(faults), np.asarray(noise_std_K, dtype=float)
        self._rng = np.random.default_rng(seed + 7919)
        self._held: dict[int, float] = {}

    def apply(self, sample_times_s, sensed) -> np.ndarray:
        """``sensed`` (n_gen, n_outputs, n) at ``sample_times_s`` (n,), s since the mission start, as read."""
        read = np.array(sensed, dtype=float, copy=True)
        times = np.asarray(sample_times_s, dtype=float)
        for k, item in enumerate(self.faults):
            if item.on_input:
                continue
            fault, g, row = item.fault, item.generator, item.row
            if self._hold(k, fault, times, read[g, row]):
                continue
            read[g, row] = fault.reading(times, read[g, row], float(self.noise_std_K[row]), self._rng)
        return read

    def apply_inputs(self, sample_times_s, values: dict) -> dict:
        """The measured temperature inputs: ``values`` maps an input name to its true value
        (n_gen, n) at ``sample_times_s`` (n,), s since the mission start, °C; returns the readings
        (inputs without a fault as given)."""
        read = {name: np.array(v, dtype=float, copy=True) for name, v in values.items()}
        times = np.asarray(sample_times_s, dtype=float)
        for k, item in enumerate(self.faults):
            if not item.on_input or item.fault.sensor not in read:
                continue
            row = read[item.fault.sensor][item.generator]
            if not self._hold(k, item.fault, times, row):
                row[:] = item.fault.reading(times, row)
        return read

    def _hold(self, k: int, fault: SensorFault, times, reading) -> bool:
        """A ``stuck`` fault without a value holds the reading at its onset across cycles (in place);
        True when ``fault`` is one."""
        if fault.kind != "stuck" or fault.value != 0.0:
            return False
        after = times >= fault.onset_s
        if after.any() and k not in self._held:
            self._held[k] = float(reading[int(np.flatnonzero(after)[0])])
        if k in self._held:
            reading[after] = self._held[k]
        return True
