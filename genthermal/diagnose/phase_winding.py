"""Phase-resolved winding: the slot winding node split into one node per phase.

:func:`phase_resolved` splits the slot winding node into three phase nodes, each with a third of
its capacity and conductances and its heat sources split by phase, with no new parameter, and
reads one sensor per phase column (``T_winding_u/v/w``). Under balanced load it reproduces the
model exactly. It is a view for fitting (:class:`~genthermal.diagnose.sensor_view.SensorView`).
Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import sympy

from ..errors import InputError
from ..losses import input_symbol
from ..machines.interface import Role, Sensor
from ..model import ThermalModel
from ..network import HeatSource, Link, Node


def _split_power(power: sympy.Expr, theta: sympy.Symbol, theta_phase: sympy.Symbol, currents, phase: int) -> sympy.Expr:
    """The share of ``power`` that phase ``phase`` (an index of ``currents``) carries (module docstring)."""
    alone = {c: 0 for k, c in enumerate(currents) if k != phase}
    at_rest = {c: 0 for c in currents}
    local = power.subs(theta, theta_phase)
    return local.subs(alone) - sympy.Rational(2, 3) * local.subs(at_rest)


def phase_sensor(model: ThermalModel) -> Sensor | None:
    """The sensor that reads the slot winding through one CSV column per phase (the Genco's
    ``T_winding`` from ``T_winding_u/v/w``), or None when the model has none."""
    interface = model.spec.interface
    slot = interface.roles.get(Role.SLOT_WINDING)
    phases = interface.roles.get(Role.PHASE_CURRENTS, ())
    for sensor in interface.sensors:
        if slot is not None and sensor.node == slot and len(sensor.columns) == len(phases) == 3:
            return sensor
    return None


def phase_resolved(model: ThermalModel) -> ThermalModel:
    """``model`` with its slot winding node split into three phase nodes (module docstring).

    Parameters
    ----------
    model : ThermalModel
        A model whose interface names a capacitive slot winding (``Role.SLOT_WINDING``), the three
        phase currents (``Role.PHASE_CURRENTS``) and a sensor reading the slot winding through one
        column per phase.

    Returns
    -------
    ThermalModel
        Same parameters; the winding sensor replaced by one sensor per phase column (output = the
        column's name, e.g. ``T_winding_u``), in phase order; variant
        ``"<variant>, phase-resolved winding"``.
    """
    interface = model.spec.interface
    reader = phase_sensor(model)
    if reader is None:
        raise InputError("model.spec.interface", model.name, "needs a slot_winding node, three phase_currents and a "
                         "sensor reading the slot winding with one column per phase to split the winding by phase")
    slot = interface.roles[Role.SLOT_WINDING]
    currents = [input_symbol(name) for name in interface.roles[Role.PHASE_CURRENTS]]
    network = model.network
    node = network.node(slot)
    if node.kind != "capacitive":
        raise InputError(f"node {slot}.kind", node.kind, "the slot winding must be capacitive to split by phase")
    if any(slot in (s.upstream, s.downstream) for s in network.air_streams):
        raise InputError("slot_winding", slot, "an air stream passes through it; cannot split it by phase")
    names = [f"{slot}_{column}" for column in reader.columns]
    theta = network.temperature_symbol(slot)
    theta_phases = [sympy.Symbol(f"theta_{name}", real=True) for name in names]
    theta_mean = sum(theta_phases) / 3

    nodes = []
    for n in network.nodes:
        nodes += ([Node(name, "capacitive", n.capacitance / 3, n.role) for name in names] if n.name == slot else [n])
    links = []
    for link in network.links:
        if slot not in (link.a, link.b):
            links.append(link)
            continue
        for name in names:
            a, b = (name, link.b) if link.a == slot else (link.a, name)
            links.append(Link(a, b, 3 * link.resistance, f"{link.label} (one phase: a third of the slots)"))
    sources = []
    for source in network.heat_sources:
        if source.node != slot:  # a loss elsewhere that depends on the slot temperature sees the mean
            sources.append(dataclasses.replace(source, power=source.power.subs(theta, theta_mean)))
            continue
        for k, name in enumerate(names):
            sources.append(HeatSource(name, _split_power(source.power, theta, theta_phases[k], currents, k),
                                      source.label))
    split = network.replace(nodes=tuple(nodes), links=tuple(links), heat_sources=tuple(sources))
    sensors = []
    for sensor in interface.sensors:
        if sensor is reader:
            sensors += [Sensor(column, name, (column,), sensor.noise_variance_K2, sensor.limit_C,
                               f"{sensor.description} (phase column {column})")
                        for column, name in zip(sensor.columns, names)]
        elif sensor.node != slot:
            sensors.append(sensor)
    roles = {role: value for role, value in interface.roles.items() if role is not Role.SLOT_WINDING}
    resolved = dataclasses.replace(interface, sensors=tuple(sensors), roles=roles)
    return model.with_network(split, interface=resolved, variant=f"{model.spec.variant}, phase-resolved winding")


#: A record's phase spread must exceed this many standard errors to count as real.
PHASE_SPREAD_SIGMAS = 6.0
#: Averaging window of the phase spread, s.
PHASE_SPREAD_WINDOW_S = 600.0


def phases_differ(frame, dt_s: float, columns) -> bool:
    r"""True when a record's three winding sensors disagree by more than their noise explains.

    For each phase :math:`x`, the spread :math:`s_x = T_x - (T_y + T_z)/2` is averaged over
    :data:`PHASE_SPREAD_WINDOW_S`; with :math:`\sigma_s` the noise of :math:`s_x` (from its second
    differences, :func:`~genthermal.diagnose.search.noise_std`) and :math:`m` samples per window,
    the phases differ when some window mean exceeds
    :data:`PHASE_SPREAD_SIGMAS` :math:`\cdot\,\sigma_s/\sqrt m` in magnitude — a constant sensor
    offset between phases counts as well, so a record whose sensors disagree from the start is
    also fitted phase by phase.

    Parameters
    ----------
    frame : pandas.DataFrame
        The record (°C); without the three ``columns`` the answer is False.
    dt_s : float
        Its sample period, s.
    columns : sequence of str
        The three phase columns of the winding sensor (:func:`phase_sensor`).
    """
    from .search import noise_std

    if len(columns) != 3 or not all(column in frame for column in columns):
        return False
    readings = frame[list(columns)].to_numpy(dtype=float)
    window = max(int(round(PHASE_SPREAD_WINDOW_S / dt_s)), 1)
    for x in range(3):
        spread = readings[:, x] - readings[:, [y for y in range(3) if y != x]].mean(axis=1)
        spread = spread[np.isfinite(spread)]
        if spread.size < 3 * window:
            continue
        sigma = noise_std(spread[None, :])
        means = np.convolve(spread, np.ones(window) / window, mode="valid")
        if np.isfinite(sigma) and np.max(np.abs(means)) > PHASE_SPREAD_SIGMAS * sigma / np.sqrt(window):
            return True
    return False
