"""Loss models: heat sources written as sympy expressions of inputs, states and parameters.

Copper loss per winding division at its own temperature (thesis eqs. 4.40-4.41), constant iron
loss split by mass, and the linear design model's affine copper loss (thesis 5.2, eq. 5.3) with
its floor at zero (:class:`LossFloor`); :func:`input_symbol` names a model input. Guide:
``docs/guide/model.md``.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import sympy

from .errors import InputError
from .network import HeatSource, Network


class LossFloor(sympy.Function):
    r""":math:`\max(v, 0)` of a linearised loss term that would otherwise go negative.

    A model is still called affine (:attr:`genthermal.model.ThermalModel.is_affine`) when its only
    non-affine parts are loss floors: its affine branch (every floor taken as the identity) holds
    wherever the floored terms are positive, and its exact step applies the floors.
    """

    nargs = 1

    @classmethod
    def eval(cls, value):
        if value.is_Number:
            return sympy.Max(value, 0)
        return None


def input_symbol(name: str) -> sympy.Symbol:
    """Return the sympy symbol of model input ``name`` (an input of the machine's interface,
    :attr:`genthermal.machines.interface.MachineInterface.inputs`)."""
    if not (isinstance(name, str) and name.isidentifier()):
        raise InputError("input", name, "an input name must be an identifier (e.g. I_u, T_coolant)")
    return sympy.Symbol(name, real=True)


def mass_shares(network: Network, nodes: tuple[str, ...]) -> dict[str, sympy.Expr]:
    """Share of each node's heat capacity in the total of ``nodes`` (same material → mass share)."""
    capacitances = {n: network.node(n).capacitance for n in nodes}
    total = sum(capacitances.values())
    return {n: c / total for n, c in capacitances.items()}


def copper_loss_sources(network: Network, winding_nodes: tuple[str, ...], current_inputs: tuple[str, ...],
                        R0: sympy.Symbol, alpha: sympy.Symbol) -> list[HeatSource]:
    """Temperature-dependent I²R heat sources in the winding divisions (thesis eqs. 4.40-4.41).

    Parameters
    ----------
    network : Network
        Supplies the winding capacitances (mass shares) and temperature symbols.
    winding_nodes : tuple of str
        Winding divisions that share the phase resistance.
    current_inputs : tuple of str
        The current inputs whose squares sum gives the loss per ohm (the three RMS phase currents).
    R0 : sympy.Symbol
        Phase resistance at 0 °C, Ω.
    alpha : sympy.Symbol
        Temperature coefficient of copper, 1/K.
    """
    current_squared = sum(input_symbol(p) ** 2 for p in current_inputs)
    shares = mass_shares(network, winding_nodes)
    return [HeatSource(node, shares[node] * current_squared * R0
                       * (1 + alpha * network.temperature_symbol(node)), "copper")
            for node in winding_nodes]


def iron_loss_sources(network: Network, iron_nodes: tuple[str, ...],
                      P_iron: sympy.Symbol) -> list[HeatSource]:
    """Constant iron loss ``P_iron`` (W) split between ``iron_nodes`` by mass."""
    shares = mass_shares(network, iron_nodes)
    return [HeatSource(node, shares[node] * P_iron, "iron") for node in iron_nodes]


@dataclasses.dataclass(frozen=True)
class CurrentSquaredFit:
    """Least-squares line :math:`I^2 \\approx a I + b` over a current range (thesis eq. 5.3).

    Attributes
    ----------
    slope : float
        :math:`a`, in A.
    intercept : float
        :math:`b`, in A².
    r_squared : float
        Coefficient of determination of the fit over the range.
    current_range : tuple of float
        (lowest, highest) current in A RMS.
    """

    slope: float
    intercept: float
    r_squared: float
    current_range: tuple[float, float]

    @property
    def exact_at(self) -> tuple[float, float]:
        """The two currents (A) where the line crosses :math:`I^2` (thesis: 2.4 A and 4.9 A)."""
        roots = np.roots([1.0, -self.slope, -self.intercept])
        return tuple(sorted(float(r.real) for r in roots))


def fit_current_squared(current_min: float, current_max: float, samples: int = 2001) -> CurrentSquaredFit:
    """Fit :math:`I^2 \\approx a I + b` by least squares on a uniform grid over a current range.

    Parameters
    ----------
    current_min, current_max : float
        Current range in A RMS (``0 <= current_min < current_max``).
    samples : int
        Number of grid points.

    Returns
    -------
    CurrentSquaredFit
    """
    if not (np.isfinite(current_min) and current_min >= 0):
        raise InputError("current_min", current_min, "must be a current >= 0 A")
    if not (np.isfinite(current_max) and current_max > current_min):
        raise InputError("current_max", current_max, f"must be > current_min = {current_min} A")
    current = np.linspace(current_min, current_max, samples)
    squared = current**2
    design = np.column_stack([current, np.ones_like(current)])
    (slope, intercept), *_ = np.linalg.lstsq(design, squared, rcond=None)
    residual = squared - design @ np.array([slope, intercept])
    r_squared = 1.0 - residual @ residual / np.sum((squared - squared.mean()) ** 2)
    return CurrentSquaredFit(float(slope), float(intercept), float(r_squared),
                             (float(current_min), float(current_max)))


def linearise_copper_sources(sources: tuple[HeatSource, ...], network: Network, current_inputs: tuple[str, ...],
                             slope: sympy.Symbol, intercept: sympy.Symbol,
                             theta_ref: sympy.Symbol) -> tuple[HeatSource, ...]:
    """Return ``sources`` with every copper loss made affine in the currents and independent of
    temperature: :math:`I_p^2 \\to \\max(a I_p + b, 0)`, :math:`\\theta_k \\to \\theta_{ref}`
    (thesis 5.2; the floor keeps the loss >= 0 below the line's zero, see :class:`LossFloor`)."""
    substitutions = {input_symbol(p) ** 2: LossFloor(slope * input_symbol(p) + intercept) for p in current_inputs}
    out = []
    for source in sources:
        if source.label == "copper":
            power = sympy.expand(source.power).subs(substitutions)
            power = power.subs(network.temperature_symbol(source.node), theta_ref)
            source = dataclasses.replace(source, power=power)
        out.append(source)
    return tuple(out)
