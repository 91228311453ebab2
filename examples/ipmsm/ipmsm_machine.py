"""A water-cooled interior permanent-magnet motor on a test bench, as a genthermal machine plug-in.

The motor of the public bench data set of Liu et al. (IEEE Trans. Power Electronics 2024, doi
10.1109/TPEL.2024.3409388, MIT licence), as a 9-node network with copper, iron, magnet and
bearing losses and speed-dependent convection. ``MACHINE`` is the full model, ``MACHINE_PLAIN``
the plain one a first attempt would write (copper loss only, constant convection); the logger's
column map is :data:`COLUMN_MAP` (``columns.yaml`` beside this file). Every geometric value is
``assumed`` with its reason. Tutorial: ``docs/tutorials/real_motor.md``; the network and its
losses: ``docs/guide/methods.md``.
"""

from __future__ import annotations

from pathlib import Path

import sympy
import yaml

from genthermal import speed_losses as speed
from genthermal.losses import input_symbol
from genthermal.machines import InputKind, Machine, MachineInterface, ModelInput, Role, Sensor, SpeedRole
from genthermal.network import HeatSource, Link, Network, Node
from genthermal.parameters import Parameter, ParameterSet

NAME = "ipmsm_bench"
CURRENTS = ("i_d", "i_q")
#: Rated current amplitude, A (assumed: the bench profiles reach 350 A peak at 160 N·m briefly;
#: 250 A is the continuous level of the long profiles).
RATED_CURRENT_A = 250.0
#: Thermocouple noise variance, K² (the logger resolves 0.1 K; sigma ~0.15 K).
THERMOCOUPLE_NOISE_K2 = 0.02
#: Winding limit, °C (assumed: class-H insulation, 180 °C, minus a 40 K hot-spot margin).
WINDING_LIMIT_C = 140.0
#: Loss maps' reference speed, rpm (the top speed of the profiles).
N_REF_RPM = 4000.0
#: Speed at which the step's linear part is taken, rpm (mid-range: the convection's rise with speed
#: is the step's explicit part, and it stays below the conductances at rest at every speed of the
#: profiles, so that 10-s steps stay stable).
LINEARISATION_SPEED_RPM = 2000.0

INPUTS = (
    ModelInput("motor_speed", "rpm", InputKind.SPEED, "rotor speed (the motor does not run backwards)"),
    ModelInput("i_d", "A", InputKind.CURRENT, "d-axis current (amplitude-invariant, < 0 in field weakening)",
               signed=True),
    ModelInput("i_q", "A", InputKind.CURRENT, "q-axis current (amplitude-invariant)", signed=True),
    ModelInput("T_water", "degC", InputKind.TEMPERATURE, "water at the jacket outlet", 25.0),
    ModelInput("T_ambient", "degC", InputKind.TEMPERATURE, "air around the motor", 23.0),
)


def _sensor(output, node, columns, description, limit=None):
    return Sensor(output, node, tuple(columns), THERMOCOUPLE_NOISE_K2, limit, description)


SENSORS = (
    _sensor("T_winding", "winding_slot", ("activewind_1", "activewind_2"), "two thermocouples in the slot winding",
            WINDING_LIMIT_C),
    _sensor("T_slot_side", "winding_slot", ("slotside",), "thermocouple at the side of a slot, in the winding"),
    _sensor("T_end_winding", "end_winding", ("endwind_1", "endwind_2"), "thermocouples on both end windings",
            WINDING_LIMIT_C),
    _sensor("T_slot_open", "tooth", ("slotopen",), "thermocouple at the slot opening (tooth tip)"),
    _sensor("T_slot_bottom", "yoke_inner", ("slotbottom",), "thermocouple at the slot bottom (yoke)"),
    _sensor("T_outer_yoke", "yoke_outer", ("outer_yoke",), "thermocouple at the yoke's outer surface (jacket)"),
    _sensor("T_endcap", "endcap", ("endcap",), "thermocouple on the end cap"),
    _sensor("T_rotor", "rotor", ("rotor",), "rotor (magnet) temperature, telemetry"),
    _sensor("T_bearing", "shaft_bearing", ("bearing",), "bearing outer ring"),
)
ROLES = {
    Role.SLOT_WINDING: "winding_slot",
    Role.END_WINDINGS: ("end_winding",),
    Role.IRON: ("tooth", "yoke_inner"),
    Role.ROTOR: ("rotor",),
    Role.FRAME: ("yoke_outer", "endcap"),
    Role.WINDING_INSULATION: (("winding_slot", "tooth"), ("winding_slot", "yoke_inner")),
    Role.FRAME_TO_AMBIENT: (("endcap", "ambient"),),
    Role.LOAD_CURRENTS: CURRENTS,
    # the parts the speed-dependent catalogue effects act on (genthermal.speed_losses)
    Role.SPEED: SpeedRole("motor_speed", N_REF_RPM, RATED_CURRENT_A),
    Role.AIR_GAP: (("tooth", "rotor"),),
    Role.END_SPACE_CONVECTION: (("end_winding", "end_space_air"), ("rotor", "end_space_air"),
                                ("end_space_air", "endcap")),
    Role.BEARING: ("shaft_bearing",),
}
INTERFACE = MachineInterface(
    INPUTS, SENSORS, {"water": "T_water", "ambient": "T_ambient"}, RATED_CURRENT_A,
    ambient_input="T_ambient", coolant_input="T_water", coolant_medium="water", roles=ROLES,
    rated_inputs={"motor_speed": 3000.0, "i_d": -120.0, "i_q": 200.0, "T_water": 25.0},
    linearisation_inputs={"motor_speed": LINEARISATION_SPEED_RPM})

#: The logger's column map (``columns.yaml`` beside this file): file column -> model input or
#: sensor column, with its unit; auxiliary columns (torque, electrical power) serve unit checks.
COLUMN_MAP = yaml.safe_load((Path(__file__).parent / "columns.yaml").read_text(encoding="utf-8"))

#: The effects the plain model lacks, by name, with their parameters.
EFFECT_PARAMETERS = {
    "speed_iron_loss": ("P_hyst_ref", "P_eddy_ref", "k_fe_current", "tooth_iron_share"),
    "air_gap_convection_speed": ("G_gap_speed",),
    "end_space_convection_speed": ("k_end_space_speed",),
    "ac_copper_loss": ("k_ac",),
    "magnet_eddy_loss": ("P_pm_ref", "k_pm_current"),
    "magnet_loss_exponent": ("pm_speed_exponent",),
    "bearing_friction": ("P_friction_ref",),
}


#: A heat capacity stays within this factor of its estimate in a fit (masses of an unpublished
#: geometry are known to about a factor of two; beyond that the fit trades nodes for time constants).
CAPACITY_RANGE = 3.0


def _capacity(name, value, why):
    return Parameter(name, value, "J/K", "assumed", why, lower=value / CAPACITY_RANGE,
                     upper=value * CAPACITY_RANGE, lower_inclusive=True)


def _steel(name, kg, why):
    return _capacity(name, kg * 460.0, f"{kg:g} kg x 460 J/(kg K) (steel, literature): {why}")


def default_parameters() -> ParameterSet:
    """Parameter set of the bench IPMSM with the provenance of every value."""
    return ParameterSet([
        # heat capacities, J/K
        _capacity("C_winding_slot", 4.0 * 385.0 + 300.0,
                  "4 kg of copper in the slots x 385 J/(kg K) + 0.25 kg resin and liners (150 mm stack, ~60 % "
                  "of the conductor length in the slots)"),
        _capacity("C_end_winding", 2.6 * 385.0 + 200.0,
                  "2.6 kg of copper in both end windings x 385 J/(kg K) + potting"),
        _steel("C_tooth", 4.0, "teeth of a 220 mm stator, 150 mm stack"),
        _steel("C_yoke_inner", 5.0, "inner half of the back iron"),
        _capacity("C_yoke_outer", 5.0 * 460.0 + 4.0 * 900.0,
                  "outer half of the back iron (5 kg steel) with the aluminium jacket wall (4 kg x 900 J/(kg K))"),
        _capacity("C_endcap", 3.0 * 900.0, "two aluminium end caps, 1.5 kg each"),
        _capacity("C_rotor", 14.0 * 460.0 + 1.5 * 440.0, "rotor lamination 14 kg x 460 J/(kg K) + 1.5 kg NdFeB x "
                  "440 J/(kg K)"),
        _capacity("C_end_space_air", 500.0, "end-space air (~2 l) with the sheet-metal "
                  "baffles and winding-head surface layer it exchanges heat with"),
        _capacity("C_shaft_bearing", 4.0 * 460.0, "shaft ends and bearings, 4 kg of steel"),
        # conductances, W/K
        Parameter("G_slot_end", 6.0, "W/K", "assumed", "axial conduction in the copper: 400 W/(m K) x ~40 cm² "
                  "of copper over ~0.2 m from mid-stack to the end-winding centre, doubled for both ends"),
        Parameter("G_slot_tooth", 60.0, "W/K", "assumed", "slot liner and impregnation: ~0.4 m² of slot wall, "
                  "0.3 mm liner at 0.2 W/(m K) in series with the winding's radial conductance"),
        Parameter("G_slot_yoke", 25.0, "W/K", "assumed", "slot bottoms: ~1/3 of the slot wall area"),
        Parameter("G_tooth_yoke", 150.0, "W/K", "assumed", "radial conduction through the tooth roots, steel "
                  "25 W/(m K)"),
        Parameter("G_yoke_radial", 120.0, "W/K", "assumed", "radial conduction across the back iron, ~15 mm"),
        Parameter("G_jacket", 150.0, "W/K", "assumed", "water jacket: h ~ 2500 W/(m² K) on ~0.1 m² in series "
                  "with the lamination-housing contact gap"),
        Parameter("G_gap", 4.0, "W/K", "assumed", "0.7 mm air gap at rest: conduction and natural convection "
                  "over the ~0.08 m² rotor surface"),
        Parameter("G_gap_speed", 10.0, "W/K", "assumed", "rise of the air-gap conductance at n_ref (Taylor-"
                  "Couette flow, Nu growing about linearly with the rotational Reynolds number)",
                  lower_inclusive=True),
        Parameter("G_end_winding_air", 3.0, "W/K", "assumed", "end-winding surface ~0.06 m² x h ~ 50 W/(m² K) "
                  "of end-space air"),
        Parameter("G_rotor_air", 1.5, "W/K", "assumed", "rotor end faces ~0.03 m² x h ~ 50 W/(m² K)"),
        Parameter("G_air_endcap", 3.0, "W/K", "assumed", "inner end-cap surfaces ~0.06 m² x h ~ 50 W/(m² K)"),
        Parameter("k_end_space_speed", 1.0, "1", "assumed", "relative rise of the end-space convection at n_ref "
                  "(the rotor's end rings stir the air)", lower_inclusive=True),
        Parameter("G_end_winding_frame", 2.0, "W/K", "assumed", "end-winding potting and air towards the "
                  "jacket-cooled frame"),
        Parameter("G_frame_endcap", 8.0, "W/K", "assumed", "bolted aluminium joint frame-end cap"),
        Parameter("G_endcap_ambient", 1.5, "W/K", "assumed", "natural convection from ~0.15 m² of end caps"),
        Parameter("G_rotor_shaft", 15.0, "W/K", "assumed", "rotor hub to shaft, press fit"),
        Parameter("G_bearing_endcap", 3.0, "W/K", "assumed", "bearing outer ring into the end-cap bores"),
        # losses
        Parameter("R_0", 0.0132, "ohm", "fitted", "phase resistance at 0 °C (cables included), estimated from "
                  "the bench's own data: the fit P_ele = 1.5 R (i_d² + i_q²) + b T omega over each profile gives "
                  "R = 14.5-16.5 mOhm near 35 °C on 9 of the 12 profiles"),
        Parameter("alpha_cu", 0.00393, "1/K", "literature", "temperature coefficient of copper resistivity"),
        Parameter("end_winding_share", 0.4, "1", "assumed", "share of the conductor length in the end windings "
                  "(short-pitched distributed winding, 150 mm stack)", upper=1.0),
        Parameter("k_ac", 0.1, "1", "assumed", "AC copper-loss rise at n_ref (proximity and skin effect at "
                  "~270 Hz in stranded wire)", lower_inclusive=True),
        Parameter("P_hyst_ref", 250.0, "W", "assumed", "hysteresis iron loss at n_ref in ~9 kg of stator steel "
                  "(~1.2 T, 0.35 mm lamination)", lower_inclusive=True),
        Parameter("P_eddy_ref", 250.0, "W", "assumed", "eddy iron loss at n_ref, same split as hysteresis",
                  lower_inclusive=True),
        Parameter("k_fe_current", 0.3, "1", "assumed", "relative iron-loss rise at I_ref from armature reaction",
                  lower_inclusive=True),
        Parameter("tooth_iron_share", 0.5, "1", "assumed", "share of the iron loss in the teeth (higher flux "
                  "density, less mass than the yoke)", upper=1.0),
        Parameter("P_pm_ref", 50.0, "W", "assumed", "magnet eddy loss at n_ref from slot harmonics "
                  "(segmented NdFeB)", lower_inclusive=True),
        Parameter("k_pm_current", 1.0, "1", "assumed", "relative rise of the magnet loss at I_ref "
                  "(armature-field harmonics)", lower_inclusive=True),
        Parameter("pm_speed_exponent", 2.0, "1", "assumed", "exponent of the magnet eddy loss in speed: 2 for "
                  "resistance-limited eddy currents, towards 1.5 when skin effect limits them (literature "
                  "range 1-2.5)", lower=0.5, upper=3.0),
        Parameter("P_friction_ref", 40.0, "W", "assumed", "bearing friction and windage at n_ref (two deep-"
                  "groove bearings, ~0.1 N m)", lower_inclusive=True),
    ])


def build_network(parameters: ParameterSet) -> Network:
    """The nine-node LPTN (module docstring) from the symbols of ``parameters``: the plain network
    (copper loss, constant convection) and, for each effect of :data:`EFFECT_PARAMETERS` whose
    parameters the set holds, its catalogue transform (:mod:`genthermal.speed_losses`) at the
    file's parameters; an effect whose parameters the set lacks is left out (the plain model)."""
    S = parameters.symbols()
    has = {effect: all(n in parameters for n in names) for effect, names in EFFECT_PARAMETERS.items()}
    current_squared = input_symbol("i_d") ** 2 + input_symbol("i_q") ** 2
    nodes = (
        Node("winding_slot", "capacitive", S["C_winding_slot"], "solid"),
        Node("end_winding", "capacitive", S["C_end_winding"], "solid"),
        Node("tooth", "capacitive", S["C_tooth"], "solid"),
        Node("yoke_inner", "capacitive", S["C_yoke_inner"], "solid"),
        Node("yoke_outer", "capacitive", S["C_yoke_outer"], "solid"),
        Node("endcap", "capacitive", S["C_endcap"], "solid"),
        Node("rotor", "capacitive", S["C_rotor"], "solid"),
        Node("shaft_bearing", "capacitive", S["C_shaft_bearing"], "solid"),
        Node("end_space_air", "capacitive", S["C_end_space_air"], "air"),
        Node("water", "boundary", role="T_water"),
        Node("ambient", "boundary", role="T_ambient"),
    )
    links = (
        Link("winding_slot", "end_winding", 1 / S["G_slot_end"], "axial conduction in the copper"),
        Link("winding_slot", "tooth", 1 / S["G_slot_tooth"], "slot liner to the teeth"),
        Link("winding_slot", "yoke_inner", 1 / S["G_slot_yoke"], "slot liner to the slot bottom"),
        Link("tooth", "yoke_inner", 1 / S["G_tooth_yoke"], "tooth roots"),
        Link("yoke_inner", "yoke_outer", 1 / S["G_yoke_radial"], "back iron, radial"),
        Link("yoke_outer", "water", 1 / S["G_jacket"], "water jacket"),
        Link("tooth", "rotor", 1 / S["G_gap"], "air gap at rest"),
        Link("end_winding", "end_space_air", 1 / S["G_end_winding_air"], "end-winding convection at rest"),
        Link("rotor", "end_space_air", 1 / S["G_rotor_air"], "rotor end-face convection at rest"),
        Link("end_space_air", "endcap", 1 / S["G_air_endcap"], "end-cap inner convection at rest"),
        Link("end_winding", "yoke_outer", 1 / S["G_end_winding_frame"], "end-winding potting to the frame"),
        Link("yoke_outer", "endcap", 1 / S["G_frame_endcap"], "frame to end cap"),
        Link("endcap", "ambient", 1 / S["G_endcap_ambient"], "end caps to the room"),
        Link("rotor", "shaft_bearing", 1 / S["G_rotor_shaft"], "rotor hub to shaft"),
        Link("shaft_bearing", "endcap", 1 / S["G_bearing_endcap"], "bearings to the end caps"),
    )
    network = Network(nodes, links, ())
    theta = network.temperature_symbol
    copper_per_ohm = sympy.Rational(3, 2) * current_squared * S["R_0"]
    end_share = S["end_winding_share"]
    network = network.with_heat_sources((
        HeatSource("winding_slot", (1 - end_share) * copper_per_ohm * (1 + S["alpha_cu"] * theta("winding_slot")),
                   "copper"),
        HeatSource("end_winding", end_share * copper_per_ohm * (1 + S["alpha_cu"] * theta("end_winding")), "copper"),
    ))
    # the effects: the catalogue's equations at the file's parameters (the air-gap rise is sized in
    # W/K, G_gap_speed; the catalogue's relative to the gap's conductance at rest)
    if has["ac_copper_loss"]:
        network = speed.ac_copper_loss(network, ROLES, S["k_ac"])
    if has["speed_iron_loss"]:
        network = speed.hysteresis_eddy_iron_loss(network, ROLES, S["P_hyst_ref"], S["P_eddy_ref"], S["k_fe_current"],
                                                  first_share=S["tooth_iron_share"])
    if has["magnet_eddy_loss"]:  # without the fitted exponent, the square law of resistance-limited eddy currents
        exponent = S["pm_speed_exponent"] if has["magnet_loss_exponent"] else 2
        network = speed.magnet_eddy_loss(network, ROLES, S["P_pm_ref"], exponent, S["k_pm_current"])
    if has["bearing_friction"]:
        network = speed.bearing_friction(network, ROLES, S["P_friction_ref"])
    if has["air_gap_convection_speed"]:
        network = speed.convection_rise(Role.AIR_GAP)(network, ROLES, S["G_gap_speed"] / S["G_gap"])
    if has["end_space_convection_speed"]:
        network = speed.convection_rise(Role.END_SPACE_CONVECTION)(network, ROLES, S["k_end_space_speed"])
    return network


def parameters_without(*effects: str) -> ParameterSet:
    """The default parameters without those of ``effects`` (names of :data:`EFFECT_PARAMETERS`), so
    that :func:`build_network` leaves these effects out."""
    unknown = [e for e in effects if e not in EFFECT_PARAMETERS]
    if unknown:
        raise ValueError(f"unknown effect {unknown[0]!r}: one of {', '.join(EFFECT_PARAMETERS)}")
    dropped = {name for effect in effects for name in EFFECT_PARAMETERS[effect]}
    base = default_parameters()
    return ParameterSet([base[n] for n in base if n not in dropped])


def plain_parameters() -> ParameterSet:
    """The parameters of the plain model: those of :data:`EFFECT_PARAMETERS` left out, so that
    :func:`build_network` builds copper loss and constant convection only."""
    return parameters_without(*EFFECT_PARAMETERS)


MACHINE = Machine(NAME, "nine-node LPTN of the water-cooled bench IPMSM (Liu et al. 2024 data set)",
                  INTERFACE, default_parameters, build_network, COLUMN_MAP)
MACHINE_PLAIN = Machine(f"{NAME}_plain", "the bench IPMSM with copper loss and constant convection only",
                        INTERFACE, plain_parameters, build_network, COLUMN_MAP)
