r"""The linear design model of thesis chapter 5, derived from the same network.

Two changes to the nonlinear simulation model's copper loss, nothing else:

* :math:`I_p^2 \approx a I_p + b`, a least-squares line over a current range (thesis eq. 5.3; the
  thesis fit was :math:`7.3 I - 12`, R² = 0.9764);
* the winding resistance is held at :math:`R_0(1+\alpha_{cu}\theta_{ref})`.

The result is affine in state and input, so its discrete step is an exact zero-order hold.
"""

from __future__ import annotations

from .losses import CurrentSquaredFit, fit_current_squared, linearise_copper_sources
from .model import ThermalModel
from .parameters import Parameter

#: Default linearisation range as fractions of the machine's rated current: the lowest and highest
#: currents of thesis Table 3.2 (27.3 % and 100 % of rated).
DEFAULT_CURRENT_RANGE_FRACTION = (0.273, 1.0)
#: Default winding temperature for the constant resistance, °C (assumed: near the temperatures
#: where the management decisions are made, between normal operation and the thesis's winding limit).
DEFAULT_THETA_REF_C = 90.0


def linear_design_model(model: ThermalModel, current_range_A: tuple[float, float] | None = None,
                        theta_ref_C: float = DEFAULT_THETA_REF_C) -> ThermalModel:
    """Return the linear design model of ``model`` (thesis 5.2).

    Parameters
    ----------
    model : ThermalModel
        The nonlinear simulation model.
    current_range_A : (float, float), optional
        Range over which :math:`I^2` is fitted by a line, A RMS; default
        :data:`DEFAULT_CURRENT_RANGE_FRACTION` of the machine's rated current.
    theta_ref_C : float
        Winding temperature at which the resistance is frozen, °C.

    Returns
    -------
    ThermalModel
        Same network and parameters plus ``I2_slope``, ``I2_intercept`` (fitted) and
        ``theta_ref`` (assumed); ``spec.variant == "linear"``. The fit is in
        ``current_squared_fit(result)``.
    """
    if current_range_A is None:
        rated = model.spec.rated_current_A
        current_range_A = tuple(fraction * rated for fraction in DEFAULT_CURRENT_RANGE_FRACTION)
    fit = fit_current_squared(*current_range_A)
    lo, hi = fit.current_range
    where = f"least squares of I^2 over [{lo:g}, {hi:g}] A (R^2 = {fit.r_squared:.4f}), thesis eq. 5.3"
    extra = (
        Parameter("I2_slope", fit.slope, "A", "fitted", where, lower=-1e9),
        Parameter("I2_intercept", fit.intercept, "A^2", "fitted", where, lower=-1e9),
        Parameter("theta_ref", theta_ref_C, "degC", "assumed",
                  "winding temperature of the constant resistance (thesis 5.2.2)", lower=-273.15),
    )
    parameters = model.parameters.with_parameters(*extra)
    symbols = {p.name: p.symbol for p in extra}
    sources = linearise_copper_sources(model.network.heat_sources, model.network, model.spec.interface.load_currents,
                                       symbols["I2_slope"],
                                       symbols["I2_intercept"], symbols["theta_ref"])
    return model.with_network(model.network.replace(heat_sources=sources), parameters, variant="linear")


def current_squared_fit(design_model: ThermalModel) -> CurrentSquaredFit:
    """Recover the :math:`I^2` fit stored in a linear design model's parameters."""
    v = design_model.parameters
    source = v["I2_slope"].source
    lo, hi = (float(s) for s in source[source.index("[") + 1:source.index("]")].split(","))
    return fit_current_squared(lo, hi)
