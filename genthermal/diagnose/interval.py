r"""How well the record determines a fitted effect's parameters: intervals from the fit's curvature.

:func:`fitted_intervals` refits a candidate's parameters, the earlier effects and the initial
state with the onsets held, and gives intervals from :math:`\hat\sigma^2 (J^\top J)^{-1}`
inflated by :math:`N/N_{eff}` for AR(1) residuals (Zwiers & von Storch 1995), mapped back through
the parameter's scaling and clipped to its physical bounds. Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from scipy.stats import norm

from ..errors import InputError
from .search import Candidate, EffectSearch, _indicator, _Problem
from .trajectory import parameter_scaling

#: Levenberg-Marquardt iterations of the refit that finds the initial state of the candidate's
#: optimum (the candidate keeps its values, not its initial state; from them it converges in 2-3).
REFIT_ITERATIONS = 6


@dataclasses.dataclass(frozen=True)
class ParameterInterval:
    """Interval of one fitted parameter (module docstring).

    Attributes
    ----------
    parameter : str
    estimate, low, high : float
        The candidate's value and the interval's ends, model units.
    level : float
        Coverage the interval is built for (0.95).
    n_effective : float
        Effective number of independent sensor samples behind it.
    at_lower, at_upper : bool
        The end is the parameter's physical bound: the record does not exclude it.
    """

    parameter: str
    estimate: float
    low: float
    high: float
    level: float
    n_effective: float
    at_lower: bool
    at_upper: bool

    def to_dict(self) -> dict:
        """JSON entry."""
        return {"estimate": self.estimate, "low": self.low, "high": self.high, "level": self.level,
                "n_effective": self.n_effective, "at_lower": self.at_lower, "at_upper": self.at_upper}


def effective_samples(residuals: np.ndarray) -> float:
    r"""Effective number of independent samples of ``residuals`` (n_outputs, N; NaN missing):
    :math:`\sum_j N_j (1-\rho_j)/(1+\rho_j)` over the outputs, :math:`\rho_j` the lag-1
    autocorrelation of output j clipped to [0, 0.999] (module docstring)."""
    total = 0.0
    for series in np.atleast_2d(residuals):
        valid = series[np.isfinite(series)]
        if valid.size < 3:
            total += valid.size
            continue
        centred = valid - valid.mean()
        denominator = float(centred @ centred)
        rho = float(centred[1:] @ centred[:-1]) / denominator if denominator > 0 else 0.0
        rho = min(max(rho, 0.0), 0.999)
        total += valid.size * (1.0 - rho) / (1.0 + rho)
    return total


def fitted_intervals(search: EffectSearch, candidate: Candidate, level: float = 0.95) -> dict:
    """Interval of each parameter of ``candidate``'s effect from the curvature of its fit (module
    docstring).

    Parameters
    ----------
    search : EffectSearch
        The search that fitted ``candidate`` (fitted: :meth:`EffectSearch.fit_found` called).
    candidate : Candidate
        A candidate of ``search``, with its onset.
    level : float
        Coverage, in (0, 1).

    Returns
    -------
    dict
        Parameter name → :class:`ParameterInterval`, for the parameters of the candidate's effect.
    """
    if not 0.0 < level < 1.0:
        raise InputError("level", level, "the interval's coverage must lie strictly between 0 and 1")
    search._require_fitted()
    effect = search.effect(candidate.effect)
    names = search._found_names + [p.name for p in effect.parameters]
    groups = [(list(f.values), {n: n for n in f.values}) for f in search.found]
    groups.append(([p.name for p in effect.parameters], {p.name: p.name for p in effect.parameters}))
    simulator = search.simulator(candidate.effect, search.series, names, groups)
    model = search.neutral_model(candidate.effect)
    start = [*(v for f in search.found for v in candidate.found_values[f.effect].values()),
             *(candidate.values[p.name] for p in effect.parameters)]
    scalings = [parameter_scaling(model, n, start=v) for n, v in zip(names, start)]
    onsets = [*(candidate.found_onsets.get(f.effect, f.onset_index) for f in search.found), candidate.onset_index]
    indicator = _indicator(search.series.time_s.size, onsets)
    problem = _Problem(simulator, search.series, scalings, exact=True, fit_initial_state=True)
    x0 = search.x0_coefficients
    z, _ = problem.gauss_newton(np.zeros(len(names) + 2), x0, indicator, REFIT_ITERATIONS)
    residual, jacobian = problem.evaluate(z, x0, indicator)
    on_grid = np.full(problem.mask.T.shape, np.nan)  # (N, n_outputs), the residual's sample order
    on_grid[problem.mask.T] = residual
    n_effective = max(effective_samples(on_grid.T), len(z) + 1.0)
    variance = float(residual @ residual) / max(residual.size - len(z), 1) * residual.size / n_effective
    covariance = np.linalg.pinv(jacobian.T @ jacobian) * variance
    spread = float(norm.ppf(0.5 + level / 2.0))
    intervals = {}
    offset = len(search._found_names)
    for j, parameter in enumerate(effect.parameters):
        i = offset + j
        half = spread * math.sqrt(max(covariance[i, i], 0.0))
        low, high = max(z[i] - half, problem.lower[i]), min(z[i] + half, problem.upper[i])
        estimate = float(candidate.values[parameter.name])
        intervals[parameter.name] = ParameterInterval(
            parameter.name, estimate, min(float(scalings[i].value(low)), estimate),
            max(float(scalings[i].value(high)), estimate), level, float(n_effective),
            bool(low <= problem.lower[i]), bool(high >= problem.upper[i]))
    return intervals
