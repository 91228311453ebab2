"""The plant a flight flies: the :class:`Plant` protocol, what it is told (:class:`PlantSetup`), what it
answers (:class:`Readings`) and the manager's check of every answer (:func:`checked_readings`)."""

from __future__ import annotations

import dataclasses
from typing import Protocol, runtime_checkable

import numpy as np

from ..errors import GenthermalError, InputError

#: Timestamps of a plant's readings must match the end of each step within this, s.
TIMESTAMP_TOLERANCE_S = 1e-6


@dataclasses.dataclass(frozen=True)
class PlantSetup:
    """What a plant is told at :meth:`Plant.reset`.

    Attributes
    ----------
    generator_names : tuple of str
        The generators of the power system (``gen1``, ``gen2``), one plant instance each.
    input_names : tuple of str
        The machine's inputs, in the order of :meth:`Plant.step`'s ``inputs`` (phase currents, A RMS;
        excitation current, A; coolant inlet and ambient temperatures, °C).
    sensor_names : tuple of str
        The machine's temperature sensors the manager reads (``T_winding``, ``T_iron``).
    dt_s : float
        The step of the inputs, s.
    initial_C : float
        Every node's temperature at the start (a cold machine at the ambient), °C.
    faults : tuple of dict
        The scenario's faults (``generator`` 0-based, ``onset_s``, ``kind``, ``effect``, ``values``,
        ``inlet_rise_C``): a plant of its own may model them; their inlet rise is already in the
        inputs.
    """

    generator_names: tuple
    input_names: tuple
    sensor_names: tuple
    dt_s: float
    initial_C: float
    faults: tuple = ()


@dataclasses.dataclass(frozen=True)
class Readings:
    """What a plant's sensors read over one control interval.

    Attributes
    ----------
    time_s : numpy.ndarray
        (n,) timestamp of each sample, s since the mission start: the end of each step.
    values : numpy.ndarray
        (n_generators, n_sensors, n) temperatures, °C, in the order of ``sensor_names``.
    sensor_names : tuple of str
        The sensors read; the manager checks they are the machine's (:func:`checked_readings`).
    applied_A : numpy.ndarray, optional
        (n_generators, n) the phase currents the plant really carried over each step, A RMS, when
        they are not the commanded ones (a replayed log); None: the commanded currents.
    """

    time_s: np.ndarray
    values: np.ndarray
    sensor_names: tuple
    applied_A: np.ndarray | None = None


@runtime_checkable
class Plant(Protocol):
    """Anything a flight can fly: a simulator, an FMU, a rig.

    A plant holds one machine per generator. ``reset`` puts every node at ``setup.initial_C``;
    ``step`` applies the inputs of ``n`` steps of ``dt_s`` from ``t_s`` and returns what the sensors
    read at the end of each step. The manager adds the machine's sensor noise to the readings
    (``noise_variances_K2`` of its interface) and scores the flight on them; a plant that raises,
    or answers with other sensors, other timestamps or a non-finite value, stops the flight with a
    recorded fault (:class:`PlantFault`).

    Attributes
    ----------
    sensor_names : tuple of str
        The sensors the plant reads, checked against the machine's before take-off.
    """

    sensor_names: tuple

    def reset(self, setup: PlantSetup) -> None:
        """Start every generator's machine at ``setup.initial_C``."""

    def step(self, t_s: float, dt_s: float, inputs: dict) -> Readings:
        """Apply ``inputs`` (input name → (n_generators, n) values) over ``n`` steps of ``dt_s``
        from ``t_s`` (s); return the readings at ``t_s + dt_s * (1..n)``."""


class PlantFault(GenthermalError):
    """A plant that failed in flight: it raised, or its readings cannot be used.

    Attributes
    ----------
    kind : str
        ``raised``, ``sensors``, ``timestamps``, ``shape`` or ``not_finite``.
    """

    def __init__(self, kind: str, message: str):
        self.kind = kind
        super().__init__(message)


def check_sensors(plant, option: str, value, sensor_names) -> None:
    """Before take-off: ``plant.sensor_names`` must be the machine's ``sensor_names``; else an
    InputError naming ``option`` and ``value`` and the sensors missing or extra."""
    offered = tuple(getattr(plant, "sensor_names", ()) or ())
    missing = [s for s in sensor_names if s not in offered]
    extra = [s for s in offered if s not in sensor_names]
    if missing or extra or len(set(offered)) != len(offered):
        raise InputError(option, value, f"the plant's sensors {list(offered)} are not the machine's "
                         f"{list(sensor_names)}" + (f": missing {missing}" if missing else "")
                         + (f"; extra {extra}" if extra else "")
                         + ("; a sensor named twice" if len(set(offered)) != len(offered) else ""))


def checked_readings(readings, sensor_names, n_generators: int, expected_time_s: np.ndarray) -> np.ndarray:
    """The readings as (n_generators, len(sensor_names), n) in the machine's sensor order, °C; a
    :class:`PlantFault` naming what is wrong when they are not readings of the machine's sensors
    at ``expected_time_s`` (s), or not finite."""
    if not isinstance(readings, Readings):
        raise PlantFault("shape", f"the plant's step returned {type(readings).__name__}, not Readings")
    names = tuple(readings.sensor_names)
    missing = [s for s in sensor_names if s not in names]
    extra = [s for s in names if s not in sensor_names]
    if missing or extra:
        raise PlantFault("sensors", f"the plant read {list(names)}, not the machine's sensors {list(sensor_names)}"
                         + (f": missing {missing}" if missing else "") + (f"; extra {extra}" if extra else ""))
    values = np.asarray(readings.values, dtype=float)
    n = expected_time_s.size
    if values.shape != (n_generators, len(names), n):
        raise PlantFault("shape", f"the plant's readings have the shape {list(values.shape)}, not "
                         f"[{n_generators} generators, {len(names)} sensors, {n} samples]")
    time_s = np.asarray(readings.time_s, dtype=float)
    if time_s.shape != (n,) or not np.allclose(time_s, expected_time_s, rtol=0.0, atol=TIMESTAMP_TOLERANCE_S):
        raise PlantFault("timestamps", f"the plant's timestamps {time_s[:3].tolist()}... are not the ends of the "
                         f"steps {expected_time_s[:3].tolist()}...")
    ordered = values[:, [names.index(s) for s in sensor_names], :]
    if not np.all(np.isfinite(ordered)):
        g, k, i = (int(v[0]) for v in np.nonzero(~np.isfinite(ordered)))
        raise PlantFault("not_finite", f"the plant read {ordered[g, k, i]} for {sensor_names[k]} of generator "
                         f"{g + 1} at {expected_time_s[i]:g} s")
    return ordered
