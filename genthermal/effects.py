"""The effect catalogue: physical effects as small, named transformations of a model.

An :class:`Effect` turns a model's network (and the machine's roles) into a modified network with
one or two new named parameters (:class:`EffectParameter`, each with a neutral value at which the
effect vanishes). :data:`CATALOGUE` holds the registered effects, :func:`register_effect` adds one
and :func:`applicable_effects` lists those a model can take. How to write an effect:
``docs/tutorials/own-machine.md``.
"""

from __future__ import annotations

import dataclasses
import difflib
from typing import Callable

import sympy

from .errors import InputError
from .losses import LossFloor, input_symbol, mass_shares
from .machines.interface import Role
from .network import HeatSource, Network
from .parameters import Parameter
from . import speed_losses as speed


@dataclasses.dataclass(frozen=True)
class EffectParameter:
    """A parameter an effect adds to the model.

    Attributes
    ----------
    name : str
        Unique parameter name (``"k_flow"``).
    neutral : float
        Value at which the effect vanishes (the model is unchanged).
    unit : str
    lower, upper : float
        Physical bounds (inclusive), also the bounds used when the parameter is fitted.
    typical : float or None
        A clearly-active value, used to start a fit and in examples.
    plausible : (float, float) or None
        The range a real machine's effect can take (documented in ``docs/guide/evidence.md``):
        a diagnosis claims no effect fitted outside it (the fit's ``lower``/``upper`` are wider,
        so that a misfit pushed to an absurd value shows as such). None: the physical bounds.
    """

    name: str
    neutral: float
    unit: str
    lower: float
    upper: float
    typical: float | None = None
    plausible: tuple | None = None

    def is_plausible(self, value: float) -> bool:
        """Whether ``value`` lies in :attr:`plausible` (the physical bounds when None)."""
        low, high = self.plausible if self.plausible is not None else (self.lower, self.upper)
        return bool(low <= value <= high)

    def as_parameter(self, value: float, effect: str, provenance: str, source: str) -> Parameter:
        """The :class:`~genthermal.parameters.Parameter` carrying ``value`` for ``effect``."""
        if not (self.lower <= value <= self.upper):
            raise InputError(f"{effect}.{self.name}", value,
                             f"must lie in [{self.lower:g}, {self.upper:g}] {self.unit}")
        return Parameter(self.name, value, self.unit, provenance, source or f"effect {effect}",
                         lower=self.lower, upper=self.upper, lower_inclusive=True)


@dataclasses.dataclass(frozen=True)
class Effect:
    """A physical effect as a transformation of a model's network.

    Attributes
    ----------
    name : str
    summary : str
        One line in plain language.
    latex : str
        The effect's equation.
    parameters : tuple of EffectParameter
    transform : callable
        ``transform(network, roles, *symbols) -> Network`` with one sympy symbol per parameter.
    signature : str
        The residual pattern the effect explains, for diagnosis reports.
    requires : callable or None
        ``requires(model) -> str | None``: why the effect cannot apply to ``model`` (None if it
        can), for conditions beyond the roles (a parameter of the design model).
    shape_parameters : tuple of EffectParameter
        Parameters that shape the effect but do not switch it on (the exponent of a power law).
        A diagnosis search holds them at their default (``neutral``); ``calibrate`` fits them when
        named. ``transform`` takes their symbols after those of ``parameters``.
    needs : tuple of Role
        Machine roles the transform reads (``roles[Role.IRON]`` ...): the effect applies to every
        machine that has them and to no other.
    from_start : bool
        The effect is a property of the machine's design (a stray load loss, the field's iron loss):
        it is there from the first ampere and does not start while the machine runs. A diagnosis
        claims no such effect with an onset later than :data:`FROM_START_TOLERANCE_S` into a record.
    """

    name: str
    summary: str
    latex: str
    parameters: tuple[EffectParameter, ...]
    transform: Callable[..., Network]
    signature: str = ""
    requires: Callable | None = None
    shape_parameters: tuple[EffectParameter, ...] = ()
    needs: tuple[Role, ...] = ()
    from_start: bool = False

    def __post_init__(self):
        bad = [role for role in self.needs if not isinstance(role, Role)]
        if bad:
            raise InputError(f"effect {self.name}.needs", bad[0], "must be genthermal.machines.Role members, "
                             f"e.g. Role.IRON; known: {', '.join(r.name for r in Role)}")

    @property
    def all_parameters(self) -> tuple[EffectParameter, ...]:
        """The switching parameters followed by the shape parameters."""
        return self.parameters + self.shape_parameters

    def with_shapes_fitted(self) -> "Effect":
        """This effect with its shape parameters fitted beside the switching ones (same name), each
        bounded to its plausible range: a diagnosis then measures the shape (how far a blockage's
        convection follows the flow) instead of assuming it. Unchanged when it has none."""
        if not self.shape_parameters:
            return self
        shapes = tuple(dataclasses.replace(p, lower=p.plausible[0], upper=p.plausible[1]) if p.plausible else p
                       for p in self.shape_parameters)
        return dataclasses.replace(self, parameters=self.parameters + shapes, shape_parameters=())

    def implausible(self, values, onset_s: float | None = None) -> str | None:
        """Why fitted ``values`` (parameter name -> value) from ``onset_s`` (s into the record) are
        no finding for a real machine: the first parameter outside its plausible range, or an onset
        during the run of a :attr:`from_start` effect, in plain language; None when all is plausible."""
        for parameter in self.all_parameters:
            value = values.get(parameter.name)
            if value is not None and not parameter.is_plausible(float(value)):
                low, high = parameter.plausible or (parameter.lower, parameter.upper)
                return (f"{self.name}: {parameter.name} = {float(value):.4g} {parameter.unit} lies outside its "
                        f"plausible range [{low:g}, {high:g}]")
        if self.from_start and onset_s is not None and onset_s > FROM_START_TOLERANCE_S:
            return (f"{self.name} from {onset_s / 3600:.2f} h: a property of the design is there from the start, "
                    "it does not begin while the machine runs")
        return None

    def unavailable_reason(self, model) -> str | None:
        """Why this effect cannot be added to ``model``, or None when it can."""
        if self.name in model.spec.effects:
            return "already applied"
        clash = [p.name for p in self.all_parameters if p.name in model.parameters]
        if clash:
            return f"parameter {clash[0]} already in the model"
        missing = [role.value for role in self.needs if not model.spec.interface.has_role(role)]
        if missing:
            return f"the machine has no {', '.join(missing)} role"
        return self.requires(model) if self.requires else None


#: How late into a record a :attr:`Effect.from_start` effect may still be fitted to begin, s: the
#: initial state is fitted, so the first minutes carry little information on an onset.
FROM_START_TOLERANCE_S = 600.0

CATALOGUE: dict[str, Effect] = {}


def register_effect(effect: Effect) -> Effect:
    """Add ``effect`` to the catalogue (names must be unique) and return it."""
    if effect.name in CATALOGUE:
        raise InputError("effect", effect.name, "an effect of this name is already registered")
    CATALOGUE[effect.name] = effect
    return effect


def get_effect(name: str) -> Effect:
    """Return the catalogue effect called ``name`` or raise InputError suggesting the closest."""
    try:
        return CATALOGUE[name]
    except KeyError:
        close = difflib.get_close_matches(name, list(CATALOGUE), n=2)
        hint = f"did you mean {', '.join(close)}? " if close else ""
        raise InputError("effect", name, f"unknown effect; {hint}known: {', '.join(CATALOGUE)}") from None


def applicable_effects(model, catalogue=None) -> list[Effect]:
    """The effects of ``catalogue`` (default :data:`CATALOGUE`) that can be added to ``model``: the
    machine has every role they need and none is applied yet."""
    catalogue = CATALOGUE if catalogue is None else catalogue
    return [effect for effect in catalogue.values() if effect.unavailable_reason(model) is None]


def combination_reason(model, effects) -> str | None:
    """Why ``effects`` (Effect objects) cannot all be added to ``model`` in that order, or None when
    they can: each must still be available on the model with the ones before it (two forms of
    one loss, such as two speed-dependent iron losses, exclude each other)."""
    for k, effect in enumerate(effects):
        reason = effect.unavailable_reason(model)
        if reason:
            return f"{effect.name} after {', '.join(e.name for e in effects[:k]) or 'nothing'}: {reason}"
        if k + 1 < len(effects):
            model = model.with_effect(effect)
    return None


def apply_effect(model, effect, provenance: str = "assumed", source: str = "", **values):
    """Return ``model`` with ``effect`` applied at parameter ``values`` (neutral by default).

    Parameters
    ----------
    model : ThermalModel
    effect : str or Effect
    provenance, source : str
        Recorded on the effect's parameters (``"fitted"`` after a diagnosis).
    **values : float
        Parameter values by name.
    """
    effect = get_effect(effect) if isinstance(effect, str) else effect
    reason = effect.unavailable_reason(model)
    if reason:
        raise InputError("effect", effect.name, f"cannot be added to {model.name}: {reason}")
    known = {p.name for p in effect.all_parameters}
    unknown = set(values) - known
    if unknown:
        raise InputError(f"{effect.name} parameter", sorted(unknown)[0],
                         f"unknown; {effect.name} takes {', '.join(sorted(known)) or 'no parameters'}")
    new = [p.as_parameter(float(values.get(p.name, p.neutral)), effect.name, provenance, source)
           for p in effect.all_parameters]
    network = effect.transform(model.network, model.spec.roles, *[p.symbol for p in new])
    return model.with_network(network, model.parameters.with_parameters(*new),
                              effects=model.spec.effects + (effect.name,))


# --- helpers for the transformations ------------------------------------------------------------

def _copper_sources(network: Network) -> list[HeatSource]:
    return [s for s in network.heat_sources if s.label == "copper"]


def _replace_copper(network: Network, rewrite) -> Network:
    sources = tuple(dataclasses.replace(s, power=rewrite(s)) if s.label == "copper" else s
                    for s in network.heat_sources)
    return network.replace(heat_sources=sources)


def _needs_symbol(name: str, what: str):
    def requires(model):
        if name not in model.parameters:
            return f"the model has no {name} ({what})"
        free = set().union(*(s.power.free_symbols for s in _copper_sources(model.network)))
        if model.parameters[name].symbol not in free:
            return f"its copper loss does not use {name}: {what} is already modelled"
        return None
    return requires


def _copper_symbol(network: Network, name: str) -> sympy.Symbol:
    """The parameter symbol called ``name`` as used in the copper losses (assumptions included)."""
    for source in _copper_sources(network):
        for symbol in source.power.free_symbols:
            if symbol.name == name:
                return symbol
    raise InputError("copper loss", name, "the model's copper loss does not use this parameter")


def _current_squared(roles):
    return sum(input_symbol(p) ** 2 for p in roles[Role.LOAD_CURRENTS])


# --- the catalogue ---------------------------------------------------------------------------

def _resistance_temperature(network, roles, alpha):
    theta_ref = _copper_symbol(network, "theta_ref")
    return _replace_copper(network, lambda s: s.power * (1 + alpha * (network.temperature_symbol(s.node)
                                                                      - theta_ref)))


def _quadratic_copper(network, roles, weight):
    r"""Blend the linearised loss back to :math:`I^2`: :math:`(1-\lambda)P + \lambda P|_{aI_p \to I_p^2}`."""
    slope = _copper_symbol(network, "I2_slope")
    squares = {input_symbol(p): input_symbol(p) ** 2 for p in roles[Role.LOAD_CURRENTS]}

    def rewrite(source):
        line = source.power.replace(LossFloor, lambda value: value)  # the line through its floor
        per_current = sympy.expand(line).coeff(slope)  # the loss per unit slope: c sum_p I_p
        return (1 - weight) * source.power + weight * per_current.subs(squares, simultaneous=True)
    return _replace_copper(network, rewrite)


def _flow_reduction(network, roles, k_flow, n_flow):
    r"""Coolant flow :math:`\dot m \to k\,\dot m`; the internal convection coefficients follow
    the flow velocity, :math:`h \to h\,k^{n}` (forced convection :math:`Nu \propto Re^{n}`:
    n = 0.8 turbulent, Dittus-Boelter; 0.5 laminar). At :math:`k = 1` the model is unchanged for any n."""
    symbols = {symbol.name: symbol for link in network.links for symbol in link.resistance.free_symbols}
    convection = {symbols[name]: symbols[name] * k_flow ** n_flow
                  for name in roles.get(Role.INTERNAL_CONVECTION, ()) if name in symbols}
    return network.scale_air_streams(k_flow).substitute_in_links(convection)


def _phase_short(network, roles, R_short):
    first_phase = roles[Role.PHASE_CURRENTS][0]
    return network.with_heat_sources([HeatSource(roles[Role.SLOT_WINDING], R_short * input_symbol(first_phase) ** 2,
                                                 "phase_short_circuit")])


def _excitation_iron(network, roles, k_exc):
    shares = mass_shares(network, roles[Role.IRON])
    excitation = input_symbol(roles[Role.EXCITATION_CURRENT])
    return network.with_heat_sources([HeatSource(n, shares[n] * k_exc * excitation ** 2,
                                                 "excitation_iron_loss") for n in roles[Role.IRON]])


def _scale_links(role):
    def transform(network, roles, k):
        for a, b in roles[role]:
            network = network.scale_links(a, b, k)
        return network
    return transform


def _end_winding_stray(network, roles, R_stray):
    ends = roles[Role.END_WINDINGS]
    return network.with_heat_sources([HeatSource(n, R_stray * _current_squared(roles) / len(ends),
                                                 "end_winding_stray_loss") for n in ends])


for _effect in (
    Effect("copper_resistance_temperature", "winding resistance rises with its own temperature",
           r"R = R_{ref}\,(1 + \alpha_R(\theta_w - \theta_{ref}))",
           (EffectParameter("alpha_R", 0.0, "1/K", 0.0, 0.02, 0.0039, (0.002, 0.006)),), _resistance_temperature,
           "error grows with winding temperature at constant current: resistance rises with temperature",
           _needs_symbol("theta_ref", "temperature-dependent resistance"), needs=(Role.LOAD_CURRENTS,)),
    Effect("quadratic_copper_loss", "copper loss follows I^2 instead of the linearised a I + b",
           r"P = (1-\lambda)\,R(aI + b) + \lambda\,R I^2",
           (EffectParameter("lambda_I2", 0.0, "1", 0.0, 1.0, 1.0, (0.0, 1.0)),), _quadratic_copper,
           "error changes sign between low and high currents: the loss is quadratic in current",
           _needs_symbol("I2_slope", "the quadratic copper loss"), needs=(Role.LOAD_CURRENTS,)),
    Effect("coolant_flow_reduction",
           "fan mass flow reduced by a factor (blockage); internal convection falls as flow^n",
           r"\dot m \to k_{flow}\,\dot m,\quad h_{int} \to h_{int}\,k_{flow}^{\,n_{flow}}",
           (EffectParameter("k_flow", 1.0, "1", 0.05, 2.0, 0.5, (0.1, 0.9)),), _flow_reduction,
           "all temperatures and the outlet air run hot after an onset, at every load: less coolant flow",
           # n: k_flow = 1 is neutral for any n; default 0.8 from the Dittus-Boelter correlation
           # Nu = 0.023 Re^0.8 Pr^0.4 for turbulent forced convection (0.5 laminar); plausible 0..1:
           # 0 when the internal convection is driven by the rotor, not by the through-flow
           shape_parameters=(EffectParameter("n_flow", 0.8, "1", 0.0, 1.5, 0.8, (0.0, 1.0)),),
           needs=(Role.COOLANT_FLOW, Role.INTERNAL_CONVECTION)),
    Effect("phase_short_circuit", "shorted turns: extra loss R_short I_u^2 in the slot winding",
           r"q_{sw} \mathrel{+}= R_{short} I_u^2",
           (EffectParameter("R_short", 0.0, "ohm", 0.0, 5.0, 0.3, (0.0, 2.0)),), _phase_short,
           "winding runs hot after an onset, in proportion to I^2, iron follows: an extra winding loss",
           needs=(Role.SLOT_WINDING, Role.PHASE_CURRENTS)),
    # k_exc plausible 0..100 W/A^2: at the rated field current (1.02 A, genthermal.exciter at 7 A,
    # pf 0.8) 100 W/A^2 adds 104 W, 2.6 times the generator's whole iron loss (P_iron 40 W) and
    # 0.4 times its rated copper loss, already a severe core fault (shorted laminations); the
    # independent records' excitation faults are 25 and 48 W/A^2. The robustness grid draws within it.
    Effect("excitation_iron_loss", "iron loss grows with the excitation current squared",
           r"q_{iron} \mathrel{+}= k_{exc} I_{exc}^2",
           (EffectParameter("k_exc", 0.0, "W/A^2", 0.0, 200.0, 20.0, (0.0, 100.0)),), _excitation_iron,
           "iron error follows I_exc^2 more than I^2: iron loss depends on excitation",
           needs=(Role.IRON, Role.EXCITATION_CURRENT), from_start=True),
    Effect("winding_insulation_degradation", "winding-to-core conductance multiplied by a factor",
           r"G_{w,core} \to k_{ins}\,G_{w,core}",
           (EffectParameter("k_ins", 1.0, "1", 0.05, 10.0, 0.5, (0.2, 0.97)),), _scale_links(Role.WINDING_INSULATION),
           "winding hotter and iron cooler than modelled, more so at high load: winding-to-core path changed",
           needs=(Role.WINDING_INSULATION,)),
    Effect("end_winding_stray_loss", "extra stray loss R_stray I^2 in the end windings",
           r"q_{ew} \mathrel{+}= R_{stray} \sum_p I_p^2",
           (EffectParameter("R_stray", 0.0, "ohm", 0.0, 5.0, 0.2, (0.0, 1.5)),), _end_winding_stray,
           "winding error proportional to I^2 from the start, iron barely affected: an extra end-winding loss",
           needs=(Role.END_WINDINGS, Role.LOAD_CURRENTS), from_start=True),
    Effect("frame_cooling_change", "frame-to-ambient conductance multiplied by a factor",
           r"G_{f,amb} \to k_{frame}\,G_{f,amb}",
           (EffectParameter("k_frame", 1.0, "1", 0.05, 20.0, 3.0, (0.5, 5.0)),), _scale_links(Role.FRAME_TO_AMBIENT),
           "slow error that follows ambient temperature and the frame: external cooling changed",
           needs=(Role.FRAME_TO_AMBIENT,)),
):
    register_effect(_effect)


# --- speed-dependent effects (:mod:`genthermal.speed_losses`), for machines with a Role.SPEED ----
# Sizes refer to the machine's reference speed n_ref (SpeedRole.reference_rpm). Plausible ranges,
# all "assumed" orders of magnitude for machines of ~10-200 kW (docs/guide/evidence.md): iron loss
# 1-3 % of rated power at top speed, split at a fixed flux density into hysteresis (~ f) and
# classical eddy currents (~ f^2), each part up to about two thirds of it, the armature reaction
# raising it under load up to about twofold (assumed); the air-gap Nusselt number rises from ~2 (conduction) to
# ~10-20 in Taylor-Couette flow with vortices (Becker and Kaye 1962); end-space convection
# h = k1 (1 + k2 v^k3) rises a few-fold over the rotor's tip speeds (Boglietti et al. 2009); R_ac/R_dc
# of stranded windings at top frequency 1-1.5, hairpins up to 2; magnet eddy loss tens to hundreds of
# W, exponent 1 (skin-limited) to 2 (resistance-limited) and above with harmonics; bearing
# friction and windage tens to hundreds of W (friction torque ~0.1-1 N m).
for _effect in (
    Effect("speed_iron_loss", "iron loss rising with speed (hysteresis ~ n, eddy currents ~ n^2)",
           r"q_{iron} \mathrel{+}= P_{fe}\,(n/n_{ref})^{c_{fe}}",
           (EffectParameter("P_fe_ref", 0.0, "W", 0.0, 5000.0, 300.0, (0.0, 3000.0)),), speed.speed_iron_loss,
           "stator iron and winding run hot at speed whatever the current: an iron loss rising with speed",
           speed.loss_not_modelled(Role.IRON, "a speed-dependent iron loss"),
           shape_parameters=(EffectParameter("fe_speed_exponent", 1.5, "1", 1.0, 2.0, 1.5, (1.0, 2.0)),),
           needs=(Role.SPEED, Role.IRON), from_start=True),
    Effect("iron_loss_hysteresis_eddy", "iron loss as hysteresis (~ n) plus eddy currents (~ n^2), rising under load",
           r"q_{iron} \mathrel{+}= (P_h\,n/n_{ref} + P_e(n/n_{ref})^2)(1 + k_{fe}(I/I_{ref})^2)",
           (EffectParameter("P_hyst_speed", 0.0, "W", 0.0, 5000.0, 150.0, (0.0, 2000.0)),
            EffectParameter("P_eddy_speed", 0.0, "W", 0.0, 5000.0, 150.0, (0.0, 2000.0))),
           speed.hysteresis_eddy_iron_loss,
           "stator iron and winding run hot at speed, a little more under load: hysteresis and eddy iron loss",
           speed.loss_not_modelled(Role.IRON, "a speed-dependent iron loss"),
           shape_parameters=(EffectParameter("k_fe_load", 0.3, "1", 0.0, 5.0, 0.3, (0.0, 2.0)),),
           needs=(Role.SPEED, Role.IRON, Role.LOAD_CURRENTS), from_start=True),
    Effect("air_gap_convection_speed", "air-gap conductance rising with speed (Taylor-Couette flow)",
           r"G_{gap} \to G_{gap}\,(1 + k_{gap}\,n/n_{ref})",
           (EffectParameter("k_gap_speed", 0.0, "1", 0.0, 20.0, 2.0, (0.0, 10.0)),),
           speed.convection_rise(Role.AIR_GAP),
           "rotor cooler than modelled at speed, stator side warmer: the air gap conducts more when turning",
           speed.convection_not_modelled(Role.AIR_GAP, "an air-gap convection rising with speed"),
           needs=(Role.SPEED, Role.AIR_GAP), from_start=True),
    Effect("end_space_convection_speed", "end-space convection rising with speed (the rotor stirs the air)",
           r"G_{es} \to G_{es}\,(1 + k_{es}\,n/n_{ref})",
           (EffectParameter("k_end_space", 0.0, "1", 0.0, 10.0, 1.0, (0.0, 5.0)),),
           speed.convection_rise(Role.END_SPACE_CONVECTION),
           "end windings and rotor cooler than modelled at speed: the end-space air is stirred",
           speed.convection_not_modelled(Role.END_SPACE_CONVECTION, "an end-space convection rising with speed"),
           needs=(Role.SPEED, Role.END_SPACE_CONVECTION), from_start=True),
    Effect("ac_copper_loss", "copper loss rising with frequency (skin and proximity effect)",
           r"P_{cu} \to P_{cu}\,(1 + k_{ac}(n/n_{ref})^2)",
           (EffectParameter("k_ac_speed", 0.0, "1", 0.0, 2.0, 0.1, (0.0, 1.0)),), speed.ac_copper_loss,
           "winding runs hot at high current and high speed together: the copper loss grows with frequency",
           speed.copper_without_speed, needs=(Role.SPEED, Role.LOAD_CURRENTS), from_start=True),
    Effect("magnet_eddy_loss", "rotor (magnet eddy-current) loss rising with speed and current",
           r"q_{rotor} \mathrel{+}= P_{pm}\,(n/n_{ref})^{c_{pm}}\,(1 + k_{pm}(I/I_{ref})^2)",
           (EffectParameter("P_pm_speed", 0.0, "W", 0.0, 2000.0, 50.0, (0.0, 1000.0)),), speed.magnet_eddy_loss,
           "rotor runs hot at speed, more under load, stator barely affected: a rotor loss rising with speed",
           speed.loss_not_modelled(Role.ROTOR, "a speed-dependent rotor loss"),
           shape_parameters=(EffectParameter("pm_loss_exponent", 2.0, "1", 0.5, 3.0, 2.0, (1.0, 2.5)),
                             EffectParameter("k_pm_load", 1.0, "1", 0.0, 10.0, 1.0, (0.0, 5.0))),
           needs=(Role.SPEED, Role.ROTOR, Role.LOAD_CURRENTS), from_start=True),
    Effect("bearing_friction", "bearing friction loss rising with speed",
           r"q_{bearing} \mathrel{+}= P_{fr}\,n/n_{ref}",
           (EffectParameter("P_friction_speed", 0.0, "W", 0.0, 1000.0, 40.0, (0.0, 500.0)),), speed.bearing_friction,
           "bearing and shaft warm at speed without load: friction",
           speed.loss_not_modelled(Role.BEARING, "a bearing friction loss"),
           needs=(Role.SPEED, Role.BEARING), from_start=True),
):
    register_effect(_effect)
