"""The design model the schedulers plan on, for any model with its fault effects: every loss that
is nonlinear in the currents replaced by its least-squares line along the load path (thesis
eq. 5.3). Main object: :func:`planning_design_model`.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import sympy

from ...design import DEFAULT_CURRENT_RANGE_FRACTION, linear_design_model
from ...exciter import DEFAULT_POWER_FACTOR
from ...losses import input_symbol
from ...model import ThermalModel

#: Currents sampled for the line fit, evenly over the design current range.
FIT_POINTS = 41


def _load_path_line(power: sympy.Expr, parameter_values: dict, current_range_A, generator,
                    rated_current_A: float) -> tuple[float, float]:
    """``(alpha W/A, beta W)`` of the least-squares line of ``power`` along the load path of
    ``generator`` (balanced phases, field current from its exciter law)."""
    currents = np.linspace(*current_range_A, FIT_POINTS)
    inputs = [input_symbol(p) for p in generator.phase_inputs] + [input_symbol(generator.excitation_input)]
    evaluate = sympy.lambdify(inputs, power.subs(parameter_values), "numpy")
    field = generator.exciter_law(currents, DEFAULT_POWER_FACTOR, rated_current_A)
    values = np.broadcast_to(evaluate(*([currents] * len(generator.phase_inputs)), field), currents.shape)
    alpha, beta = np.polyfit(currents, values, 1)
    return float(alpha), float(beta)


def planning_design_model(model: ThermalModel, current_range_A=None) -> ThermalModel:
    """The affine design model of ``model`` (nonlinear or already linear) for the schedulers.

    Parameters
    ----------
    model : ThermalModel
        A simulation model, possibly with fault effects, or a linear design model.
    current_range_A : (float, float), optional
        Range of the line fits, A RMS; default the design model's (thesis eq. 5.3,
        :data:`~genthermal.design.DEFAULT_CURRENT_RANGE_FRACTION` of the rated current).

    Returns
    -------
    ThermalModel
        Affine in state and input. Losses that were already affine are unchanged.
    """
    generator = model.spec.interface.generator
    rated = model.spec.rated_current_A
    if current_range_A is None:
        current_range_A = tuple(fraction * rated for fraction in DEFAULT_CURRENT_RANGE_FRACTION)
    design = model if model.spec.variant == "linear" else linear_design_model(model, current_range_A)
    if design.is_affine:
        return design
    symbols = design.parameters.symbols()
    values = {symbols[name]: value for name, value in design.parameters.values().items()}
    phases = generator.phase_inputs
    currents = [input_symbol(p) for p in phases] + [input_symbol(generator.excitation_input)]
    mean_phase = sum(input_symbol(p) for p in phases) / len(phases)
    sources = []
    for source in design.network.heat_sources:
        nonlinear_in_currents = source.label != "copper" and source.power.has(*currents) and \
            sympy.Poly(sympy.expand(source.power), *currents).total_degree() > 1  # copper: already a line
        if nonlinear_in_currents:
            alpha, beta = _load_path_line(source.power, values, current_range_A, generator, rated)
            source = dataclasses.replace(source, power=alpha * mean_phase + beta)
        sources.append(source)
    return design.with_network(design.network.replace(heat_sources=tuple(sources)))
