"""Sensor faults: what a misbehaving sensor does to its reading (the measurement, not the machine).

:class:`SensorFault` changes a sensor's reading from an onset: ``bias`` (K), ``drift`` (K/h),
``stuck`` (°C), ``gain`` (relative) or ``noise`` (a factor on the noise std), the common failure
modes of resistance thermometers in service; :func:`inject_sensor_faults` applies them to a
record. The table of readings: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd

from .errors import InputError

#: Kinds of sensor fault and the unit of their ``value``.
SENSOR_FAULT_KINDS = {"bias": "K", "drift": "K/h", "stuck": "°C", "gain": "(relative)", "noise": "(factor)"}


#: Largest fault a faulty but still reading resistance thermometer shows, by sensor kind and fault
#: kind (bias K, drift K/h, gain relative; a stuck reading must lie in :data:`STUCK_RANGE_C`). A
#: larger error is a broken element or lead, which reads open or short circuit (a stuck or absurd
#: value the logger flags), not a slightly wrong temperature. Sources and reasoning:
#: ``docs/guide/evidence.md``.
SENSOR_FAULT_BOUNDS = {"air": {"bias": 10.0, "drift": 5.0, "gain": 0.05},
                       "winding": {"bias": 15.0, "drift": 10.0, "gain": 0.05},
                       "iron": {"bias": 15.0, "drift": 10.0, "gain": 0.05}}
#: Increased noise is claimed from this factor on the noise standard deviation (a smaller growth is
#: within what a healthy reading's noise estimate varies by).
MIN_NOISE_FACTOR = 2.0
#: Readings a stuck sensor can hold, °C (beyond: an open or shorted element, not a temperature).
STUCK_RANGE_C = (-40.0, 200.0)


def sensor_kind(sensor: str) -> str:
    """``"air"`` (inlet, ambient, outlet), ``"winding"`` or ``"iron"`` for a sensor's name
    (column or model output); an unknown name is treated as ``"winding"`` (the widest bounds)."""
    name = sensor.lower()
    if any(word in name for word in ("inlet", "ambient", "outlet", "air", "coolant")):
        return "air"
    return "iron" if "iron" in name or "core" in name or "stator" in name else "winding"


def fault_bound_reason(fault: "SensorFault") -> str | None:
    """Why ``fault`` is larger than a sensor of its kind can be wrong (:data:`SENSOR_FAULT_BOUNDS`),
    in plain language; None when it is within the bounds."""
    if fault.kind == "stuck":
        low, high = STUCK_RANGE_C
        if fault.value != 0.0 and not low <= fault.value <= high:
            return f"a reading stuck at {fault.value:.1f} °C is outside [{low:g}, {high:g}] °C"
        return None
    kind = sensor_kind(fault.sensor)
    bound = SENSOR_FAULT_BOUNDS[kind].get(fault.kind)
    if bound is not None and abs(fault.value) > bound:
        return (f"{fault.describe()}: beyond the {bound:g} {fault.unit} a faulty {kind} sensor can be off "
                f"({fault.kind})")
    return None


def fault_bounds(fault: "SensorFault") -> tuple[float, float]:
    """The range of ``value`` a faulty but still reading sensor of the fault's kind can show
    (:data:`SENSOR_FAULT_BOUNDS`, :data:`STUCK_RANGE_C` for a stuck reading, in the unit of the
    fault's kind); NaN where no bound is set (a noise factor)."""
    if fault.kind == "stuck":
        return float(STUCK_RANGE_C[0]), float(STUCK_RANGE_C[1])
    bound = SENSOR_FAULT_BOUNDS[sensor_kind(fault.sensor)].get(fault.kind)
    return (-float(bound), float(bound)) if bound is not None else (math.nan, math.nan)


@dataclasses.dataclass(frozen=True)
class SensorFault:
    """One sensor fault (module docstring).

    Attributes
    ----------
    sensor : str
        Record column of the sensor (``"T_iron"``, ``"T_winding_u"``, ...) or model output it
        feeds (``"T_winding"`` in flight).
    kind : str
        A key of :data:`SENSOR_FAULT_KINDS`.
    value : float
        Size of the fault in the unit of its kind (bias K, drift K/h, stuck °C, gain relative,
        noise factor).
    onset_s : float
        Time of the onset from the start of the record, s.
    """

    sensor: str
    kind: str
    value: float
    onset_s: float = 0.0

    def __post_init__(self):
        if self.kind not in SENSOR_FAULT_KINDS:
            raise InputError("sensor fault kind", self.kind, f"must be one of {', '.join(SENSOR_FAULT_KINDS)}")
        if not (isinstance(self.value, (int, float)) and math.isfinite(self.value)):
            raise InputError(f"sensor fault {self.sensor}.{self.kind} value", self.value, "must be a finite number")
        if not (math.isfinite(self.onset_s) and self.onset_s >= 0.0):
            raise InputError(f"sensor fault {self.sensor}.{self.kind} onset_s", self.onset_s, "must be >= 0 s")
        if self.kind == "noise" and self.value < 1.0:
            raise InputError(f"sensor fault {self.sensor}.noise value", self.value,
                             "is the factor on the noise standard deviation: must be >= 1")

    @property
    def unit(self) -> str:
        """Unit of :attr:`value`."""
        return SENSOR_FAULT_KINDS[self.kind]

    def reading(self, elapsed_s, true_C, noise_std_K: float = 0.0,
                rng: np.random.Generator | None = None) -> np.ndarray:
        """What the faulty sensor reports.

        Parameters
        ----------
        elapsed_s : array_like
            Time of each sample from the start of the record, s.
        true_C : array_like
            The healthy sensor's reading (true temperature plus its usual noise), °C.
        noise_std_K : float
            The sensor's usual noise standard deviation, K (``noise`` kind only).
        rng : numpy.random.Generator, optional
            Random numbers of the ``noise`` kind (default seeded by 0).

        Returns
        -------
        numpy.ndarray
            The reading, °C.
        """
        elapsed = np.asarray(elapsed_s, dtype=float)
        reading = np.array(true_C, dtype=float, copy=True)
        after = elapsed >= self.onset_s
        if not after.any():
            return reading
        if self.kind == "bias":
            reading[after] += self.value
        elif self.kind == "drift":
            reading[after] += self.value * (elapsed[after] - self.onset_s) / 3600.0
        elif self.kind == "stuck":
            first = int(np.flatnonzero(after)[0])
            reading[after] = self.value if self.value != 0.0 else reading[first]
        elif self.kind == "gain":
            reading[after] *= 1.0 + self.value
        else:
            rng = np.random.default_rng(0) if rng is None else rng
            # independent noise of std sqrt(k^2 - 1) sigma on a reading of std sigma: std k sigma
            reading[after] += math.sqrt(self.value ** 2 - 1.0) * noise_std_K * rng.standard_normal(int(after.sum()))
        return reading

    def describe(self) -> str:
        """Plain language: ``"the T_iron sensor drifts by 1.40 K/h from 1.60 h"``."""
        when = f"from {self.onset_s / 3600:.2f} h" if self.onset_s > 0 else "from the start"
        what = {"bias": f"reads {abs(self.value):.2f} K {'high' if self.value > 0 else 'low'}",
                "drift": f"drifts by {self.value:+.2f} K/h",
                "stuck": f"is stuck at {self.value:.2f} °C" if self.value != 0.0 else "is stuck at its reading",
                "gain": f"reads {100 * abs(self.value):.1f} % {'high' if self.value > 0 else 'low'} (gain error)",
                "noise": f"is {self.value:.1f}× noisier than its usual noise"}[self.kind]
        return f"the {self.sensor} sensor {what} {when}"

    def to_dict(self) -> dict:
        """JSON entry."""
        return {"sensor": self.sensor, "kind": self.kind, "value": self.value, "unit": self.unit,
                "onset_s": self.onset_s, "text": self.describe()}


def inject_sensor_faults(record: pd.DataFrame, faults, noise_std_K: float = 0.1, seed: int = 0) -> pd.DataFrame:
    """A copy of ``record`` (measurement CSV schema) with ``faults`` applied to their sensor columns.

    Parameters
    ----------
    record : pandas.DataFrame
        With ``time_s`` and the faulty sensors' columns.
    faults : sequence of SensorFault
    noise_std_K : float
        Usual noise standard deviation of the sensors, K (``noise`` kind).
    seed : int
        Seeds the extra noise.
    """
    changed = record.copy()
    elapsed = record["time_s"].to_numpy(dtype=float) - float(record["time_s"].iloc[0])
    rng = np.random.default_rng(seed)
    for fault in faults:
        if fault.sensor not in changed:
            raise InputError("sensor fault sensor", fault.sensor,
                             f"is not a column of the record: {', '.join(c for c in changed if c.startswith('T_'))}")
        changed[fault.sensor] = fault.reading(elapsed, changed[fault.sensor].to_numpy(dtype=float), noise_std_K, rng)
    return changed
