"""Thermal resistance and capacitance formulas of thesis chapter 4, as sympy expressions.

Each function takes sympy symbols or expressions for geometry and materials and returns a
resistance in K/W or a capacitance in J/K, unevaluated. Where the printed equations are ambiguous
or dimensionally wrong (eqs. 4.6, 4.11, 4.15, 4.18, 4.19, 4.23-4.25, 4.28, the axial resistances)
the decisions taken are listed in ``docs/guide/methods.md``.
"""

from __future__ import annotations

import sympy
from sympy import log, pi

Expr = sympy.Expr


# --- Cylinder (eqs. 4.3-4.7) and rod (eqs. 4.8-4.9) -------------------------------------------

def cylinder_axial(L: Expr, r_outer: Expr, r_inner: Expr, k_axial: Expr) -> Expr:
    r"""Axial resistance from the mean node to both end faces, eq. 4.3 [K/W].

    :math:`R_a = L / (12\pi k_a (r_1^2 - r_2^2))`
    """
    return L / (12 * pi * k_axial * (r_outer**2 - r_inner**2))


def _radial_prefactor(L: Expr, k_radial: Expr, stacking: Expr) -> Expr:
    return 1 / (4 * pi * k_radial * L * stacking)


def cylinder_radial_outer(L, r_outer, r_inner, k_radial, stacking) -> Expr:
    r"""Radial resistance, intermediate node to outer surface, eq. 4.4 [K/W].

    :math:`R_{r1} = \frac{1}{4\pi k_r L s}\left(1 - \frac{2 r_2^2 \ln(r_1/r_2)}{r_1^2-r_2^2}\right)`
    """
    ratio = log(r_outer / r_inner) / (r_outer**2 - r_inner**2)
    return _radial_prefactor(L, k_radial, stacking) * (1 - 2 * r_inner**2 * ratio)


def cylinder_radial_inner(L, r_outer, r_inner, k_radial, stacking) -> Expr:
    r"""Radial resistance, intermediate node to inner surface, eq. 4.5 [K/W].

    :math:`R_{r2} = \frac{1}{4\pi k_r L s}\left(\frac{2 r_1^2 \ln(r_1/r_2)}{r_1^2-r_2^2} - 1\right)`
    """
    ratio = log(r_outer / r_inner) / (r_outer**2 - r_inner**2)
    return _radial_prefactor(L, k_radial, stacking) * (2 * r_outer**2 * ratio - 1)


def cylinder_radial_mean(L, r_outer, r_inner, k_radial, stacking) -> Expr:
    r"""Radial resistance, mean node to intermediate node, eq. 4.6 (thesis sign) [K/W].

    :math:`R_{r3} = \frac{1}{8\pi k_r L s (r_1^2-r_2^2)}\left(r_1^2 + r_2^2
    - \frac{4 r_1^2 r_2^2 \ln(r_1/r_2)}{r_1^2-r_2^2}\right)`
    """
    area = r_outer**2 - r_inner**2
    bracket = r_outer**2 + r_inner**2 - 4 * r_outer**2 * r_inner**2 * log(r_outer / r_inner) / area
    return bracket / (8 * pi * k_radial * L * stacking * area)


def cylinder_capacitance(L, r_outer, r_inner, density, specific_heat) -> Expr:
    r"""Heat capacity of a hollow cylinder, eq. 4.7 [J/K]: :math:`C = \rho c_p \pi (r_1^2-r_2^2) L`."""
    return density * specific_heat * pi * (r_outer**2 - r_inner**2) * L


def rod_axial(L, r, k_axial) -> Expr:
    r"""Axial resistance of a solid rod, eq. 4.8 [K/W]: :math:`R_a = L/(12\pi k_a r_1^2)`."""
    return L / (12 * pi * k_axial * r**2)


def rod_radial(L, k_radial, stacking) -> Expr:
    r"""Radial resistance of a solid rod, eq. 4.9 [K/W]: :math:`R_r = 1/(4\pi k_r L s)`."""
    return _radial_prefactor(L, k_radial, stacking)


# --- Frame (eqs. 4.10-4.15) ------------------------------------------------------------------

def frame_to_ambient(r_f2, L_s, L_fei, L_feo, h_ambient) -> Expr:
    r"""Frame to ambient convection, eq. 4.10 [K/W]:
    :math:`R_{famb} = 1/(2\pi r_{f2}(L_s+L_{fei}+L_{feo}) H_f)`."""
    return 1 / (2 * pi * r_f2 * (L_s + L_fei + L_feo) * h_ambient)


def frame_wall(r_f2, L_s, t_f, k_steel) -> Expr:
    r"""Frame mean to inner surface, eq. 4.11 corrected [K/W]:
    :math:`R_{f1} = (t_f/2)/(2\pi K_{sr} r_{f2} L_s)` (see module notes)."""
    return (t_f / 2) / (2 * pi * k_steel * r_f2 * L_s)


def surface_convection(area, h) -> Expr:
    r"""Convection from a surface of ``area`` [m²] with coefficient ``h`` [W/(m² K)],
    eq. 4.39 [K/W]: :math:`R = 1/(A_c h)`. Eqs. 4.12-4.14 are this with the frame areas."""
    return 1 / (area * h)


def frame_capacitance(r_f, L_f, t_f, t_end, density, specific_heat) -> Expr:
    r"""Frame heat capacity, eq. 4.15 [J/K]:
    :math:`C_f = \rho c (\pi L_f((r_f+t_f)^2 - r_f^2) + t_{end}\pi r_f^2)`."""
    return density * specific_heat * (pi * L_f * ((r_f + t_f)**2 - r_f**2) + t_end * pi * r_f**2)


# --- Stator teeth (eqs. 4.16-4.21) -----------------------------------------------------------

def teeth_axial(L_s, r_st1, r_st2, k_sa, tooth_ratio) -> Expr:
    r"""Teeth axial resistance, eq. 4.16 [K/W]; ``tooth_ratio`` is :math:`\phi_{se}/\phi_{sp}`."""
    return cylinder_axial(L_s, r_st1, r_st2, k_sa) / tooth_ratio


def teeth_radial_outer(L_s, r_st1, r_st2, k_sr, stacking, tooth_ratio) -> Expr:
    """Teeth radial resistance to the outer (yoke) surface, eq. 4.17 [K/W]."""
    return cylinder_radial_outer(L_s, r_st1, r_st2, k_sr, stacking) / tooth_ratio


def teeth_radial_inner(L_s, r_st1, r_st2, k_sr, stacking, tooth_ratio) -> Expr:
    """Teeth radial resistance to the inner (bore) surface, eq. 4.18 with r_1 read as r_st1 [K/W]."""
    return cylinder_radial_inner(L_s, r_st1, r_st2, k_sr, stacking) / tooth_ratio


def teeth_radial_mean(L_s, r_st1, r_st2, k_sr, stacking, tooth_ratio) -> Expr:
    """Teeth radial resistance, mean to intermediate node, eq. 4.19 (thesis sign) [K/W]."""
    return cylinder_radial_mean(L_s, r_st1, r_st2, k_sr, stacking) / tooth_ratio


def teeth_to_slot(L_s, r_st1, r_st2, k_sr, stacking, tooth_ratio, n_slots) -> Expr:
    r"""Teeth to the inside of the slots, eq. 4.20 [K/W]:
    :math:`R_{strw} = \frac{\pi(r_{st1}^2-r_{st2}^2)\phi_{se}}{K_{sr}L_s(r_{st1}-r_{st2})^2 n_s^2\phi_{sp} s}`."""
    return (pi * (r_st1**2 - r_st2**2) * tooth_ratio
            / (k_sr * L_s * (r_st1 - r_st2)**2 * n_slots**2 * stacking))


def teeth_capacitance(L_s, r_st1, r_st2, A_sw, n_slots, stacking, density, specific_heat) -> Expr:
    r"""Teeth heat capacity, eq. 4.21 [J/K]:
    :math:`C_{st} = \rho c s(\pi L_s(r_{st1}^2-r_{st2}^2) - A_{sw}L_s n_s)`."""
    return density * specific_heat * stacking * (pi * L_s * (r_st1**2 - r_st2**2) - A_sw * L_s * n_slots)


# --- Slot winding (eqs. 4.22-4.26) -----------------------------------------------------------

def winding_axial(L_s, A_sw, n_slots, k_ca) -> Expr:
    r"""Slot winding axial resistance to both ends, eq. 4.22 [K/W]: :math:`L_s/(12 k_{ca} A_{sw} n_s)`."""
    return L_s / (12 * k_ca * A_sw * n_slots)


def winding_to_back_iron(L_s, r_sw1, n_slots, H_i, k_l, k_cr, s_c) -> Expr:
    r"""Slot winding to the back iron (slot bottom), eq. 4.23 corrected [K/W]:
    :math:`\frac{4H_i s_c}{\pi k_l L_s r_{sw1} n_s} + \frac{1}{4\pi k_{cr} L_s n_s}`."""
    return 4 * H_i * s_c / (pi * k_l * L_s * r_sw1 * n_slots) + 1 / (4 * pi * k_cr * L_s * n_slots)


def winding_to_teeth(L_s, r_sw1, n_slots, H_i, k_l, k_cr, s_c) -> Expr:
    r"""Slot winding to the teeth (slot sides), eq. 4.24 corrected [K/W]:
    :math:`\frac{8H_i s_c}{\pi k_l L_s r_{sw1} n_s} + \frac{1}{2\pi k_{cr} L_s n_s}`."""
    return 8 * H_i * s_c / (pi * k_l * L_s * r_sw1 * n_slots) + 1 / (2 * pi * k_cr * L_s * n_slots)


def winding_radial_mean(L_s, n_slots, k_cr, s_c) -> Expr:
    r"""Slot winding mean to intermediate node, eq. 4.25 corrected [K/W]:
    :math:`s_c/(2\pi k_{cr} L_s n_s)`."""
    return s_c / (2 * pi * k_cr * L_s * n_slots)


def winding_capacitance(L_s, A_sw, n_slots, s_c, density, specific_heat) -> Expr:
    r"""Slot winding heat capacity, eq. 4.26 [J/K]: :math:`\rho c A_{sw} L_s n_s s_c`."""
    return density * specific_heat * A_sw * L_s * n_slots * s_c


# --- End windings (eqs. 4.27-4.30) -----------------------------------------------------------

def end_winding_axial(L_sc, A_sw, n_slots, k_ca) -> Expr:
    r"""Overhang axial resistance, eq. 4.27 [K/W]: :math:`L_{sc}/(2 k_{ca} A_{sw} n_s)`."""
    return L_sc / (2 * k_ca * A_sw * n_slots)


def end_winding_overhang_radial(L_sc, r_sw1, r_sewt, n_slots, k_cr, s_c) -> Expr:
    r"""Overhang radial resistance, eq. 4.28 [K/W]:
    :math:`r_{sewt}^2 s_c/(32\pi r_{sw1}^2 k_{cr} L_{sc} n_s)`."""
    return r_sewt**2 * s_c / (32 * pi * r_sw1**2 * k_cr * L_sc * n_slots)


def end_winding_toroid_radial(r_sewa, k_cr, s_c) -> Expr:
    r"""Toroid radial resistance, eq. 4.29 with :math:`L_t = 2\pi r_{sewa}` [K/W]:
    :math:`s_c/(16\pi k_{cr} L_t)`."""
    return s_c / (16 * pi * k_cr * 2 * pi * r_sewa)


def end_winding_capacitance(L_sc, A_sw, n_slots, r_sewa, r_sewt, s_c, density, specific_heat) -> Expr:
    r"""End winding heat capacity, eq. 4.30 [J/K]:
    :math:`\rho c s_c(\pi r_{sewt}^2 L_t + A_{sw} L_{sc} n_s)`, :math:`L_t = 2\pi r_{sewa}`."""
    return density * specific_heat * s_c * (pi * r_sewt**2 * 2 * pi * r_sewa + A_sw * L_sc * n_slots)


# --- Rotor (eqs. 4.31-4.33) and shaft (eqs. 4.34-4.37) ---------------------------------------

def rotor_radial_outer(L_r, r_r1, r_r2, k_sr) -> Expr:
    r"""Rotor mid-radius to outer surface, eq. 4.31 [K/W]:
    :math:`\ln(r_{r1}/r_{ri})/(2\pi k_{sr} L_r)`, :math:`r_{ri} = (r_{r1}+r_{r2})/2`."""
    return log(r_r1 / ((r_r1 + r_r2) / 2)) / (2 * pi * k_sr * L_r)


def rotor_radial_inner(L_r, r_r1, r_r2, k_sr) -> Expr:
    r"""Rotor mid-radius to inner surface, eq. 4.32 [K/W]: :math:`\ln(r_{ri}/r_{r2})/(2\pi k_{sr} L_r)`."""
    return log(((r_r1 + r_r2) / 2) / r_r2) / (2 * pi * k_sr * L_r)


def rotor_capacitance(L_r, r_r1, r_r2, stacking, density, specific_heat) -> Expr:
    r"""Rotor heat capacity, eq. 4.33 [J/K]: :math:`\rho c \pi L_r s (r_{r1}^2 - r_{r2}^2)`."""
    return density * specific_heat * pi * L_r * stacking * (r_r1**2 - r_r2**2)


def shaft_radial(L_contact, k_sr) -> Expr:
    r"""Shaft centre to a contact length ``L_contact``, eqs. 4.34-4.37 [K/W]: :math:`1/(8\pi K_{sr} L)`."""
    return 1 / (8 * pi * k_sr * L_contact)


# --- Air (eqs. 4.38-4.39) --------------------------------------------------------------------

def advection_conductance(c_air, mass_flow) -> Expr:
    r"""Conductance of an air stream, the inverse of eq. 4.38 [W/K]: :math:`c_{air}\dot m`."""
    return c_air * mass_flow


def advection(c_air, mass_flow) -> Expr:
    r"""Advection resistance, eq. 4.38 [K/W]: :math:`R = 1/(c_{air}\dot m)`."""
    return 1 / advection_conductance(c_air, mass_flow)
