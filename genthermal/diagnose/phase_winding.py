r"""Phase-resolved winding: the slot winding node split into one node per phase.

The machine models lump the slot winding of all three phases into one node, read by the winding
sensor. A rig has one PT100 per phase (``T_winding_u/v/w``); under unbalanced load, or with a
fault in one phase (a shorted turn), those differ, and one winding node cannot use that. The
variant here splits the slot winding node :math:`s` (role ``slot_winding``) into :math:`s_u, s_v,
s_w`, with no new parameter:

* each phase node has a third of the heat capacity, :math:`C_x = C_s/3`, and a third of every
  conductance of :math:`s`: each link :math:`(s, j)` of resistance :math:`R` becomes three links
  :math:`(s_x, j)` of resistance :math:`3R` (the phases occupy a third of the slots each); the
  phases exchange heat through the nodes they share (the winding's radial node towards the core,
  and the end windings);
* every heat source :math:`P(I_u, I_v, I_w, \theta_s)` of :math:`s` is split by phase as

  .. math::
      P_x = P\big|_{I_y = 0\ (y \ne x),\ \theta_s \to \theta_{s_x}} - \tfrac23\,P\big|_{I = 0,\ \theta_s \to \theta_{s_x}},

  which is exact for a loss that is a sum of per-phase terms plus a constant (copper loss
  :math:`R(\theta)\sum_p I_p^2`, a shorted turn :math:`R_{short}I_u^2` — all of it into phase u —,
  a constant or excitation-driven loss, shared equally);
* the sensors reading :math:`s` become ``T_winding_u``, ``T_winding_v``, ``T_winding_w`` on the
  phase nodes.

Under balanced load the three phase nodes see the same equations and start equal, so they stay
equal and equal to the single node: the variant then reproduces the model exactly (tested). The
variant is a *view* for fitting: effects are applied to the single-node model first (their roles
name the single node), then the view is taken
(:class:`~genthermal.diagnose.sensor_view.SensorView`).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import sympy

from ..errors import InputError
from ..losses import PHASE_CURRENTS, input_symbol
from ..model import ThermalModel
from ..network import HeatSource, Link, Node

PHASES = ("u", "v", "w")
#: The per-phase winding sensors of the rig CSV schema (:mod:`genthermal.measurements`).
PHASE_SENSORS = tuple(f"T_winding_{phase}" for phase in PHASES)


def _split_power(power: sympy.Expr, theta: sympy.Symbol, theta_phase: sympy.Symbol, phase: int) -> sympy.Expr:
    """The share of ``power`` that phase ``phase`` (0, 1, 2) carries (module docstring)."""
    currents = [input_symbol(p) for p in PHASE_CURRENTS]
    alone = {c: 0 for k, c in enumerate(currents) if k != phase}
    at_rest = {c: 0 for c in currents}
    local = power.subs(theta, theta_phase)
    return local.subs(alone) - sympy.Rational(2, 3) * local.subs(at_rest)


def phase_resolved(model: ThermalModel) -> ThermalModel:
    """``model`` with its slot winding node split into three phase nodes (module docstring).

    Parameters
    ----------
    model : ThermalModel
        A model whose spec names a capacitive ``slot_winding`` node read by a sensor.

    Returns
    -------
    ThermalModel
        Same parameters; outputs ``T_winding_u, T_winding_v, T_winding_w`` and the model's other
        sensors; variant ``"<variant>, phase-resolved winding"``.
    """
    slot = model.spec.roles.get("slot_winding")
    if slot is None:
        raise InputError("model.spec.roles", sorted(model.spec.roles), "no 'slot_winding' node to split by phase")
    network = model.network
    node = network.node(slot)
    if node.kind != "capacitive":
        raise InputError(f"node {slot}.kind", node.kind, "the slot winding must be capacitive to split by phase")
    if any(slot in (s.upstream, s.downstream) for s in network.air_streams):
        raise InputError("slot_winding", slot, "an air stream passes through it; cannot split it by phase")
    readers = [name for name, sensed in model.spec.sensors.items() if sensed == slot]
    if not readers:
        raise InputError("model.spec.sensors", model.spec.sensors, f"no sensor reads the slot winding {slot}")
    names = [f"{slot}_{phase}" for phase in PHASES]
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
            sources.append(HeatSource(name, _split_power(source.power, theta, theta_phases[k], k), source.label))
    split = network.replace(nodes=tuple(nodes), links=tuple(links), heat_sources=tuple(sources))
    sensors = {}
    for name, sensed in model.spec.sensors.items():
        if name == readers[0]:
            sensors.update(zip(PHASE_SENSORS, names))
        elif sensed != slot:
            sensors[name] = sensed
    roles = {k: v for k, v in model.spec.roles.items() if k != "slot_winding"}
    return model.with_network(split, sensors=sensors, roles=roles,
                              variant=f"{model.spec.variant}, phase-resolved winding")


#: A record's phase spread must exceed this many standard errors to count as real.
PHASE_SPREAD_SIGMAS = 6.0
#: Averaging window of the phase spread, s.
PHASE_SPREAD_WINDOW_S = 600.0


def phases_differ(frame, dt_s: float) -> bool:
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
        The record, with ``T_winding_u/v/w`` (°C); without them the answer is False.
    dt_s : float
        Its sample period, s.
    """
    from .search import noise_std

    if not all(column in frame for column in PHASE_SENSORS):
        return False
    readings = frame[list(PHASE_SENSORS)].to_numpy(dtype=float)
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
