r"""A liquid-cooled permanent-magnet synchronous motor as a genthermal machine, defined outside the package.

A low-order lumped-parameter thermal network (LPTN) of an automotive traction PMSM with the
structure of Wallscheid & Böcker's four-node LPTN [1]_: stator yoke, stator tooth, stator winding
and permanent magnet (the rotor lumped with its magnets), a water-glycol jacket around the yoke
(``T_coolant``) and the air around the housing (``T_ambient``) as boundaries::

    coolant ── yoke ── tooth ── winding          magnet ── ambient
                 │  └─────────────┘  │            │
                 └── ambient         └── tooth ───┘ (air gap)

Inputs are those of the Paderborn test-bench records of that work [2]_: motor speed (rpm), the
d/q stator currents (A, amplitude-invariant, i_d < 0 in field weakening), coolant and ambient
temperature; sensors on yoke, tooth and winding; the magnet is not measured (on the bench it is
read by telemetry, in a vehicle not at all), which is why an observer must estimate it.

Losses:

* copper: :math:`P_{cu} = \tfrac32 R_s(\theta_w)\,(i_d^2 + i_q^2)`,
  :math:`R_s = R_{s,0}(1 + \alpha_{cu}\theta_w)`, in the winding;
* iron: speed-dependent (Bertotti-style hysteresis + eddy split at fixed flux density),
  :math:`P_{fe} = P_{fe,ref}\,(a_h\,n/n_{ref} + (1 - a_h)(n/n_{ref})^2)`, split between yoke and
  tooth by mass;
* magnet eddy-current loss from slot and PWM harmonics, :math:`P_{pm} = P_{pm,ref}(n/n_{ref})^2`.

The identified conductances and capacities of [1]_ are not reproduced here (they were fitted to a
specific prototype and are not available to this project), so every value below is ``assumed``
with its physical reason, chosen for a ~50 kW water-jacketed traction motor, or ``literature``
for material constants. With them, at the rating point (6000 rpm, 150 A, coolant 65 °C) the
winding settles at 105 °C, the magnet at 104 °C, the yoke at 84 °C; the stator follows load within
seconds to minutes (time constants 7 s to 3 min), the rotor over 20 minutes, as in the records of
[2]_.

References
----------
.. [1] O. Wallscheid and J. Böcker, "Global Identification of a Low-Order Lumped-Parameter
   Thermal Network for Permanent Magnet Synchronous Motors," IEEE Trans. Energy Conversion,
   vol. 31, no. 1, pp. 354-365, 2016.
.. [2] W. Kirchgässner, O. Wallscheid, J. Böcker, "Electric Motor Temperature" data set
   (Paderborn University test bench, 2019): columns motor_speed, i_d, i_q, coolant, ambient,
   stator_yoke, stator_tooth, stator_winding, pm.
"""

from __future__ import annotations

import sympy

from genthermal.losses import copper_loss_sources, input_symbol, mass_shares
from genthermal.machines import InputKind, Machine, MachineInterface, ModelInput, Role, Sensor
from genthermal.network import HeatSource, Link, Network, Node
from genthermal.parameters import Parameter, ParameterSet

NAME = "pmsm_lptn4"
CURRENTS = ("i_d", "i_q")
IRON_NODES = ("stator_yoke", "stator_tooth")
#: Rated current amplitude of the d/q currents, A (assumed: 50 kW at ~250 V phase peak).
RATED_CURRENT_A = 150.0
#: Noise variance of the stator thermocouples, K² (assumed: type-K thermocouples read by a
#: 16-bit logger, sigma 0.1 K).
THERMOCOUPLE_NOISE_K2 = 0.01
#: Winding limit, °C (assumed: class-H insulation rated 180 °C, minus a 40 K hot-spot allowance).
WINDING_LIMIT_C = 140.0

INPUTS = (
    ModelInput("motor_speed", "rpm", InputKind.SPEED, "rotor speed"),
    ModelInput("i_d", "A", InputKind.CURRENT, "d-axis stator current (amplitude-invariant)", signed=True),
    ModelInput("i_q", "A", InputKind.CURRENT, "q-axis stator current (amplitude-invariant)", signed=True),
    ModelInput("T_coolant", "degC", InputKind.TEMPERATURE, "water-glycol inlet of the housing jacket", 65.0),
    ModelInput("T_ambient", "degC", InputKind.TEMPERATURE, "air around the housing", 25.0),
)
SENSORS = (
    Sensor("T_stator_yoke", "stator_yoke", ("stator_yoke",), THERMOCOUPLE_NOISE_K2, None, "thermocouple in the yoke"),
    Sensor("T_stator_tooth", "stator_tooth", ("stator_tooth",), THERMOCOUPLE_NOISE_K2, None,
           "thermocouple in a tooth"),
    Sensor("T_stator_winding", "stator_winding", ("stator_winding",), THERMOCOUPLE_NOISE_K2, WINDING_LIMIT_C,
           "thermocouple in the end winding"),
)
ROLES = {
    Role.SLOT_WINDING: "stator_winding",
    Role.IRON: IRON_NODES,
    Role.ROTOR: ("permanent_magnet",),  # the rotor is lumped with its magnets
    Role.WINDING_INSULATION: (("stator_winding", "stator_tooth"), ("stator_winding", "stator_yoke")),
    Role.FRAME_TO_AMBIENT: (("stator_yoke", "ambient"),),
    Role.LOAD_CURRENTS: CURRENTS,
}
INTERFACE = MachineInterface(
    INPUTS, SENSORS, {"coolant": "T_coolant", "ambient": "T_ambient"}, RATED_CURRENT_A,
    ambient_input="T_ambient", coolant_input="T_coolant", coolant_medium="water", roles=ROLES,
    rated_inputs={"motor_speed": 6000.0, "i_d": -90.0, "i_q": 120.0})


def default_parameters() -> ParameterSet:
    """Parameter set of the example motor with the provenance of every value."""
    return ParameterSet([
        # heat capacities, J/K: mass x specific heat (steel 460, copper 385 J/(kg K), literature)
        Parameter("C_yoke", 3700.0, "J/K", "assumed", "8 kg of laminated steel x 460 J/(kg K)"),
        Parameter("C_tooth", 1850.0, "J/K", "assumed", "4 kg of laminated steel x 460 J/(kg K)"),
        Parameter("C_winding", 2300.0, "J/K", "assumed", "5 kg copper x 385 J/(kg K) + 0.3 kg resin/insulation"),
        Parameter("C_rotor", 5200.0, "J/K", "assumed",
                  "rotor lamination, shaft and 1.5 kg NdFeB lumped with the magnet"),
        # conductances, W/K
        Parameter("G_yoke_coolant", 65.0, "W/K", "assumed", "water jacket: h ~ 1500 W/(m^2 K) on ~0.06 m^2 of "
                  "bore in series with the housing-lamination contact"),
        Parameter("G_yoke_tooth", 160.0, "W/K", "assumed",
                  "radial conduction through the tooth roots (steel 25 W/(m K))"),
        Parameter("G_winding_tooth", 28.0, "W/K", "assumed",
                  "slot liner and impregnation between conductors and teeth"),
        Parameter("G_winding_yoke", 6.0, "W/K", "assumed", "slot bottoms and end winding potting towards the housing"),
        Parameter("G_air_gap", 3.5, "W/K", "assumed", "1 mm air gap, rotating-gap convection at a few thousand rpm"),
        Parameter("G_rotor_ambient", 1.2, "W/K", "assumed",
                  "shaft, bearings and end-space air towards the housing ends"),
        Parameter("G_housing_ambient", 1.5, "W/K", "assumed", "natural convection from ~0.2 m^2 of housing"),
        # losses
        Parameter("R_s0", 0.0125, "ohm", "assumed",
                  "phase resistance at 0 °C: 0.0174 ohm at 100 °C, 590 W copper loss at 150 A (~1.2 % of 50 kW)"),
        Parameter("alpha_cu", 0.00393, "1/K", "literature",
                  "temperature coefficient of copper resistivity near 20 °C"),
        Parameter("P_fe_ref", 650.0, "W", "assumed",
                  "iron loss at 6000 rpm (4 pole pairs: 400 Hz) in ~12 kg of stator steel, ~1.3 % of 50 kW",
                  lower_inclusive=True),
        Parameter("n_ref", 6000.0, "rpm", "assumed", "reference speed of the loss maps: the rating point"),
        Parameter("a_hyst", 0.55, "1", "assumed", "hysteresis share of the iron loss at n_ref (Bertotti split "
                  "for 0.3 mm M330 lamination near 400 Hz)", lower_inclusive=True, upper=1.0),
        Parameter("P_pm_ref", 150.0, "W", "assumed", "magnet eddy-current loss at n_ref from slot and PWM "
                  "harmonics (segmented magnets)", lower_inclusive=True),
    ])


def build_network(parameters: ParameterSet) -> Network:
    """The four-node LPTN from the symbols of ``parameters``."""
    S = parameters.symbols()
    nodes = (
        Node("stator_yoke", "capacitive", S["C_yoke"], "solid"),
        Node("stator_tooth", "capacitive", S["C_tooth"], "solid"),
        Node("stator_winding", "capacitive", S["C_winding"], "solid"),
        Node("permanent_magnet", "capacitive", S["C_rotor"], "solid"),
        Node("coolant", "boundary", role="T_coolant"),
        Node("ambient", "boundary", role="T_ambient"),
    )
    links = (
        Link("stator_yoke", "coolant", 1 / S["G_yoke_coolant"], "water jacket"),
        Link("stator_yoke", "stator_tooth", 1 / S["G_yoke_tooth"], "tooth roots"),
        Link("stator_winding", "stator_tooth", 1 / S["G_winding_tooth"], "slot liner"),
        Link("stator_winding", "stator_yoke", 1 / S["G_winding_yoke"], "slot bottom, end winding potting"),
        Link("stator_tooth", "permanent_magnet", 1 / S["G_air_gap"], "air gap"),
        Link("permanent_magnet", "ambient", 1 / S["G_rotor_ambient"], "shaft and end-space air"),
        Link("stator_yoke", "ambient", 1 / S["G_housing_ambient"], "housing surface"),
    )
    network = Network(nodes, links, ())
    speed_ratio = input_symbol("motor_speed") / S["n_ref"]
    iron = S["P_fe_ref"] * (S["a_hyst"] * speed_ratio + (1 - S["a_hyst"]) * speed_ratio**2)
    shares = mass_shares(network, IRON_NODES)
    sources = [
        *copper_loss_sources(network, ("stator_winding",), CURRENTS, sympy.Rational(3, 2) * S["R_s0"], S["alpha_cu"]),
        *(HeatSource(node, shares[node] * iron, "iron") for node in IRON_NODES),
        HeatSource("permanent_magnet", S["P_pm_ref"] * speed_ratio**2, "magnet"),
    ]
    return network.with_heat_sources(sources)


MACHINE = Machine(NAME, "four-node LPTN of a liquid-cooled automotive PMSM (example plug-in)", INTERFACE,
                  default_parameters, build_network)
