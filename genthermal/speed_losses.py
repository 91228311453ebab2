"""Losses and convection that depend on the rotor speed, as transformations of a network.

The transforms behind the speed-dependent catalogue effects (:mod:`genthermal.effects`): iron loss
as a power law of speed or as hysteresis plus eddy currents, magnet eddy loss, AC copper loss,
bearing friction, and air-gap and end-space convection rising with speed. Each reads the machine's
roles (``Role.SPEED`` gives the speed input and the reference speed the sizes refer to) and applies
to any machine declaring them.
"""

from __future__ import annotations

import dataclasses

import sympy

from .losses import input_symbol, mass_shares
from .machines.interface import Role
from .network import HeatSource, Network

#: Offset of the speed ratio in a power law of speed, so that its derivative in the exponent stays
#: finite at standstill: (n/n_ref + eps)^c - eps^c is 0 at rest.
SPEED_OFFSET = 1e-3
#: Labels of the heat sources the transforms add.
LABELS = {"iron": "speed_iron_loss", "magnet": "magnet_eddy_loss", "friction": "bearing_friction",
          "convection": "convection_rise_with_speed"}


def speed_ratio(roles) -> sympy.Expr:
    """n / n_ref of the machine's :class:`~genthermal.machines.interface.SpeedRole` (1)."""
    speed = roles[Role.SPEED]
    return input_symbol(speed.input) / speed.reference_rpm


def speed_power(roles, exponent) -> sympy.Expr:
    """(n/n_ref)^c, 0 at standstill with a finite derivative in c (:data:`SPEED_OFFSET`)."""
    return (speed_ratio(roles) + SPEED_OFFSET) ** exponent - SPEED_OFFSET ** exponent


def load_squared(roles) -> sympy.Expr:
    """sum of the load currents squared over the reference current squared, (I/I_ref)^2 (1)."""
    reference = roles[Role.SPEED].reference_current_A
    return sum(input_symbol(name) ** 2 for name in roles[Role.LOAD_CURRENTS]) / reference ** 2


def speed_iron_loss(network: Network, roles, P_fe_ref, exponent) -> Network:
    r"""Iron loss :math:`P_{fe}(n/n_{ref})^{c}` (W) shared over the iron nodes by mass (hysteresis
    c = 1, eddy currents c = 2)."""
    shares = mass_shares(network, roles_nodes(roles[Role.IRON]))
    power = P_fe_ref * speed_power(roles, exponent)
    return network.with_heat_sources([HeatSource(n, share * power, LABELS["iron"]) for n, share in shares.items()])


def hysteresis_eddy_iron_loss(network: Network, roles, P_hyst_ref, P_eddy_ref, k_current,
                              first_share=None) -> Network:
    r"""Iron loss :math:`(P_h\,n/n_{ref} + P_e(n/n_{ref})^2)(1 + k_I (I/I_{ref})^2)` (W): hysteresis
    and classical eddy currents at a flux density held by the magnets, raised under load by the
    armature reaction.

    Parameters
    ----------
    network : Network
    roles : dict
        The machine's roles (``Role.SPEED``, ``Role.IRON``, ``Role.LOAD_CURRENTS``).
    P_hyst_ref, P_eddy_ref : sympy.Expr
        Hysteresis and eddy-current loss at the reference speed and no load, W.
    k_current : sympy.Expr
        Relative rise of the loss at the reference current, 1.
    first_share : sympy.Expr, optional
        Share of the loss in the first iron node (the teeth, of higher flux density), the rest
        shared over the other iron nodes by mass; None: every iron node by mass.
    """
    nodes = roles_nodes(roles[Role.IRON])
    if first_share is None:
        shares = mass_shares(network, nodes)
    else:
        shares = {nodes[0]: first_share}
        shares.update({n: (1 - first_share) * share for n, share in mass_shares(network, nodes[1:]).items()})
    s = speed_ratio(roles)
    power = (P_hyst_ref * s + P_eddy_ref * s ** 2) * (1 + k_current * load_squared(roles))
    return network.with_heat_sources([HeatSource(n, share * power, LABELS["iron"]) for n, share in shares.items()])


def magnet_eddy_loss(network: Network, roles, P_pm_ref, exponent, k_current) -> Network:
    r"""Rotor loss :math:`P_{pm}(n/n_{ref})^{c}\,(1 + k_I (I/I_{ref})^2)` (W) shared over the rotor
    nodes by mass: magnet eddy currents from slot and armature-field harmonics."""
    shares = mass_shares(network, roles_nodes(roles[Role.ROTOR]))
    power = P_pm_ref * speed_power(roles, exponent) * (1 + k_current * load_squared(roles))
    return network.with_heat_sources([HeatSource(n, share * power, LABELS["magnet"]) for n, share in shares.items()])


def bearing_friction(network: Network, roles, P_friction_ref) -> Network:
    r"""Friction :math:`P_{fr}\,n/n_{ref}` (W, a friction torque about independent of speed),
    shared equally over the bearing nodes."""
    nodes = roles_nodes(roles[Role.BEARING])
    power = P_friction_ref * speed_ratio(roles) / len(nodes)
    return network.with_heat_sources([HeatSource(n, power, LABELS["friction"]) for n in nodes])


def ac_copper_loss(network: Network, roles, k_ac) -> Network:
    r"""Copper loss :math:`P \to P\,(1 + k_{ac}(n/n_{ref})^2)`: skin and proximity effect grow with the
    square of the electrical frequency."""
    factor = 1 + k_ac * speed_ratio(roles) ** 2
    return network.replace(heat_sources=tuple(
        dataclasses.replace(s, power=s.power * factor) if s.label == "copper" else s for s in network.heat_sources))


def convection_rise(role: Role):
    r"""Transform scaling the conductance of the ``role`` links as :math:`G \to G(1 + k\,n/n_{ref})`,
    the rise carried as heat flows (link resistances may depend on parameters only)."""
    def transform(network: Network, roles, k) -> Network:
        theta, sources = network.temperature_symbol, []
        for a, b in roles[role]:
            conductance = sum(1 / link.resistance for link in network.links_between(a, b))
            flow = k * speed_ratio(roles) * conductance * (theta(a) - theta(b))
            sources += [HeatSource(b, flow, LABELS["convection"]), HeatSource(a, -flow, LABELS["convection"])]
        return network.with_heat_sources(sources)
    return transform


def _speed_symbol(model):
    return input_symbol(model.spec.roles[Role.SPEED].input)


def _depends_on_temperature(source, network) -> bool:
    names = {f"theta_{n.name}" for n in network.nodes}
    return any(symbol.name in names for symbol in source.power.free_symbols)


def loss_not_modelled(role: Role, what: str):
    """``requires(model)`` of a speed-dependent loss on the ``role`` nodes: why it cannot apply when
    a heat source there already depends on speed and on no temperature (the loss is modelled)."""
    def requires(model):
        nodes, speed = set(roles_nodes(model.spec.roles[role])), _speed_symbol(model)
        if any(s.node in nodes and speed in s.power.free_symbols and not _depends_on_temperature(s, model.network)
               for s in model.network.heat_sources):
            return f"the model already has {what} (a heat source on {', '.join(sorted(nodes))} rising with speed)"
        return None
    return requires


def convection_not_modelled(role: Role, what: str):
    """``requires(model)`` of a convection rise on the ``role`` links: why it cannot apply when a heat
    flow between a link's nodes already depends on speed (the rise is modelled)."""
    def requires(model):
        speed, theta = _speed_symbol(model), model.network.temperature_symbol
        for a, b in model.spec.roles[role]:
            if any(s.node in (a, b) and {speed, theta(a), theta(b)} <= s.power.free_symbols
                   for s in model.network.heat_sources):
                return f"the model already has {what} (a heat flow {a}-{b} rising with speed)"
        return None
    return requires


def roles_nodes(value) -> tuple:
    """A node role's value as a tuple of nodes."""
    return (value,) if isinstance(value, str) else tuple(value)


def copper_without_speed(model):
    """``requires`` of the AC copper loss: the model has copper losses that do not depend on speed."""
    copper = [s for s in model.network.heat_sources if s.label == "copper"]
    if not copper:
        return "the model has no heat sources labelled 'copper'"
    if any(_speed_symbol(model) in s.power.free_symbols for s in copper):
        return "its copper loss already depends on speed: the AC copper loss is modelled"
    return None
