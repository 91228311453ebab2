"""The thesis generator: Genco RF201A, 5 kVA, 415/240 V, 7 A per phase, 1500 rpm, air-cooled by an
internal fan (thesis chapter 3), as the 12-division network of thesis chapter 4. Every value
carries its provenance (thesis, literature or assumed with a reason).
"""

from __future__ import annotations

from sympy import pi

from .. import elements as el
from ..exciter import exciter_current
from ..losses import copper_loss_sources, iron_loss_sources
from ..network import AirStream, HeatSource, Link, Network, Node
from ..parameters import Parameter, ParameterSet
from .interface import GeneratorRole, InputKind, Machine, MachineInterface, ModelInput, Role, Sensor

NAME = "genco_rf201a"

WINDING_NODES = ("stator_winding", "end_winding_in", "end_winding_out")
IRON_NODES = ("stator_iron", "stator_teeth")
PHASE_CURRENTS = ("I_u", "I_v", "I_w")
#: Rated RMS phase current, A (thesis Table 3.3).
RATED_CURRENT_A = 7.0
#: Winding temperature limit θmax, °C (thesis 7.3.1; the hot-spot rating is 140 °C).
WINDING_LIMIT_C = 110.0
#: Sensor noise variances of thesis eq. 6.10, K²: stator winding PT100s, stator iron PT100 (also
#: used for the outlet-air PT100, a channel of the same kind).
WINDING_NOISE_K2, IRON_NOISE_K2 = 0.0082, 0.013

#: Model inputs in input-vector order (thesis Table 3.4: logged by the rig).
INPUTS = (
    ModelInput("I_u", "A", InputKind.CURRENT, "stator phase current U, RMS"),
    ModelInput("I_v", "A", InputKind.CURRENT, "stator phase current V, RMS"),
    ModelInput("I_w", "A", InputKind.CURRENT, "stator phase current W, RMS"),
    ModelInput("I_exc", "A", InputKind.CURRENT, "exciter field current"),
    ModelInput("T_inlet", "degC", InputKind.TEMPERATURE, "cooling-air inlet temperature", 20.0),
    ModelInput("T_ambient", "degC", InputKind.TEMPERATURE, "ambient temperature", 20.0),
)
#: Sensors of the rig (thesis Table 3.4): three winding PT100s averaged, one iron PT100.
SENSORS = (
    Sensor("T_winding", "stator_winding", ("T_winding_u", "T_winding_v", "T_winding_w"), WINDING_NOISE_K2,
           WINDING_LIMIT_C, "stator slot winding PT100s, one per phase"),
    Sensor("T_iron", "stator_iron", ("T_iron",), IRON_NOISE_K2, None, "stator back iron PT100"),
)
OUTLET_SENSOR = Sensor("T_outlet", "end_air_out", ("T_outlet",), IRON_NOISE_K2, None,
                       "cooling-air outlet PT100 (optional column)")
#: Boundary nodes and the input that sets their temperature.
BOUNDARY_INPUTS = {"coolant_inlet": "T_inlet", "ambient": "T_ambient"}


def _exciter_law(mean_phase_current_A, power_factor, rated_current_A):
    return exciter_current(mean_phase_current_A, power_factor, rated_current_A)


#: Where effects, schedulers and discovery find the machine's parts.
ROLES = {
    Role.SLOT_WINDING: "stator_winding",
    Role.END_WINDINGS: ("end_winding_in", "end_winding_out"),
    Role.IRON: IRON_NODES,
    Role.ROTOR: ("rotor",),
    Role.FRAME: ("frame",),
    Role.WINDING_INSULATION: (("stator_winding_radial", "yoke_teeth_interface"),
                              ("stator_winding_radial", "stator_teeth_radial")),
    Role.FRAME_TO_AMBIENT: (("frame", "ambient"),),
    # convection coefficients of surfaces swept by the fan's air (they fall with the coolant flow)
    Role.INTERNAL_CONVECTION: ("h_top_air", "h_end_air", "h_air_gap"),
    Role.COOLANT_FLOW: True,
    Role.LOAD_CURRENTS: PHASE_CURRENTS,
    Role.PHASE_CURRENTS: PHASE_CURRENTS,
    Role.EXCITATION_CURRENT: "I_exc",
    Role.GENERATOR: GeneratorRole(PHASE_CURRENTS, "I_exc", "T_inlet", "T_ambient", _exciter_law, "T_winding"),
}
#: Rating point (thesis Table 3.3): rated current on every phase, the AVR's field current at power
#: factor 0.8 lagging, inlet and ambient at their defaults (20 °C).
RATED_INPUTS = {**{phase: RATED_CURRENT_A for phase in PHASE_CURRENTS},
                "I_exc": exciter_current(RATED_CURRENT_A, rated_current_A=RATED_CURRENT_A)}
INTERFACE = MachineInterface(INPUTS, SENSORS, BOUNDARY_INPUTS, RATED_CURRENT_A, ambient_input="T_ambient",
                             coolant_input="T_inlet", roles=ROLES, rated_inputs=RATED_INPUTS,
                             outlet_sensor=OUTLET_SENSOR,
                             coolant_medium="room_air")  # thesis rig: the fan draws the room's air


def _p(name, value, unit, provenance, source, **bounds):
    return Parameter(name, value, unit, provenance, source, **bounds)


def default_parameters() -> ParameterSet:
    """Parameter set of the thesis generator with the provenance of every value."""
    T42 = "thesis Table 4.2"
    T43 = "thesis Table 4.3"
    return ParameterSet([
        # geometry, thesis Table 4.2 [m]
        _p("r_f2", 0.159, "m", "thesis", f"{T42}: frame inner radius"),
        _p("L_f", 0.347, "m", "thesis", f"{T42}: frame length"),
        _p("r_si1", 0.136, "m", "thesis", f"{T42}: stator back iron outer radius"),
        _p("r_si2", 0.111, "m", "thesis", f"{T42}: stator back iron inner radius"),
        _p("r_st1", 0.111, "m", "thesis", f"{T42}: stator teeth outer radius"),
        _p("r_st2", 0.099, "m", "thesis", f"{T42}: stator teeth inner radius (bore)"),
        _p("L_s", 0.053, "m", "thesis", f"{T42}: stator length"),
        _p("r_sw1", 0.006, "m", "thesis", f"{T42}: slot winding (rod) radius"),
        _p("r_sewt", 0.010, "m", "thesis", f"{T42}: end winding toroid radius"),
        _p("r_sewa", 0.110, "m", "thesis", f"{T42}: end winding toroid centre radius"),
        _p("L_fei", 0.048, "m", "thesis", f"{T42}: end air in length"),
        _p("L_feo", 0.048, "m", "thesis", f"{T42}: end air out length"),
        _p("r_r1", 0.098, "m", "thesis", f"{T42}: rotor outer radius"),
        _p("r_r2", 0.023, "m", "thesis", f"{T42}: rotor inner radius"),
        _p("L_r", 0.053, "m", "thesis", f"{T42}: rotor length"),
        _p("r_sh", 0.023, "m", "thesis", f"{T42}: shaft radius"),
        _p("L_sh", 0.239, "m", "thesis", f"{T42}: shaft length"),
        _p("t_f", 0.001, "m", "thesis", "eq. 4.15: frame wall thickness"),
        _p("t_end", 0.010, "m", "thesis", "eq. 4.15: total thickness of the two end shields"),
        # geometry the thesis does not give
        _p("n_slots", 36, "1", "assumed",
           "36 slots: common for a 4-pole 3-phase machine; 36 rods of r_sw1 fill 51 % of the "
           "teeth annulus, a plausible slot/tooth split", lower=1),
        _p("L_sc", 0.030, "m", "assumed", "slot overhang length: 30 mm, about half the end air length"),
        _p("H_i", 0.0003, "m", "assumed", "slot liner thickness: 0.3 mm, typical for class H machines"),
        _p("L_shf", 0.090, "m", "assumed", "shaft length in the bearings/frame: shaft 239 mm "
           "less rotor 53 mm and the two end airs 96 mm"),
        _p("L_shai", 0.048, "m", "assumed", "shaft length in the end air in: its length, Table 4.2"),
        _p("L_shao", 0.048, "m", "assumed", "shaft length in the end air out: its length, Table 4.2"),
        # materials, thesis Table 4.3 and section 4.2.3
        _p("k_sr", 20.0, "W/(m K)", "thesis", f"{T43}: steel conductivity (radial)"),
        _p("c_steel", 502.0, "J/(kg K)", "thesis", f"{T43}: steel specific heat"),
        _p("rho_steel", 8378.0, "kg/m^3", "thesis", f"{T43}: steel density"),
        _p("k_ca", 400.5, "W/(m K)", "thesis", f"{T43}: copper conductivity (axial)"),
        _p("c_copper", 383.0, "J/(kg K)", "thesis", f"{T43}: copper specific heat"),
        _p("rho_copper", 8933.0, "kg/m^3", "thesis", f"{T43}: copper density"),
        _p("k_sa", 0.1, "W/(m K)", "thesis", "4.2.3: laminated iron axial conductivity, fitted in the thesis"),
        _p("k_cr", 0.13, "W/(m K)", "thesis", "4.2.3: winding radial conductivity, fitted in the thesis"),
        _p("s", 0.97, "1", "thesis", "4.2.3: stacking factor of stator and rotor", upper=1.0),
        _p("s_c", 0.5, "1", "thesis", "4.2.3: copper winding factor", upper=1.0),
        _p("alpha_cu", 0.0039, "1/K", "thesis", "eq. 4.41: temperature coefficient of copper"),
        _p("k_l", 0.2, "W/(m K)", "literature", "slot liner (aramid paper / varnish) 0.1-0.25 W/(m K)"),
        _p("c_air", 1005.0, "J/(kg K)", "literature", "specific heat of air near 40 °C"),
        # cooling: not in the thesis, chosen physically, then set for ~100 °C at rated load
        _p("m_dot_fan", 0.020, "kg/s", "assumed",
           "internal fan: ~17 l/s through the 50 mm outlet duct of thesis 7.3.1 (~8.5 m/s)"),
        _p("air_gap_flow_share", 0.15, "1", "assumed",
           "share of the fan flow through the air gap and slot openings; the 1 mm gap alone is "
           "3 % of the top-air annulus, rotor pumping adds more", upper=1.0),
        _p("h_ambient", 10.0, "W/(m^2 K)", "assumed", "H_f: natural convection outside the frame (5-25)"),
        _p("h_top_air", 15.5, "W/(m^2 K)", "assumed", "H_tar: low-velocity forced convection in the "
           "top-air duct (~1-3 m/s); with h_end_air, set for a 102 °C winding at rated load, 20 °C inlet"),
        _p("h_end_air", 15.5, "W/(m^2 K)", "assumed", "H_tar2 and end-air surfaces: as h_top_air"),
        _p("h_air_gap", 60.0, "W/(m^2 K)", "assumed", "air gap: rotating-gap convection, 1500 rpm"),
        # losses
        _p("R0", 1.2, "ohm", "assumed",
           "phase resistance at 0 °C: 1.67 ohm at 100 °C gives 245 W copper loss at 7 A, ~5 % of 5 kVA"),
        _p("P_iron", 40.0, "W", "assumed", "iron loss at rated voltage: ~10 kg of stator steel (Table 4.2) "
           "at 3-5 W/kg, 50 Hz, 1.5 T; the thesis's no-load test values are not printed",
           lower_inclusive=True),
    ])


def build_network(parameters: ParameterSet) -> Network:
    """Build the 19-node network of the thesis generator from the symbols of ``parameters``."""
    S = parameters.symbols()
    L_s, n = S["L_s"], S["n_slots"]
    k_sr, s, s_c, k_cr = S["k_sr"], S["s"], S["s_c"], S["k_cr"]
    A_sw = pi * S["r_sw1"] ** 2
    # phi_se/phi_sp: steel share of the teeth annulus left by the n_slots winding rods
    tooth_ratio = 1 - n * A_sw / (pi * (S["r_st1"] ** 2 - S["r_st2"] ** 2))
    steel = (S["rho_steel"], S["c_steel"])
    copper = (S["rho_copper"], S["c_copper"])
    h_ta, h_end, h_ag = S["h_top_air"], S["h_end_air"], S["h_air_gap"]

    def conv(area, h):
        return el.surface_convection(area, h)

    end_winding_C = el.end_winding_capacitance(S["L_sc"], A_sw, n, S["r_sewa"], S["r_sewt"], s_c, *copper)
    nodes = (
        Node("frame", "capacitive", el.frame_capacitance(S["r_f2"], S["L_f"], S["t_f"], S["t_end"], *steel), "solid"),
        Node("stator_iron", "capacitive",
             s * el.cylinder_capacitance(L_s, S["r_si1"], S["r_si2"], *steel), "solid"),
        Node("stator_teeth", "capacitive",
             el.teeth_capacitance(L_s, S["r_st1"], S["r_st2"], A_sw, n, s, *steel), "solid"),
        Node("stator_winding", "capacitive", el.winding_capacitance(L_s, A_sw, n, s_c, *copper), "solid"),
        Node("end_winding_in", "capacitive", end_winding_C, "solid"),
        Node("end_winding_out", "capacitive", end_winding_C, "solid"),
        Node("rotor", "capacitive", el.rotor_capacitance(S["L_r"], S["r_r1"], S["r_r2"], s, *steel), "solid"),
        Node("shaft", "capacitive", el.cylinder_capacitance(S["L_sh"], S["r_sh"], 0, *steel), "solid"),
        Node("top_air", "massless", role="air"),
        Node("end_air_in", "massless", role="air"),
        Node("air_gap", "massless", role="air"),
        Node("end_air_out", "massless", role="air"),
        Node("frame_inner_surface", "massless", role="intermediate"),
        Node("stator_iron_radial", "massless", role="intermediate"),
        Node("stator_iron_ends", "massless", role="intermediate"),
        Node("yoke_teeth_interface", "massless", role="intermediate"),
        Node("stator_teeth_radial", "massless", role="intermediate"),
        Node("stator_teeth_ends", "massless", role="intermediate"),
        Node("stator_winding_radial", "massless", role="intermediate"),
        Node("coolant_inlet", "boundary", role="T_inlet"),
        Node("ambient", "boundary", role="T_ambient"),
    )
    si = (L_s, S["r_si1"], S["r_si2"])
    st = (L_s, S["r_st1"], S["r_st2"])
    winding = (L_s, S["r_sw1"], n, S["H_i"], S["k_l"], k_cr, s_c)
    si_end_area = pi * (S["r_si1"] ** 2 - S["r_si2"] ** 2)
    st_end_area = tooth_ratio * pi * (S["r_st1"] ** 2 - S["r_st2"] ** 2)
    bore_area = 2 * pi * S["r_st2"] * L_s
    slot_to_end_winding = 2 * el.winding_axial(L_s, A_sw, n, S["k_ca"]) + el.end_winding_axial(S["L_sc"], A_sw, n, S["k_ca"])
    overhang = (el.end_winding_overhang_radial(S["L_sc"], S["r_sw1"], S["r_sewt"], n, k_cr, s_c)
                + conv(n * 2 * pi * S["r_sw1"] * S["L_sc"], h_end))
    toroid = (el.end_winding_toroid_radial(S["r_sewa"], k_cr, s_c)
              + conv(4 * pi**2 * S["r_sewa"] * S["r_sewt"], h_end))
    links = [
        # frame (eqs 4.10-4.14)
        Link("frame", "ambient", el.frame_to_ambient(S["r_f2"], L_s, S["L_fei"], S["L_feo"], S["h_ambient"]), "eq. 4.10"),
        Link("frame", "frame_inner_surface", el.frame_wall(S["r_f2"], L_s, S["t_f"], k_sr), "eq. 4.11 (corrected)"),
        Link("frame_inner_surface", "top_air", conv(2 * pi * S["r_f2"] * L_s, h_ta), "eq. 4.12"),
        Link("frame_inner_surface", "end_air_in", conv(2 * pi * S["r_f2"] * S["L_fei"], h_end), "eq. 4.13"),
        Link("frame_inner_surface", "end_air_out", conv(2 * pi * S["r_f2"] * S["L_feo"], h_end), "eq. 4.14"),
        # stator back iron (eqs 4.3-4.6)
        Link("stator_iron", "stator_iron_radial", el.cylinder_radial_mean(*si, k_sr, s), "eq. 4.6"),
        Link("stator_iron_radial", "top_air",
             el.cylinder_radial_outer(*si, k_sr, s) + conv(2 * pi * S["r_si1"] * L_s, h_ta), "eq. 4.4 + eq. 4.39"),
        Link("stator_iron_radial", "yoke_teeth_interface", el.cylinder_radial_inner(*si, k_sr, s), "eq. 4.5"),
        Link("stator_iron", "stator_iron_ends", el.cylinder_axial(*si, S["k_sa"]), "eq. 4.3"),
        Link("stator_iron_ends", "end_air_in", conv(si_end_area, h_end), "eq. 4.39"),
        Link("stator_iron_ends", "end_air_out", conv(si_end_area, h_end), "eq. 4.39"),
        # stator teeth (eqs 4.16-4.20)
        Link("stator_teeth", "stator_teeth_radial", el.teeth_radial_mean(*st, k_sr, s, tooth_ratio), "eq. 4.19"),
        Link("stator_teeth_radial", "yoke_teeth_interface", el.teeth_radial_outer(*st, k_sr, s, tooth_ratio), "eq. 4.17"),
        Link("stator_teeth_radial", "air_gap",
             el.teeth_radial_inner(*st, k_sr, s, tooth_ratio) + conv(tooth_ratio * bore_area, h_ag), "eq. 4.18 + eq. 4.39"),
        Link("stator_teeth", "stator_teeth_ends", el.teeth_axial(*st, S["k_sa"], tooth_ratio), "eq. 4.16"),
        Link("stator_teeth_ends", "end_air_in", conv(st_end_area, h_end), "eq. 4.39"),
        Link("stator_teeth_ends", "end_air_out", conv(st_end_area, h_end), "eq. 4.39"),
        # slot winding (eqs 4.20, 4.22-4.25)
        Link("stator_winding", "stator_winding_radial", el.winding_radial_mean(L_s, n, k_cr, s_c), "eq. 4.25 (corrected)"),
        Link("stator_winding_radial", "yoke_teeth_interface", el.winding_to_back_iron(*winding), "eq. 4.23 (corrected)"),
        Link("stator_winding_radial", "stator_teeth_radial",
             el.winding_to_teeth(*winding) + el.teeth_to_slot(*st, k_sr, s, tooth_ratio, n), "eq. 4.24 (corrected) + eq. 4.20"),
        Link("stator_winding_radial", "air_gap", conv((1 - tooth_ratio) * bore_area, h_ag), "eq. 4.39 (slot openings)"),
        Link("stator_winding", "end_winding_in", slot_to_end_winding, "2 x eq. 4.22 + eq. 4.27"),
        Link("stator_winding", "end_winding_out", slot_to_end_winding, "2 x eq. 4.22 + eq. 4.27"),
        # end windings (eqs 4.28-4.29): overhang and toroid in parallel to the end air
        Link("end_winding_in", "end_air_in", overhang, "eq. 4.28 + eq. 4.39 (overhang)"),
        Link("end_winding_in", "end_air_in", toroid, "eq. 4.29 + eq. 4.39 (toroid)"),
        Link("end_winding_out", "end_air_out", overhang, "eq. 4.28 + eq. 4.39 (overhang)"),
        Link("end_winding_out", "end_air_out", toroid, "eq. 4.29 + eq. 4.39 (toroid)"),
        # rotor (eqs 4.31-4.32) and shaft (eqs 4.34-4.37)
        Link("rotor", "air_gap", el.rotor_radial_outer(S["L_r"], S["r_r1"], S["r_r2"], k_sr)
             + conv(2 * pi * S["r_r1"] * S["L_r"], h_ag), "eq. 4.31 + eq. 4.39"),
        Link("rotor", "shaft", el.rotor_radial_inner(S["L_r"], S["r_r1"], S["r_r2"], k_sr)
             + el.shaft_radial(S["L_r"], k_sr), "eq. 4.32 + eq. 4.34"),
        Link("shaft", "frame", el.shaft_radial(S["L_shf"], k_sr), "eq. 4.35"),
        Link("shaft", "end_air_in", el.shaft_radial(S["L_shai"], k_sr)
             + conv(2 * pi * S["r_sh"] * S["L_shai"], h_end), "eq. 4.36 + eq. 4.39"),
        Link("shaft", "end_air_out", el.shaft_radial(S["L_shao"], k_sr)
             + conv(2 * pi * S["r_sh"] * S["L_shao"], h_end), "eq. 4.37 + eq. 4.39"),
    ]
    m_dot, share, c_air = S["m_dot_fan"], S["air_gap_flow_share"], S["c_air"]
    streams = (
        AirStream("coolant_inlet", "end_air_in", el.advection(c_air, m_dot), "fan inlet (eq. 4.38)"),
        AirStream("end_air_in", "air_gap", el.advection(c_air, share * m_dot), "eq. 4.38"),
        AirStream("end_air_in", "top_air", el.advection(c_air, (1 - share) * m_dot), "eq. 4.38"),
        AirStream("air_gap", "end_air_out", el.advection(c_air, share * m_dot), "eq. 4.38"),
        AirStream("top_air", "end_air_out", el.advection(c_air, (1 - share) * m_dot), "eq. 4.38"),
    )
    network = Network(nodes, tuple(links), streams)
    sources: list[HeatSource] = [
        *copper_loss_sources(network, WINDING_NODES, PHASE_CURRENTS, S["R0"], S["alpha_cu"]),
        *iron_loss_sources(network, IRON_NODES, S["P_iron"]),
    ]
    return network.with_heat_sources(sources)


MACHINE = Machine(NAME, "Genco RF201A 5 kVA air-cooled aircraft-type generator (the thesis machine)",
                  INTERFACE, default_parameters, build_network)
