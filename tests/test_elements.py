"""Every element formula of thesis chapter 4 against a value worked out by hand.

The expected numbers were computed from the printed equations (with the corrections documented in
genthermal/elements.py) for the Table 4.2/4.3 dimensions and materials, rounded to 5 figures.
Dimensions: stator back iron r1 = 136 mm, r2 = 111 mm, L = 53 mm; teeth 111/99 mm with a tooth
ratio of 0.5; winding rod r = 6 mm, 36 slots; steel k = 20, k_a = 0.1 W/(m K), s = 0.97.
"""

import math

import pytest
import sympy

from genthermal import elements as el

STEEL = (8378.0, 502.0)
COPPER = (8933.0, 383.0)
A_SW = math.pi * 0.006**2
IRON = (0.053, 0.136, 0.111)
TEETH = (0.053, 0.111, 0.099)
WINDING = (0.053, 0.006, 36, 0.0003, 0.2, 0.13, 0.5)

CASES = [
    ("eq 4.3 cylinder axial", el.cylinder_axial(*IRON, 0.1), 2.2767),
    ("eq 4.4 cylinder radial outer", el.cylinder_radial_outer(*IRON, 20, 0.97), 0.014659),
    ("eq 4.5 cylinder radial inner", el.cylinder_radial_inner(*IRON, 20, 0.97), 0.016782),
    ("eq 4.6 cylinder radial mean", el.cylinder_radial_mean(*IRON, 20, 0.97), 0.0052116),
    ("eq 4.7 cylinder capacitance", el.cylinder_capacitance(*IRON, *STEEL), 4324.2),
    ("eq 4.8 rod axial", el.rod_axial(0.239, 0.023, 0.1), 119.84),
    ("eq 4.9 rod radial", el.rod_radial(0.239, 20, 0.97), 0.017163),
    ("eq 4.10 frame to ambient", el.frame_to_ambient(0.159, 0.053, 0.048, 0.048, 10), 0.67179),
    ("eq 4.11 frame wall (corrected)", el.frame_wall(0.159, 0.053, 0.001, 20), 4.7216e-4),
    ("eq 4.15 frame capacitance", el.frame_capacitance(0.159, 0.347, 0.001, 0.01, *STEEL), 4802.9),
    ("eq 4.16 teeth axial", el.teeth_axial(*TEETH, 0.1, 0.5), 11.158),
    ("eq 4.17 teeth radial outer", el.teeth_radial_outer(*TEETH, 20, 0.97, 0.5), 0.017035),
    ("eq 4.18 teeth radial inner", el.teeth_radial_inner(*TEETH, 20, 0.97, 0.5), 0.018384),
    ("eq 4.19 teeth radial mean", el.teeth_radial_mean(*TEETH, 20, 0.97, 0.5), 0.0058929),
    ("eq 4.20 teeth to slot", el.teeth_to_slot(*TEETH, 20, 0.97, 0.5, 36), 0.020629),
    ("eq 4.21 teeth capacitance", el.teeth_capacitance(*TEETH, A_SW, 36, 0.97, *STEEL), 831.42),
    ("eq 4.22 winding axial", el.winding_axial(0.053, A_SW, 36, 400.5), 0.0027086),
    ("eq 4.23 winding to back iron", el.winding_to_back_iron(*WINDING), 0.40424),
    ("eq 4.24 winding to teeth", el.winding_to_teeth(*WINDING), 0.80848),
    ("eq 4.25 winding radial mean", el.winding_radial_mean(0.053, 36, 0.13, 0.5), 0.32083),
    ("eq 4.26 winding capacitance", el.winding_capacitance(0.053, A_SW, 36, 0.5, *COPPER), 369.14),
    ("eq 4.27 end winding axial", el.end_winding_axial(0.03, A_SW, 36, 400.5), 0.0091989),
    ("eq 4.28 overhang radial", el.end_winding_overhang_radial(0.03, 0.006, 0.01, 36, 0.13, 0.5), 0.098401),
    ("eq 4.29 toroid radial", el.end_winding_toroid_radial(0.11, 0.13, 0.5), 0.11071),
    ("eq 4.30 end winding capacitance",
     el.end_winding_capacitance(0.03, A_SW, 36, 0.11, 0.01, 0.5, *COPPER), 580.39),
    ("eq 4.31 rotor radial outer", el.rotor_radial_outer(0.053, 0.098, 0.023, 20), 0.072419),
    ("eq 4.32 rotor radial inner", el.rotor_radial_inner(0.053, 0.098, 0.023, 20), 0.14521),
    ("eq 4.33 rotor capacitance", el.rotor_capacitance(0.053, 0.098, 0.023, 0.97, *STEEL), 6164.4),
    ("eqs 4.34-4.37 shaft", el.shaft_radial(0.09, 20), 0.022105),
    ("eq 4.38 advection", el.advection(1005, 0.02), 0.049751),
    ("eq 4.39 convection", el.surface_convection(0.05, 40), 0.5),
]


@pytest.mark.parametrize("name, expression, expected", CASES, ids=[c[0] for c in CASES])
def test_element_matches_hand_value(name, expression, expected):
    assert float(expression) == pytest.approx(expected, rel=1e-4)


def test_elements_are_symbolic_and_print_as_latex():
    L, r1, r2, k = sympy.symbols("L r_1 r_2 k_a", positive=True)
    expression = el.cylinder_axial(L, r1, r2, k)
    assert expression.free_symbols == {L, r1, r2, k}
    latex = sympy.latex(expression)
    assert "\\pi" in latex and "k_{a}" in latex


def test_rod_is_cylinder_limit_of_radial_network():
    """Eq. 4.9 is R_r1 of the cylinder as the inner radius goes to zero (thesis 4.2.1)."""
    L, r1, r2, k, s = sympy.symbols("L r_1 r_2 k s", positive=True)
    limit = sympy.limit(el.cylinder_radial_outer(L, r1, r2, k, s), r2, 0)
    assert sympy.simplify(limit - el.rod_radial(L, k, s)) == 0


def test_resistances_have_units_of_kelvin_per_watt():
    """Dimensional check of the corrected formulas: scale every length by 2 and the conduction
    resistance of a 3-D body scales as 1/length (the printed eqs 4.11 and 4.23-4.25 did not)."""
    lengths = (0.053, 0.006, 0.0003)
    base = float(el.winding_to_back_iron(*lengths[:2], 36, lengths[2], 0.2, 0.13, 0.5))
    doubled = float(el.winding_to_back_iron(*(2 * v for v in lengths[:2]), 36, 2 * lengths[2], 0.2, 0.13, 0.5))
    assert doubled == pytest.approx(base / 2, rel=1e-12)
    base = float(el.frame_wall(0.159, 0.053, 0.001, 20))
    assert float(el.frame_wall(0.318, 0.106, 0.002, 20)) == pytest.approx(base / 2, rel=1e-12)
