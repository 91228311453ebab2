"""Least-squares calibration of named model parameters against measurements (CasADi + IPOPT).

:func:`calibrate` fits the parameters with exact Jacobians from
:class:`~genthermal.diagnose.trajectory.ParametricSimulator` and returns a
:class:`CalibrationResult`: values, confidence intervals from the Fisher information (inflated for
time-correlated residuals), identifiability warnings and a status that says whether the fit
stopped at a bound or left a residual that is not white. Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Sequence

import casadi as ca
import numpy as np

from ..errors import InputError
from ..model import ThermalModel
from .trajectory import ParametricSimulator, Scaling, parameter_scaling

#: Correlation above which two fitted parameters are reported as not separately identifiable.
CORRELATION_LIMIT = 0.99
#: Condition number of the column-normalised Fisher information above which a fit is ill-posed.
CONDITION_LIMIT = 1e8
_IPOPT_OPTIONS = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
                  "ipopt.max_iter": 40, "ipopt.tol": 1e-6, "ipopt.mu_strategy": "adaptive",
                  "ipopt.acceptable_tol": 1e-4, "ipopt.acceptable_obj_change_tol": 1e-10,
                  "ipopt.acceptable_iter": 2}


@dataclasses.dataclass
class LeastSquaresFit:
    """Result of :func:`fit_least_squares`.

    Attributes
    ----------
    theta : numpy.ndarray
        Fitted parameter values (model units), in ``simulator.fitted`` order.
    x0_coefficients : numpy.ndarray
        Fitted ``(a, c)`` of the initial state.
    predicted : numpy.ndarray
        Model outputs at the optimum, (n_outputs, N), °C.
    rss : float
        Residual sum of squares over the valid samples, K².
    n_valid : int
        Number of valid sensor samples.
    jacobian : numpy.ndarray or None
        :math:`\\partial y/\\partial(\\theta, a, c)` at the optimum on the valid samples.
    converged : bool
    """

    theta: np.ndarray
    x0_coefficients: np.ndarray
    predicted: np.ndarray
    rss: float
    n_valid: int
    jacobian: np.ndarray
    converged: bool

    @property
    def rmse(self) -> float:
        """Root-mean-square error over every valid sensor sample, K."""
        return math.sqrt(self.rss / max(self.n_valid, 1))


def fit_least_squares(simulator: ParametricSimulator, measured: np.ndarray, scalings: Sequence[Scaling],
                      x0_coefficients, indicator=None, fit_initial_state: bool = True,
                      with_jacobian: bool = True) -> LeastSquaresFit:
    """Fit ``simulator.fitted`` (and the initial state) to ``measured`` with IPOPT.

    Parameters
    ----------
    simulator : ParametricSimulator
    measured : numpy.ndarray
        Measured outputs (n_outputs, N), °C; NaN marks a missing sample.
    scalings : sequence of Scaling
        One per fitted parameter; their references are the start values.
    x0_coefficients : (float, float)
        Start (or fixed) ``(a, c)``.
    indicator : numpy.ndarray, optional
        Regime indicator; default: regime 0 throughout.
    fit_initial_state : bool
        Fit ``(a, c)`` too, within ±1 and ±5 K of the start (default), or hold them.
    with_jacobian : bool
        Compute :attr:`LeastSquaresFit.jacobian` (for :func:`fisher_summary`); else it is None.
    """
    indicator = simulator.indicator() if indicator is None else indicator
    mask = np.isfinite(measured)
    target = np.where(mask, measured, 0.0)
    n_theta = len(scalings)
    n_z = n_theta + (2 if fit_initial_state else 0)
    z = ca.MX.sym("z", n_z)
    theta = ca.vertcat(*[s.value(z[i]) for i, s in enumerate(scalings)]) if n_theta else ca.MX(0, 1)
    a0, c0 = (float(v) for v in x0_coefficients)
    # the initial state may move by ±1 in a and ±5 K in c: enough for noise on the first samples,
    # too little to absorb a misfit of the whole record
    ac = ca.vertcat(a0 + z[n_theta], c0 + 10.0 * z[n_theta + 1]) if fit_initial_state else ca.DM([a0, c0])
    residual = ca.vec(ca.DM(mask.astype(float)) * (simulator.symbolic(theta, ac, ca.DM(indicator)) - ca.DM(target)))
    jac = ca.jacobian(residual, z)
    lam_f = ca.MX.sym("lam_f")
    hessian = ca.Function("gauss_newton", [z, ca.MX.sym("p", 0), lam_f, ca.MX.sym("lam_g", 0)],
                          [ca.triu(lam_f * (jac.T @ jac))], ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])
    solver = ca.nlpsol("least_squares", "ipopt", {"x": z, "f": 0.5 * ca.sumsqr(residual)},
                       dict(_IPOPT_OPTIONS, hess_lag=hessian))
    bounds = [s.bounds() for s in scalings] + ([(-1.0, 1.0), (-0.5, 0.5)] if fit_initial_state else [])
    solution = solver(x0=np.zeros(n_z), lbx=[b[0] for b in bounds], ubx=[b[1] for b in bounds])
    # IPOPT relaxes the bounds by its bound_relax_factor (1e-8): a P_iron fitted to its lower bound
    # 0 came back as -4e-7 W, which the model then refused as not physical, stopping a flight
    z_opt = np.clip(np.asarray(solution["x"]).ravel(), [b[0] for b in bounds], [b[1] for b in bounds])
    theta_opt = np.array([s.value(float(z_opt[i])) for i, s in enumerate(scalings)])
    ac_opt = np.array([a0 + z_opt[n_theta], c0 + 10.0 * z_opt[n_theta + 1]]) if fit_initial_state \
        else np.array([a0, c0])
    if with_jacobian:
        predicted, jacobian = simulator.outputs_and_jacobian(theta_opt, ac_opt, indicator)
        jacobian = jacobian[mask.T.ravel()]
    else:
        predicted, jacobian = simulator.outputs(theta_opt, ac_opt, indicator), None
    rss = float(np.sum(np.where(mask, predicted - target, 0.0) ** 2))
    return LeastSquaresFit(theta_opt, ac_opt, predicted, rss, int(mask.sum()), jacobian,
                           bool(solver.stats()["success"]))


def fisher_summary(fit: LeastSquaresFit, names: Sequence[str], residuals: np.ndarray | None = None) -> dict:
    """Standard errors, 95 % intervals, correlations and identifiability of a fit.

    The Fisher information of :math:`(\\theta, a, c)` is :math:`F = J^\\top J/\\hat\\sigma^2` with
    :math:`\\hat\\sigma^2 = RSS/(N - n)`; the covariance is :math:`F^{-1}` (pseudo-inverse when
    singular). The condition number is that of F with columns scaled to unit norm. Given the
    ``residuals`` (n_outputs, N; NaN missing), :math:`\\hat\\sigma^2` is inflated by
    :math:`N/N_{eff}` (:func:`genthermal.diagnose.interval.effective_samples`): residuals that are
    not white hold fewer independent samples, and intervals that ignore it exclude the truth.

    Returns
    -------
    dict
        ``std``, ``ci95`` (list of (low, high)), ``correlation`` (n_theta × n_theta),
        ``condition_number``, ``warnings`` (plain-language lines naming the parameters).
    """
    n_theta = len(names)
    J = fit.jacobian
    dof = max(fit.n_valid - J.shape[1], 1)
    sigma2 = fit.rss / dof
    inflation = 1.0
    if residuals is not None:  # correlated residuals carry fewer independent samples than N
        from .interval import effective_samples

        inflation = max(fit.n_valid / max(effective_samples(residuals), J.shape[1] + 1.0), 1.0)
        sigma2 *= inflation
    norms = np.linalg.norm(J, axis=0)
    norms[norms == 0] = 1.0
    Jn = J / norms
    condition = float(np.linalg.cond(Jn.T @ Jn))
    covariance = np.linalg.pinv(J.T @ J) * sigma2
    std = np.sqrt(np.clip(np.diag(covariance)[:n_theta], 0.0, None))
    outer = np.sqrt(np.outer(np.diag(covariance), np.diag(covariance)))
    correlation = np.divide(covariance, outer, out=np.zeros_like(covariance), where=outer > 0)[:n_theta, :n_theta]
    warnings = []
    for i in range(n_theta):
        if np.linalg.norm(J[:, i]) == 0:
            warnings.append(f"{names[i]} does not change the sensor temperatures: not identifiable")
        for j in range(i + 1, n_theta):
            if abs(correlation[i, j]) > CORRELATION_LIMIT:
                warnings.append(f"{names[i]} and {names[j]} are correlated ({correlation[i, j]:+.3f}): "
                                "the data cannot tell them apart; fix one of them")
    if condition > CONDITION_LIMIT:
        warnings.append(f"Fisher information is ill-conditioned (condition number {condition:.2e}): "
                        f"the parameters {', '.join(names)} are not all identifiable from these data")
    ci = [(float(v - 1.96 * s), float(v + 1.96 * s)) for v, s in zip(fit.theta, std)]
    return {"std": std.tolist(), "ci95": ci, "correlation": correlation.tolist(),
            "condition_number": condition, "sigma_K": math.sqrt(sigma2 / inflation), "warnings": warnings,
            "interval_widening": math.sqrt(inflation)}


@dataclasses.dataclass
class CalibrationResult:
    """Result of :func:`calibrate`.

    Attributes
    ----------
    model : ThermalModel
        The model with the fitted values (provenance ``fitted``, source naming the data), without
        a disturbance prior (``genthermal calibrate --out`` adds one:
        :func:`genthermal.estimation.disturbance_prior.learn_disturbance_prior`).
    names : list of str
    start, values : list of float
        Values before and after the fit (model units).
    fisher : dict
        See :func:`fisher_summary`.
    before, after : dict
        Comparison metrics (:func:`genthermal.diagnose.compare.compare`) of the model before and
        after the fit.
    converged : bool
        IPOPT's own verdict; :attr:`status` is what to report.
    at_bounds : list of str
        Fitted parameters that stopped at a bound of their physical range (``"R0 (upper bound
        1200)"``): the data would move them further, the fit did not converge to an optimum inside.
    residual_autocorrelation : dict
        Output name → lag-1 autocorrelation of the fit's residual. Above
        :data:`~genthermal.diagnose.residual.MAX_AUTOCORRELATION` the residual is not white: the
        intervals are widened for it (:func:`fisher_summary`) and :attr:`status` says so.
    start_provenance : list of str
        Provenance of each start value (``thesis``, ``literature``, ``assumed``, ``fitted``).
    trajectories : pandas.DataFrame or None
        ``time_s`` and per sensor ``<sensor>_measured``, ``<sensor>_before`` and
        ``<sensor>_after``: the measurement and the model before and after the fit, °C (from the
        two comparisons; what :meth:`plot` draws).
    """

    model: ThermalModel
    names: list
    start: list
    values: list
    fisher: dict
    before: dict
    after: dict
    converged: bool
    at_bounds: list = dataclasses.field(default_factory=list)
    residual_autocorrelation: dict = dataclasses.field(default_factory=dict)
    start_provenance: list = dataclasses.field(default_factory=list)
    trajectories: object = None

    @property
    def intervals_valid(self) -> bool:
        """True when the residual passes the whiteness test the intervals assume."""
        from .residual import MAX_AUTOCORRELATION

        return all(rho <= MAX_AUTOCORRELATION for rho in self.residual_autocorrelation.values())

    @property
    def status(self) -> str:
        """``converged``, or what went wrong: not converged, at a bound, intervals not valid."""
        from .residual import MAX_AUTOCORRELATION

        problems = [] if self.converged else ["NOT converged"]
        if self.at_bounds:
            problems.append(f"stopped at a bound: {', '.join(self.at_bounds)}")
        if not self.intervals_valid:
            worst = max(self.residual_autocorrelation, key=self.residual_autocorrelation.get)
            problems.append(f"the residual of {worst} is not white (lag-1 autocorrelation "
                            f"{self.residual_autocorrelation[worst]:.2f} > {MAX_AUTOCORRELATION:g}): 95 % intervals "
                            f"widened x{self.fisher.get('interval_widening', 1.0):.3g} for it, a model error "
                            "may remain")
        return "; ".join(problems) or "converged"

    @property
    def warnings(self) -> list:
        """Identifiability warnings (plain language, naming the parameters)."""
        return self.fisher["warnings"]

    def to_pandas(self):
        """The fitted parameters as a table (:func:`~genthermal.diagnose.result_views.parameters_frame`).

        Returns
        -------
        pandas.DataFrame
            One row per parameter: ``name``, ``value``, ``unit``, ``ci95_low``, ``ci95_high``,
            ``std``, ``start``, ``provenance``, ``source`` and ``start_provenance``.
        """
        from .result_views import parameters_frame

        return parameters_frame(self)

    def plot(self, path=None, ax=None):
        """Measured temperatures per sensor against the model before and after the fit.

        Parameters
        ----------
        path : path-like, optional
            PNG file to write the figure to.
        ax : matplotlib.axes.Axes or sequence of Axes, optional
            Draw into this Axes (every sensor) or these (one per sensor) instead of a new figure.

        Returns
        -------
        matplotlib.figure.Figure
        """
        from .result_views import plot_fit

        return plot_fit(self, path=path, ax=ax)

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        rows = []
        for i, name in enumerate(self.names):
            parameter = self.model.parameters[name]
            rows.append({"name": name, "unit": parameter.unit, "start": self.start[i], "value": self.values[i],
                         "std": self.fisher["std"][i], "ci95": list(self.fisher["ci95"][i])})
        return {"model": self.model.name, "parameters": rows, "converged": self.converged,
                "status": self.status, "at_bounds": self.at_bounds, "intervals_valid": self.intervals_valid,
                "residual_lag1_autocorrelation": self.residual_autocorrelation,
                "condition_number": self.fisher["condition_number"], "correlation": self.fisher["correlation"],
                "residual_sigma_K": self.fisher["sigma_K"], "warnings": self.warnings,
                "rmse_before": self.before["rmse_all_sensors"], "rmse_after": self.after["rmse_all_sensors"],
                "before": self.before["overall"], "after": self.after["overall"]}


def check_parameter_names(model: ThermalModel, names: Sequence[str], field: str = "params") -> list[str]:
    """Return ``names`` if every one is a parameter of ``model``, else raise InputError naming it."""
    import difflib

    given = ",".join(names)
    names = [n.strip() for n in names if n.strip()]
    if not names:
        raise InputError(field, given, "name at least one parameter to fit")
    for name in names:
        if name not in model.parameters:
            close = difflib.get_close_matches(name, model.parameter_names, n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise InputError(field, name, f"not a parameter of {model.name}{hint}")
    if len(set(names)) != len(names):
        raise InputError(field, ",".join(names), "a parameter is named twice")
    return names


def calibrate(model: ThermalModel, data, names: Sequence[str], dt_s: float | None = None) -> CalibrationResult:
    """Fit the named parameters of ``model`` to measurements by least squares (IPOPT).

    Parameters
    ----------
    model : ThermalModel
    data : MeasurementData, pandas.DataFrame, path or MeasuredSeries
    names : sequence of str
        Parameters to fit; bounds from their physical ranges.
    dt_s : float, optional
        Resample the data to this period first, s.

    Returns
    -------
    CalibrationResult
        The fitted model carries provenance ``fitted`` and a source naming the data.
    """
    from .compare import compare, initial_coefficients, measured_series

    names = check_parameter_names(model, names)
    series = measured_series(data, dt_s, model.output_names, model.spec.interface)
    before = compare(model, series)
    simulator = ParametricSimulator(model, series.dt_s, series.input_matrix, names)
    scalings = [parameter_scaling(model, n) for n in names]
    fit = fit_least_squares(simulator, series.outputs, scalings, initial_coefficients(model, series))
    fisher = fisher_summary(fit, names, fit.predicted - series.outputs)
    values = {n: float(v) for n, v in zip(names, fit.theta)}
    source = (f"least squares on {series.source} ({series.time_s.size} samples, "
              f"{(series.time_s[-1] - series.time_s[0]) / 3600:.2f} h)")
    fitted = model.with_parameters(provenance="fitted", source=source, **values)
    after = compare(fitted, series)
    return CalibrationResult(fitted, names, [model.parameters.value(n) for n in names], list(values.values()),
                             fisher, before.metrics, after.metrics, fit.converged, _at_bounds(names, scalings, fit),
                             _residual_autocorrelation(fit, series.outputs, model.output_names),
                             [model.parameters[n].provenance for n in names], _trajectories(before, after))


def _trajectories(before, after):
    """``time_s`` and per sensor the measurement and the model before and after the fit (°C), from
    the two comparisons."""
    import pandas as pd

    columns = {"time_s": before.frame["time_s"].to_numpy()}
    for name in before.output_names:
        columns[f"{name}_measured"] = before.frame[f"{name}_measured"].to_numpy()
        columns[f"{name}_before"] = before.frame[f"{name}_model"].to_numpy()
        columns[f"{name}_after"] = after.frame[f"{name}_model"].to_numpy()
    return pd.DataFrame(columns)


def _at_bounds(names, scalings, fit: LeastSquaresFit) -> list[str]:
    """Fitted parameters within 1e-6 (relative) of a bound of their range."""
    found = []
    for name, scaling, value in zip(names, scalings, fit.theta):
        for side, bound in (("lower", scaling.lower), ("upper", scaling.upper)):
            if abs(value - bound) <= 1e-6 * max(abs(bound), abs(scaling.reference), 1e-12):
                found.append(f"{name} ({side} bound {bound:.6g})")
    return found


def _residual_autocorrelation(fit: LeastSquaresFit, measured: np.ndarray, outputs) -> dict:
    """Output → lag-1 autocorrelation of the residual over its valid samples (consecutive pairs)."""
    result = {}
    for name, predicted, data in zip(outputs, fit.predicted, measured):
        residual = predicted - data
        pairs = np.isfinite(residual[1:]) & np.isfinite(residual[:-1])
        if pairs.sum() < 3:
            continue
        a, b = residual[:-1][pairs], residual[1:][pairs]
        a, b = a - a.mean(), b - b.mean()
        scale = math.sqrt(float(np.dot(a, a) * np.dot(b, b)))
        result[name] = float(np.dot(a, b) / scale) if scale > 0 else 0.0
    return result
