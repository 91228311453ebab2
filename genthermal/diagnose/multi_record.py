"""Fit and score one model on several measured records, each from its own measured initial state.

A :class:`Record` is one profile on a uniform grid with an initial state taken from its first
measured temperatures; :class:`StateTrajectory` steps the model over it with the fitted parameters
symbolic; :func:`fit_records` minimises the squared sensor errors over all records (IPOPT, exact
Jacobian); its :class:`RecordsFit` carries confidence intervals and identifiability warnings
(:func:`records_fisher`);
:func:`decimated` block-averages long 1-Hz records first. Tutorial: ``docs/tutorials/real_motor.md``.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Mapping, Sequence

import casadi as ca
import numpy as np

from ..discretise import parametric_step
from ..errors import InputError
from ..long_records import block_average
from ..machines.interface import InputKind
from ..model import ThermalModel
from .calibrate import CONDITION_LIMIT, CORRELATION_LIMIT
from .trajectory import _chunked_outputs


@dataclasses.dataclass
class Record:
    """One measured profile on a uniform grid.

    Attributes
    ----------
    name : str
    dt_s : float
        Sample period, s.
    inputs : numpy.ndarray
        (n_inputs, N) in the model's input order and units.
    outputs : numpy.ndarray
        (n_outputs, N) measured sensor outputs, °C (NaN: missing).
    x0 : numpy.ndarray
        Initial state, °C, in ``model.state_names`` order.
    """

    name: str
    dt_s: float
    inputs: np.ndarray
    outputs: np.ndarray
    x0: np.ndarray

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return self.inputs.shape[1]


def decimated(data, step_s: float):
    """``data`` (MeasurementData) block-averaged to ``step_s`` s; signed currents keep their mean
    square (copper loss) with the sign of their block mean."""
    averaged = block_average(data, step_s)
    frame = averaged.frame
    elapsed = data.time_s - data.time_s[0]
    block = np.floor(elapsed / step_s + 1e-9).astype(np.int64)
    n_blocks = len(frame)
    for spec in data.interface.inputs:
        if spec.kind is InputKind.CURRENT and spec.signed:
            values = data.frame[spec.name].to_numpy(dtype=float)
            counts = np.maximum(np.bincount(block, minlength=n_blocks), 1)
            mean_square = np.bincount(block, values ** 2, n_blocks) / counts
            frame[spec.name] = np.sign(frame[spec.name].to_numpy()) * np.sqrt(mean_square)
    return averaged


def initial_state_from_measurements(model: ThermalModel, first_outputs: np.ndarray, u0: np.ndarray) -> np.ndarray:
    """Initial state (°C): each state node the mean of the first measured sensors on it; nodes
    without one the mean of their measured network neighbours, else the coolant temperature."""
    interface = model.spec.interface
    by_node: dict = {}
    for sensor, value in zip(interface.sensors, first_outputs):
        if np.isfinite(value):
            by_node.setdefault(sensor.node, []).append(float(value))
    coolant = float(u0[model.input_names.index(interface.coolant_input)])
    known = {node: float(np.mean(v)) for node, v in by_node.items()}
    x0 = []
    for node in model.state_names:
        if node in known:
            x0.append(known[node])
            continue
        neighbours = [l.b if l.a == node else l.a for l in model.network.links if node in (l.a, l.b)]
        values = [known[n] for n in neighbours if n in known]
        x0.append(float(np.mean(values)) if values else coolant)
    return np.array(x0)


def record_from_measurements(model: ThermalModel, data, step_s: float | None = None) -> Record:
    """A :class:`Record` of ``data`` (MeasurementData in the model's schema), block-averaged to
    ``step_s`` s when given."""
    if step_s is not None:
        data = decimated(data, step_s)
    time_s = data.time_s
    steps = np.diff(time_s)
    if steps.size == 0:
        raise InputError("data", data.source, "need at least two samples")
    dt_s = float(np.median(steps))
    if np.max(np.abs(steps - dt_s)) > 1e-6 * dt_s:
        raise InputError("data", data.source, "the samples are not uniform; give a step to average them to")
    inputs = data.frame[list(model.input_names)].to_numpy(dtype=float).T
    outputs = data.sensors[list(model.output_names)].to_numpy(dtype=float).T
    return Record(data.source, dt_s, inputs, outputs, initial_state_from_measurements(model, outputs[:, 0], inputs[:, 0]))


class StateTrajectory:
    """Outputs of ``model`` over ``n_samples`` steps of ``dt_s`` from a given initial state, with the
    parameters ``fitted`` symbolic (module docstring).

    Calls take ``(theta, x0, inputs)``: fitted values (model units), initial state (°C), inputs
    (n_inputs, N); return outputs (n_outputs, N) (the output at sample k is that of the state at k).
    """

    def __init__(self, model: ThermalModel, dt_s: float, n_samples: int, fitted: Sequence[str]):
        self.model, self.dt_s, self.n_samples, self.fitted = model, float(dt_s), int(n_samples), list(fitted)
        nx, nu = model.n_states, len(model.input_names)
        theta = ca.SX.sym("theta", len(self.fitted))
        values = [ca.SX(v) for v in model.p0]
        for j, name in enumerate(self.fitted):
            values[model.parameter_names.index(name)] = theta[j]
        p = ca.vertcat(*values)
        x, u = ca.SX.sym("x", nx), ca.SX.sym("u", nu)
        step_parts = parametric_step(model, x, u, p, self.dt_s)
        y = model.functions["outputs"](x, u, p)
        (x_next, y), symbols, parametric = ca.extract_parametric([step_parts.x_next, y], theta,
                                                                 {"extract_trivial": True})
        e = ca.vertcat(*symbols) if symbols else ca.SX.zeros(0)
        phis = ca.vertcat(*[ca.vec(m) for m in step_parts.phis])
        used = [i for i, d in enumerate(ca.which_depends(x_next, phis, 1, False)) if d]
        step = ca.Function("step", [x, u, e, phis[used]], [x_next, y])
        hoisted = ca.Function("hoisted", [theta], [ca.vertcat(*parametric) if parametric else ca.SX.zeros(0)])
        state_matrix = ca.Function("state_matrix", [theta], [step_parts.state_matrix])
        th, x0, U = ca.MX.sym("theta", len(self.fitted)), ca.MX.sym("x0", nx), ca.MX.sym("inputs", nu, self.n_samples)
        exponentials = ca.vertcat(*[ca.vec(m) for m in step_parts.exponential(state_matrix(th))])[used]
        Y, _ = _chunked_outputs(step, self.n_samples, x0, U, [hoisted(th), exponentials])
        self.function = ca.Function("trajectory", [th, x0, U], [Y])

    def outputs(self, theta, x0, inputs) -> np.ndarray:
        """Numeric outputs, °C, (n_outputs, N)."""
        return np.asarray(self.function(theta, x0, inputs))


def simulate_record(model: ThermalModel, record: Record) -> np.ndarray:
    """Open-loop outputs (°C, (n_outputs, N)) of ``model`` on ``record`` from its initial state."""
    return StateTrajectory(model, record.dt_s, record.n_samples, []).outputs(ca.DM(0, 1), record.x0, record.inputs)


@dataclasses.dataclass
class RecordsFit:
    """Result of :func:`fit_records`.

    Attributes
    ----------
    model : ThermalModel
        The model with the fitted values (provenance ``fitted``).
    names : list of str
    start, values : numpy.ndarray
        Values before and after the fit (model units).
    rss : float
        Sum of squared sensor errors over all records at the optimum, K².
    n_valid : int
        Valid sensor samples.
    jacobian : numpy.ndarray
        d(residual)/d(theta) at the optimum (valid samples), for :func:`records_fisher`.
    converged : bool
    fit_time_s : float
        Wall time of the fit, s.
    records : list of str
        The records' names (their sources).
    fisher : dict
        Standard errors, 95 % intervals and warnings (:func:`records_fisher`); a caller may widen
        them (:func:`~genthermal.diagnose.error_model.widened_calibration`).
    """

    model: ThermalModel
    names: list
    start: np.ndarray
    values: np.ndarray
    rss: float
    n_valid: int
    jacobian: np.ndarray
    converged: bool
    fit_time_s: float
    records: list = dataclasses.field(default_factory=list)
    fisher: dict = dataclasses.field(default=None)

    def __post_init__(self):
        if self.fisher is None:
            self.fisher = records_fisher(self)

    @property
    def rmse(self) -> float:
        """RMSE over every valid sensor sample of every record, K."""
        return math.sqrt(self.rss / max(self.n_valid, 1))

    def to_dict(self) -> dict:
        """JSON-ready summary: each parameter's start, value, standard error and 95 % interval, the
        records, convergence, the RMSE after the fit (K) and the identifiability warnings."""
        rows = [{"name": n, "unit": self.model.parameters[n].unit, "start": float(self.start[i]),
                 "value": float(self.values[i]), "std": self.fisher["std"][i], "ci95": list(self.fisher["ci95"][i])}
                for i, n in enumerate(self.names)]
        return {"model": self.model.name, "records": list(self.records), "parameters": rows,
                "converged": self.converged, "rmse_after": self.rmse,
                "condition_number": self.fisher["condition_number"], "warnings": self.fisher["warnings"]}


def _scaled(model: ThermalModel, name: str, factor: float):
    """(value(z), lower, upper) of the scaled decision variable of ``name``: ln(theta/theta0)
    within a factor ``factor`` of a positive start (and the physical bounds); linear from 0 for
    parameters that start at 0 (an effect switched off), scale the parameter's upper bound or 1."""
    parameter = model.parameters[name]
    start, lower, upper = parameter.value, parameter.lower, parameter.upper
    if start > 0:
        low = max(math.log(max(lower, 1e-300) / start) if lower > 0 else -math.log(factor), -math.log(factor))
        high = min(math.log(upper / start) if math.isfinite(upper) else math.log(factor), math.log(factor))
        return (lambda z: start * ca.exp(z) if isinstance(z, (ca.MX, ca.SX)) else start * math.exp(z)), low, high
    scale = upper if math.isfinite(upper) else 1.0
    return (lambda z: start + scale * z), (lower - start) / scale if math.isfinite(lower) else -1e3, \
        (upper - start) / scale if math.isfinite(upper) else 1e3


def _prior_weights(prior_weight, names: Sequence[str]) -> np.ndarray:
    """The prior's weight of each of ``names`` from a number (all alike) or a mapping by name."""
    if isinstance(prior_weight, Mapping):
        unknown = sorted(set(prior_weight) - set(names))
        if unknown:
            raise InputError("prior_weight", unknown[0], "names no fitted parameter")
        given = prior_weight
    else:
        given = {name: prior_weight for name in names}
    weights = []
    for name in names:
        weight = given.get(name, 0.0)
        try:
            weight = float(weight)
        except (TypeError, ValueError):
            raise InputError(f"prior_weight[{name}]", weight, "a weight must be a number >= 0") from None
        if not (math.isfinite(weight) and weight >= 0):
            raise InputError(f"prior_weight[{name}]", weight, "a weight must be a number >= 0")
        weights.append(weight)
    return np.array(weights)


def fit_records(model: ThermalModel, records: Sequence[Record], names: Sequence[str], factor: float = 30.0,
                prior_weight=0.0, max_iter: int = 60, output_weights=None) -> RecordsFit:
    """Fit ``names`` to all ``records`` at once (least squares, IPOPT, exact derivatives).

    Parameters
    ----------
    model : ThermalModel
    records : sequence of Record
        On one grid step each (steps may differ between records).
    names : sequence of str
        Parameters to fit.
    factor : float
        A positive parameter stays within this factor of its start value.
    prior_weight : float or mapping of str to float
        Weight (K² per unit of ln(theta/theta0)²) of a prior pulling each log-scaled parameter to
        its start: regularises parameters the data hardly see. 0: none. A mapping gives each
        parameter its own weight (fitted parameters it does not name have none).
    max_iter : int
        IPOPT iterations.
    output_weights : sequence of float, optional
        Weight of each model output in the sum of squares (default 1 each).

    Returns
    -------
    RecordsFit
    """
    if not records:
        raise InputError("records", records, "give at least one record")
    for name in names:
        if name not in model.parameters:
            raise InputError("params", name, f"not a parameter of {model.name}")
    started = time.perf_counter()
    n_y = len(model.output_names)
    weights = np.ones(n_y) if output_weights is None else np.asarray(output_weights, dtype=float)
    scalings = [_scaled(model, n, factor) for n in names]
    z = ca.MX.sym("z", len(names))
    theta = ca.vertcat(*[value(z[i]) for i, (value, _, _) in enumerate(scalings)])
    residuals, n_valid, trajectories = [], 0, {}
    for record in records:
        key = (record.dt_s, record.n_samples)
        if key not in trajectories:
            trajectories[key] = StateTrajectory(model, record.dt_s, record.n_samples, names)
        mask = np.isfinite(record.outputs)
        n_valid += int(mask.sum())
        target = np.where(mask, record.outputs, 0.0)
        predicted = trajectories[key].function(theta, ca.DM(record.x0), ca.DM(record.inputs))
        weight = ca.DM(mask * np.sqrt(weights)[:, None])
        residuals.append(ca.vec(weight * (predicted - ca.DM(target))))
    prior = _prior_weights(prior_weight, names)
    log_scaled = [i for i, n in enumerate(names) if model.parameters[n].value > 0 and prior[i] > 0]
    if log_scaled:
        residuals.append(ca.DM(np.sqrt(prior[log_scaled])) * z[log_scaled])
    residual = ca.vertcat(*residuals)
    jac = ca.jacobian(residual, z)
    lam_f = ca.MX.sym("lam_f")
    hessian = ca.Function("gauss_newton", [z, ca.MX.sym("p", 0), lam_f, ca.MX.sym("lam_g", 0)],
                          [ca.triu(lam_f * (jac.T @ jac))], ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])
    options = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.max_iter": int(max_iter),
               "ipopt.tol": 1e-8, "ipopt.acceptable_tol": 1e-5, "ipopt.acceptable_iter": 3,
               "ipopt.mu_strategy": "adaptive", "hess_lag": hessian}
    solver = ca.nlpsol("records_least_squares", "ipopt", {"x": z, "f": 0.5 * ca.sumsqr(residual)}, options)
    lower = [low for _, low, _ in scalings]
    upper = [high for _, _, high in scalings]
    solution = solver(x0=np.zeros(len(names)), lbx=lower, ubx=upper)
    z_opt = np.clip(np.asarray(solution["x"]).ravel(), lower, upper)
    values = np.array([float(value(float(z_opt[i]))) for i, (value, _, _) in enumerate(scalings)])
    for i, name in enumerate(names):  # round-off at a bound must not leave the physical range
        parameter = model.parameters[name]
        values[i] = min(max(values[i], parameter.lower), parameter.upper)
    jac_theta = ca.Function("jac_theta", [z], [ca.jacobian(residual, z), residual])
    J_z, r = (np.asarray(m) for m in jac_theta(z_opt))
    data_rows = slice(0, r.size - len(log_scaled))
    dtheta_dz = np.array([values[i] if model.parameters[n].value > 0 else
                          (scalings[i][0](1.0) - scalings[i][0](0.0)) for i, n in enumerate(names)])
    jacobian = J_z[data_rows] / dtheta_dz
    rss = float(np.sum(r[data_rows] ** 2))
    source = (f"least squares on {len(records)} record(s): " + ", ".join(r.name for r in records))
    fitted = model.with_parameters(provenance="fitted", source=source, **dict(zip(names, values)))
    return RecordsFit(fitted, list(names), np.array([model.parameters.value(n) for n in names]), values, rss,
                      n_valid, jacobian, bool(solver.stats()["success"]), time.perf_counter() - started,
                      [r.name for r in records])


def records_fisher(fit: RecordsFit) -> dict:
    """Standard errors, 95 % intervals and identifiability warnings of a :class:`RecordsFit`.

    As :func:`genthermal.diagnose.calibrate.fisher_summary`: covariance
    :math:`\\hat\\sigma^2 (J^\\top J)^{-1}` (pseudo-inverse), white-noise assumption (optimistic for
    residuals correlated in time), warnings for parameters the sensors do not see, pairs correlated
    above :data:`~genthermal.diagnose.calibrate.CORRELATION_LIMIT` and an ill-conditioned problem.
    """
    J, names = fit.jacobian, fit.names
    rows = np.any(J != 0, axis=1)
    J = J[rows] if rows.any() else J
    dof = max(fit.n_valid - J.shape[1], 1)
    sigma2 = fit.rss / dof
    norms = np.linalg.norm(J, axis=0)
    safe = np.where(norms > 0, norms, 1.0)
    Jn = J / safe
    condition = float(np.linalg.cond(Jn.T @ Jn))
    covariance = np.linalg.pinv(J.T @ J) * sigma2
    std = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
    outer = np.sqrt(np.outer(np.diag(covariance), np.diag(covariance)))
    correlation = np.divide(covariance, outer, out=np.zeros_like(covariance), where=outer > 0)
    warnings = [f"{names[i]} does not change the sensor temperatures: not identifiable"
                for i in range(len(names)) if norms[i] == 0]
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            if abs(correlation[i, j]) > CORRELATION_LIMIT:
                warnings.append(f"{names[i]} and {names[j]} are correlated ({correlation[i, j]:+.3f}): "
                                "the data cannot tell them apart; fix one of them")
    if condition > CONDITION_LIMIT:
        warnings.append(f"Fisher information is ill-conditioned (condition number {condition:.2e}): "
                        "not every fitted parameter is identifiable from these records")
    ci = [(float(v - 1.96 * s), float(v + 1.96 * s)) for v, s in zip(fit.values, std)]
    return {"std": std.tolist(), "ci95": ci, "condition_number": condition, "sigma_K": math.sqrt(sigma2),
            "warnings": warnings}
