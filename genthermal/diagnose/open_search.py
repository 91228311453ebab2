"""Open search for a heat flow no catalogue names: a generic library of small effects.

:func:`heat_flow_library` builds one :class:`~genthermal.effects.Effect` per node group (slot and
end windings, stator iron, rotor, frame) and form (constant, ΣI², I_exc², per-phase I², I²θ, a
temperature-dependent or re-formed modelled loss, a conductance factor, one surface's convection
factor); :func:`open_search` runs the catalogue search with it. :func:`describe_term` says in words
what was found and :func:`effect_code` writes it as Python that registers a new effect. Method:
``docs/guide/methods.md``.
"""

from __future__ import annotations

from typing import Mapping

import sympy

from ..effects import Effect, EffectParameter
from ..errors import InputError
from ..losses import input_symbol, mass_shares
from ..machines.interface import Role
from ..model import ThermalModel
from ..network import HeatSource
from .loss_terms import (I2_BOUND, I2_TYPICAL, LOSS_GROUPS, REFORMED_LOSSES, loss_reform_effect,
                         loss_temperature_effect)
from .search import FoundEffect

#: Extra heat-flow forms: name → (plain-language factor, unit of k, bound on |k|, typical k).
HEAT_FORMS = {
    "constant": ("", "W", 500.0, 20.0),
    "I2": ("ΣI²", "W/A^2", I2_BOUND, I2_TYPICAL),
    "I_exc2": ("I_exc²", "W/A^2", 200.0, 20.0),
    "I_u2": ("I_u²", "W/A^2", 5.0, 0.3),
    "I_v2": ("I_v²", "W/A^2", 5.0, 0.3),
    "I_w2": ("I_w²", "W/A^2", 5.0, 0.3),
    "I2_theta": ("ΣI² (θ − 20 °C)", "W/(A^2 K)", 0.05, 0.003),
}
#: Forms tried on every node group; the others only on the slot winding.
COMMON_FORMS = ("constant", "I2", "I_exc2")
#: Conductances that can change: name → plain language.
CONDUCTANCES = {"winding_insulation": "the winding-to-core conductance",
                "frame_to_ambient": "the frame-to-ambient conductance",
                "air_streams": "the coolant air flow",
                "internal_convection": "the internal convection to the cooling air"}
#: Machine roles each conductance change reads.
CONDUCTANCE_NEEDS = {"winding_insulation": (Role.WINDING_INSULATION,), "frame_to_ambient": (Role.FRAME_TO_AMBIENT,),
                     "air_streams": (Role.COOLANT_FLOW,), "internal_convection": (Role.INTERNAL_CONVECTION,)}


#: Node groups of the extra heat flows: plain name → the machine role that names their nodes.
GROUP_ROLES = {"slot winding": Role.SLOT_WINDING, "end windings": Role.END_WINDINGS, "stator iron": Role.IRON,
               "rotor": Role.ROTOR, "frame": Role.FRAME}


def node_groups(model: ThermalModel) -> dict[str, tuple[str, ...]]:
    """Node groups of ``model`` for extra heat flows: plain name → capacitive nodes."""
    roles, states = model.spec.roles, set(model.state_names)
    groups = {g: (roles.get(role),) if role is Role.SLOT_WINDING else tuple(roles.get(role, ()))
              for g, role in GROUP_ROLES.items()}
    return {g: nodes for g, nodes in groups.items() if nodes and all(n in states for n in nodes)}


#: Machine roles each heat-flow form reads (a form applies to machines that have them).
FORM_NEEDS = {"constant": (), "I2": (Role.LOAD_CURRENTS,), "I_exc2": (Role.EXCITATION_CURRENT,),
              "I_u2": (Role.PHASE_CURRENTS,), "I_v2": (Role.PHASE_CURRENTS,), "I_w2": (Role.PHASE_CURRENTS,),
              "I2_theta": (Role.LOAD_CURRENTS,)}
#: Index of the phase (in the machine's PHASE_CURRENTS role) of the single-phase forms.
_PHASE_FORMS = {"I_u2": 0, "I_v2": 1, "I_w2": 2}


def _factor(form: str, temperature, roles):
    if form in _PHASE_FORMS:
        return input_symbol(roles[Role.PHASE_CURRENTS][_PHASE_FORMS[form]]) ** 2
    if form == "I_exc2":
        return input_symbol(roles[Role.EXCITATION_CURRENT]) ** 2
    if form == "constant":
        return sympy.Integer(1)
    squares = sum(input_symbol(p) ** 2 for p in roles[Role.LOAD_CURRENTS])
    return squares if form == "I2" else squares * (temperature - 20)


def _slug(group: str) -> str:
    return group.replace(" ", "_")


def heat_flow_effect(group: str, nodes: tuple[str, ...], form: str, name: str | None = None) -> Effect:
    """An extra heat flow :math:`k f` (``form`` of :data:`HEAT_FORMS`) into ``nodes``.

    Parameters
    ----------
    group : str
        Plain name of the node group (``"end windings"``).
    nodes : tuple of str
        Capacitive nodes; the flow is shared by heat capacity.
    form : str
        A key of :data:`HEAT_FORMS`.
    name : str, optional
        Effect name (default ``heat_<form>_<group>``); its parameter is ``k_<name>``.
    """
    if form not in HEAT_FORMS:
        raise InputError("form", form, f"must be one of {', '.join(HEAT_FORMS)}")
    label, unit, bound, typical = HEAT_FORMS[form]
    name = name or f"heat_{form}_{_slug(group)}"

    def transform(network, roles, k):
        shares = mass_shares(network, nodes)
        return network.with_heat_sources(
            [HeatSource(n, shares[n] * k * _factor(form, network.temperature_symbol(n), roles), name) for n in nodes])

    return Effect(name, f"extra heat flow k {label or '(constant)'} into the {group}".replace("  ", " "),
                  rf"q_{{{_slug(group)}}} \mathrel{{+}}= k\,{label or '1'}",
                  (EffectParameter(f"k_{name}", 0.0, unit, -bound, bound, typical),), transform,
                  f"residual follows {label or 'a constant heat input'} and is largest near the {group}",
                  needs=FORM_NEEDS[form] + ((GROUP_ROLES[group],) if group in GROUP_ROLES else ()))


def conductance_effect(role: str, name: str | None = None, coefficients: tuple[str, ...] | None = None) -> Effect:
    """A change of a conductance (``role`` of :data:`CONDUCTANCES`) by a factor :math:`k`.

    Parameters
    ----------
    role : str
        A key of :data:`CONDUCTANCES`.
    name : str, optional
        Effect name (default ``conductance_<role>``, with ``_<coefficient>`` for one surface); its
        parameter is ``k_<name>``.
    coefficients : tuple of str, optional
        With ``role`` ``"internal_convection"``: only these convection coefficients (of the
        machine's ``Role.INTERNAL_CONVECTION``) change, e.g. ``("h_top_air",)``: the convection of
        one surface (default: all of them).
    """
    if role not in CONDUCTANCES:
        raise InputError("conductance", role, f"must be one of {', '.join(CONDUCTANCES)}")
    if coefficients is not None and (role != "internal_convection" or not coefficients):
        raise InputError("coefficients", coefficients, "name one or more convection coefficients, and only for "
                         "the internal_convection conductance")
    name = name or f"conductance_{role}" + ("_" + "_".join(coefficients) if coefficients else "")
    what = CONDUCTANCES[role] if not coefficients else f"the convection {', '.join(coefficients)}"

    def transform(network, roles, k):
        if role == "air_streams":
            return network.scale_air_streams(k)
        if role == "internal_convection":
            return _scale_convection(network, coefficients or roles[Role.INTERNAL_CONVECTION], k)
        for a, b in roles[Role(role)]:
            network = network.scale_links(a, b, k)
        return network

    return Effect(name, f"{what} multiplied by a factor", r"G \to k\,G",
                  (EffectParameter(f"k_{name}", 1.0, "1", 0.05, 20.0, 0.5),), transform,
                  f"{what} changed", needs=CONDUCTANCE_NEEDS[role])


def _scale_convection(network, coefficients, k):
    """``network`` with every heat-transfer coefficient named in ``coefficients`` multiplied by ``k``."""
    symbols = {symbol.name: symbol for link in network.links for symbol in link.resistance.free_symbols}
    missing = [name for name in coefficients if name not in symbols]
    if missing:
        raise InputError("internal_convection", missing[0], "no link of the network uses this coefficient")
    return network.substitute_in_links({symbols[name]: k * symbols[name] for name in coefficients})


def heat_flow_library(model: ThermalModel) -> dict[str, Effect]:
    """The generic library for ``model``: heat flows (node group × form) and conductance changes."""
    library = {}
    for group, nodes in node_groups(model).items():
        forms = HEAT_FORMS if group == "slot winding" else COMMON_FORMS
        for form in forms:
            if all(model.spec.interface.has_role(role) for role in FORM_NEEDS[form]):
                effect = heat_flow_effect(group, nodes, form)
                library[effect.name] = effect
    for effect in ([loss_temperature_effect(label) for label in LOSS_GROUPS]
                   + [loss_reform_effect(label) for label in REFORMED_LOSSES]):
        if effect.unavailable_reason(model) is None:
            library[effect.name] = effect
    for role in CONDUCTANCES:
        effect = conductance_effect(role)
        if all(model.spec.interface.has_role(need) for need in effect.needs):
            library[effect.name] = effect
    if "conductance_internal_convection" in library:
        # one surface's convection: which surfaces the through-flow sweeps depends on the flow path
        for coefficient in model.spec.roles[Role.INTERNAL_CONVECTION]:
            effect = conductance_effect("internal_convection", coefficients=(coefficient,))
            library[effect.name] = effect
    return library


def describe_term(found: FoundEffect, catalogue: Mapping[str, Effect]) -> str:
    """Plain language for one found term of the library, e.g. "about 0.6 W/A² × I_v² into the slot
    winding from 0.90 h"."""
    parameters = catalogue[found.effect].parameters
    value = found.values[parameters[0].name]
    when = "from the start" if found.onset_index == 0 else f"from {found.onset_s / 3600:.2f} h"
    if found.effect.startswith("conductance_"):
        role, coefficients = conductance_role(found.effect)
        what = CONDUCTANCES[role] if not coefficients else f"the convection coefficient {coefficients[0]}"
        return f"{what} multiplied by about {value:.2f} {when}"
    if found.effect.startswith("loss_theta_"):
        label = found.effect[len("loss_theta_"):]
        return (f"the {label} loss of the {LOSS_GROUPS[label]} {'rising' if value > 0 else 'falling'} by about "
                f"{abs(value) * 100:.2g} % per K of their temperature {when}")
    if found.effect.startswith("loss_I2_"):
        label = found.effect[len("loss_I2_"):]
        square = found.values[parameters[1].name]
        return (f"the {label} loss of the {LOSS_GROUPS[label]} about {(1 + value) * 100:.2g} % of the model's "
                f"{'plus' if square >= 0 else 'minus'} {abs(square):.3g} W/A² × ΣI² (shared as the {label} loss) {when}")
    form, group = _form_and_group(found.effect)
    label, unit = HEAT_FORMS[form][:2]
    return (f"about {abs(value):.3g} {unit.replace('^2', '²')}{' × ' + label if label else ''} "
            f"{'into' if value > 0 else 'out of'} the {group} {when}")


def effect_code(found: FoundEffect, catalogue: Mapping[str, Effect], name: str) -> str:
    """Python source that builds the found term as a new effect called ``name`` and adds it to
    ``model`` at the fitted values. The code changes no global state; its last line, commented
    out, registers the effect so that model files and the command line know it by name."""
    effect = catalogue[found.effect]
    if found.effect.startswith("conductance_"):
        role, coefficients = conductance_role(found.effect)
        build = f"conductance_effect({role!r}, name={name!r}" + (f", coefficients={coefficients!r})" if coefficients else ")")
    elif found.effect.startswith("loss_theta_"):
        build = f"loss_temperature_effect({found.effect[len('loss_theta_'):]!r}, name={name!r})"
    elif found.effect.startswith("loss_I2_"):
        build = f"loss_reform_effect({found.effect[len('loss_I2_'):]!r}, name={name!r})"
    else:
        form, group = _form_and_group(found.effect)
        build = f"heat_flow_effect({group!r}, NODES, {form!r}, name={name!r})"
    lines = ["from genthermal.diagnose.loss_terms import loss_reform_effect, loss_temperature_effect",
             "from genthermal.diagnose.open_search import conductance_effect, heat_flow_effect, node_groups", ""]
    if "NODES" in build:
        lines.append(f"NODES = node_groups(model)[{_form_and_group(found.effect)[1]!r}]   # model: your ThermalModel")
    # the new effect's parameters are the found term's with its name in place of the term's
    values = ", ".join(f"k_{name}{p.name[len('k_' + found.effect):]}={found.values[p.name]:.6g}"
                       for p in effect.parameters)
    lines += [f"effect = {build}",
              f"model = model.with_effect(effect, {values})   # fitted: {describe_term(found, catalogue)}",
              "# from genthermal.effects import register_effect; register_effect(effect)   # to use it by name"]
    return "\n".join(lines) + "\n"


def conductance_role(effect_name: str) -> tuple[str, tuple[str, ...] | None]:
    """The conductance (a key of :data:`CONDUCTANCES`) and the convection coefficients of one
    surface (or None) of a conductance term's name (``conductance_internal_convection_h_top_air``)."""
    rest = effect_name[len("conductance_"):]
    for role in sorted(CONDUCTANCES, key=len, reverse=True):
        if rest == role:
            return role, None
        if rest.startswith(role + "_"):
            return role, (rest[len(role) + 1:],)
    raise InputError("effect", effect_name, "not a conductance term of the open library")


def _form_and_group(effect_name: str) -> tuple[str, str]:
    rest = effect_name[len("heat_"):]
    for form in sorted(HEAT_FORMS, key=len, reverse=True):
        if rest.startswith(form + "_"):
            return form, rest[len(form) + 1:].replace("_", " ")
    raise InputError("effect", effect_name, "not a heat-flow term of the open library")


def open_search(model: ThermalModel, data, **options):
    """Search the generic library (:func:`heat_flow_library`) instead of the catalogue.

    Parameters
    ----------
    model : ThermalModel
    data : MeasurementData, pandas.DataFrame or path
    **options
        Passed to :func:`~genthermal.diagnose.discover.diagnose` (``iterate``, ``dt_s``,
        ``progress``, ``pairs``, ``effects``, ...).

    Returns
    -------
    Diagnosis
        With ``catalogue`` the library; :func:`describe_term` and :func:`effect_code` turn each of
        its ``found`` terms into words and code.
    """
    from .discover import diagnose

    return diagnose(model, data, catalogue=heat_flow_library(model), **options)
