"""Kalman filter on the linear design model (thesis 6.2).

:class:`KalmanFilter` updates then predicts each sample of the design model's exact zero-order
hold (thesis eqs. 6.12-6.15, with a Joseph-form covariance update and process noise as an
unknown heat flow at every node, :data:`DEFAULT_HEAT_NOISE_W`); missing sensor samples drop their
rows, and steady-state mode uses the Riccati gain (thesis 6.2.3).
:func:`initial_state_from_measurements` starts a model from the first measured temperatures.
Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import itertools

import casadi as ca
import numpy as np
import pandas as pd
import scipy.linalg
import scipy.signal

from ..errors import InputError
from ..machines import DEFAULT_MACHINE, MACHINES
from ..model import ThermalModel
from .filter_base import RecursiveFilter, checked_predict_steps

#: Measurement noise covariance of the default machine, K² (thesis eq. 6.10: stator winding, stator
#: iron); a filter's default R is its model's sensor variances (``spec.interface.sensors``).
THESIS_R_K2 = MACHINES[DEFAULT_MACHINE].interface.noise_variances_K2
#: Standard deviation of the unknown heat flow per node of the default Q, W.
DEFAULT_HEAT_NOISE_W = 30.0
#: Default initial standard deviation of every state, K.
DEFAULT_INITIAL_STD_K = 3.0
#: A measurement whose magnitude exceeds this (°C) counts as missing in the generated update; NaN
#: and inf fail the comparison and count as missing too.
_LARGEST_MEASUREMENT = 1e30  # fits single precision too (the Cortex-M build uses float)


def output_matrices(model: ThermalModel) -> tuple[np.ndarray, np.ndarray]:
    """Return ``(C, e)`` with :math:`y = Cx + e` for the model's sensor outputs.

    Raises
    ------
    InputError
        If an output depends on the inputs (D ≠ 0) or is not affine in the state; the filter and
        the prediction functions assume outputs that are node temperatures.
    """
    x, u = ca.SX.sym("x", model.n_states), ca.SX.sym("u", len(model.input_names))
    y = model.functions["outputs"](x, u, model.p0)
    C_expr = ca.jacobian(y, x)
    if ca.depends_on(y, u) or ca.depends_on(C_expr, x):
        raise InputError("model", model.name, "outputs must be affine in the state and independent of "
                         "the inputs (sensor temperatures of capacitive nodes)")
    C = np.asarray(ca.Function("C", [x, u], [C_expr])(0, 0))
    e = np.asarray(ca.Function("e", [x, u], [y])(0, 0)).ravel()
    return C, e


def initial_state_from_measurements(model: ThermalModel, y0, u0) -> np.ndarray:
    """A state consistent with the first measured temperatures (°C).

    Every node starts at the mean of the measured outputs ``y0`` (at the ambient temperature of
    ``u0`` when none is measured); each node carrying a sensor starts at its own measurement.
    """
    y0 = np.asarray(y0, dtype=float)
    measured = np.isfinite(y0)
    ambient = model.input_names.index(model.spec.interface.ambient_input)
    level = float(np.mean(y0[measured])) if measured.any() else float(u0[ambient])
    x0 = np.full(model.n_states, level)
    for value, node in zip(y0, model.spec.sensors.values()):
        if np.isfinite(value) and node in model.state_names:
            x0[model.state_names.index(node)] = value
    return x0


def measurement_noise_covariance(frame: pd.DataFrame, window_samples: int = 7, polyorder: int = 2) -> pd.DataFrame:
    r"""Estimate sensor noise variances from data (thesis 6.2.2), one per column of ``frame``.

    Each column is smoothed by a Savitzky-Golay filter (``window_samples`` long, polynomial order
    ``polyorder``; :func:`scipy.signal.savgol_filter`), the smooth signal is subtracted, and the
    variance of the residual is divided by :math:`1 - h_0`, :math:`h_0` the filter's centre
    weight: for white noise of variance :math:`\sigma^2` the residual of a least-squares smoother
    has variance :math:`\sigma^2(1 - h_0)`. Samples within half a window of a missing value are
    not used.

    The default window is short (7 samples, 70 s at 10 s) because the winding temperature bends
    sharply at every load step; a longer window leaves part of those bends in the residual and
    overestimates the noise (on synthetic thesis-mission data: by 8 % at 7 samples, 77 % at 21).

    Returns
    -------
    pandas.DataFrame
        Diagonal covariance (K²), index and columns the columns of ``frame``; sensors are taken as
        independent, as in thesis eq. 6.10.
    """
    if not (isinstance(window_samples, (int, np.integer)) and window_samples % 2 == 1
            and window_samples > polyorder + 2):
        raise InputError("window_samples", window_samples, f"must be an odd integer > {polyorder + 2}")
    centre_weight = scipy.signal.savgol_coeffs(window_samples, polyorder)[window_samples // 2]
    variances = []
    for name in frame.columns:
        values = frame[name].to_numpy(dtype=float)
        usable = np.convolve(np.isfinite(values), np.ones(window_samples), mode="same") == window_samples
        if usable.sum() < 2 * window_samples:
            raise InputError(f"sensors.{name}", f"{int(usable.sum())} usable samples",
                             f"too few samples for a {window_samples}-sample smoothing window")
        smooth = scipy.signal.savgol_filter(np.nan_to_num(values), window_samples, polyorder)
        residual = (values - smooth)[usable]
        variances.append(float(np.var(residual, ddof=1)) / (1.0 - centre_weight))
    return pd.DataFrame(np.diag(variances), index=list(frame.columns), columns=list(frame.columns))


@dataclasses.dataclass(frozen=True)
class Update:
    """One measurement update: filtered state and covariance, gain (n_states × n_outputs, zero
    columns for missing sensors) and innovation (NaN for missing sensors)."""

    x: np.ndarray
    P: np.ndarray | None
    gain: np.ndarray
    innovation: np.ndarray


class KalmanFilter(RecursiveFilter):
    """Kalman filter on the discrete design model (module docstring for the equations).

    Parameters
    ----------
    design_model : ThermalModel
        An affine model (the linear design model, :func:`genthermal.design.linear_design_model`).
    dt_s : float
        Filter step :math:`T_s`, s (the data must be sampled at this step).
    Q : array_like, optional
        Process noise covariance on the states, K² per step, (n_states × n_states) or a vector of
        its diagonal. Default :func:`heat_flow_process_noise` with :data:`DEFAULT_HEAT_NOISE_W`.
    R : array_like, optional
        Measurement noise covariance, K², (n_outputs × n_outputs) or its diagonal, in
        ``design_model.output_names`` order. Default the variances of the model's sensors
        (``spec.interface``; the thesis generator: eq. 6.10).
    P0 : array_like, optional
        Initial covariance, K²; default :data:`DEFAULT_INITIAL_STD_K` ² I.
    """

    def __init__(self, design_model: ThermalModel, dt_s: float = 10.0, Q=None, R=None, P0=None):
        discrete = design_model.discretise(dt_s)
        if not discrete.exact:
            raise InputError("design_model", design_model.name,
                             "the Kalman filter needs an affine model (use linear_design_model)")
        self.model = design_model
        self.dt_s = float(dt_s)
        self.A, self.B, self.c = discrete.A, discrete.B, discrete.c
        self._step = discrete.step
        self.C, self.e = output_matrices(design_model)
        self.state_names = list(design_model.state_names)
        self.output_names = list(design_model.output_names)
        nx, ny = len(self.state_names), len(self.output_names)
        self.Q = _covariance("Q", heat_flow_process_noise(design_model, dt_s) if Q is None else Q, nx)
        self.R = _covariance("R", design_model.spec.interface.noise_variances_K2 if R is None else R, ny)
        if np.min(np.linalg.eigvalsh(self.R)) <= 0:
            raise InputError("R", self.R.tolist(), "the measurement noise covariance must be positive definite")
        self.P0 = _covariance("P0", np.full(nx, DEFAULT_INITIAL_STD_K**2) if P0 is None else P0, nx)
        self.P_steady = scipy.linalg.solve_discrete_are(self.A.T, self.C.T, self.Q, self.R)

    # --- gains -----------------------------------------------------------------------------
    def steady_state_gain(self) -> np.ndarray:
        r"""Converged gain :math:`K_\infty = P_\infty C^T (C P_\infty C^T + R)^{-1}` (n_states ×
        n_outputs), :math:`P_\infty` from :func:`scipy.linalg.solve_discrete_are`."""
        return self._gain(self.P_steady, np.ones(len(self.output_names), dtype=bool))

    def _gain(self, P_pred: np.ndarray, measured: np.ndarray) -> np.ndarray:
        C, R = self.C[measured], self.R[np.ix_(measured, measured)]
        return np.linalg.solve(C @ P_pred @ C.T + R, C @ P_pred).T

    # --- one step --------------------------------------------------------------------------
    def update(self, x_pred, P, y) -> Update:
        """Correct the predicted state ``x_pred`` (°C) with the measurement ``y`` (°C, NaN = none).

        ``P`` is the predicted covariance :math:`P_k^-`; ``None`` selects steady-state mode
        (gain from :math:`P_\\infty`, no covariance returned).
        """
        x_pred, y = np.asarray(x_pred, dtype=float), np.asarray(y, dtype=float)
        measured = np.isfinite(y)
        innovation = np.where(measured, y - self.C @ x_pred - self.e, np.nan)
        gain = np.zeros((len(x_pred), len(y)))
        if not measured.any():
            return Update(x_pred, P, gain, innovation)
        gain[:, measured] = self._gain(self.P_steady if P is None else P, measured)
        x = x_pred + gain[:, measured] @ innovation[measured]
        if P is None:
            return Update(x, None, gain, innovation)
        I_KC = np.eye(len(x)) - gain[:, measured] @ self.C[measured]
        R = self.R[np.ix_(measured, measured)]
        P_filtered = I_KC @ P @ I_KC.T + gain[:, measured] @ R @ gain[:, measured].T
        return Update(x, P_filtered, gain, innovation)

    def predict(self, x, P, u) -> tuple[np.ndarray, np.ndarray | None]:
        """One step ahead: :math:`(Ax + Bu + c,\\ APA^T + Q)` (the model's exact step, loss floors
        applied); ``P`` None stays None."""
        x_next = np.asarray(self._step(x, np.asarray(u, dtype=float))).ravel()
        return x_next, None if P is None else self.A @ P @ self.A.T + self.Q

    # --- starting and forecasting ---------------------------------------------------------
    def initial_state(self, y0, u0) -> np.ndarray:
        """:func:`initial_state_from_measurements` of the first sample."""
        return initial_state_from_measurements(self.model, y0, u0)

    def forecast(self, x_start, U: np.ndarray) -> np.ndarray:
        """Outputs (°C, n × n_outputs) of the design model run open loop from ``x_start`` at sample
        0 with inputs ``U`` (n_inputs × n): row k is :math:`C x_k + e`."""
        x = np.asarray(x_start, dtype=float)
        Y = np.empty((U.shape[1], len(self.output_names)))
        for k in range(U.shape[1]):
            Y[k] = self.C @ x + self.e
            x, _ = self.predict(x, None, U[:, k])
        return Y

    # --- CasADi functions for code generation ----------------------------------------------
    def update_function(self) -> ca.Function:
        """``(x_pred, u, y) -> (x_filtered, x_next_pred)`` with the steady-state gains baked in.

        A non-finite ``y[i]`` (NaN: the sensor did not measure) is skipped exactly as
        :meth:`update` in steady-state mode skips it: the gain is that of the sensors that
        measured (one precomputed gain per subset of sensors), and with no sensor the state is
        only predicted. A NaN never reaches the state.
        """
        n_outputs = len(self.output_names)
        x_pred = ca.SX.sym("x_pred", len(self.state_names))
        u, y = ca.SX.sym("u", len(self.model.input_names)), ca.SX.sym("y", n_outputs)
        measured = [ca.fabs(y[i]) <= _LARGEST_MEASUREMENT for i in range(n_outputs)]  # false for NaN, inf
        expected = ca.DM(self.C) @ x_pred + ca.DM(self.e)
        innovation = ca.vertcat(*(ca.if_else(measured[i], y[i] - expected[i], 0.0) for i in range(n_outputs)))
        correction = ca.SX.zeros(len(self.state_names))
        for subset in itertools.product((False, True), repeat=n_outputs):
            mask = np.array(subset)
            if not mask.any():
                continue
            gain = np.zeros((len(self.state_names), n_outputs))
            gain[:, mask] = self._gain(self.P_steady, mask)
            indicator = 1.0
            for i, used in enumerate(subset):
                indicator = indicator * (measured[i] if used else 1.0 - measured[i])
            correction += indicator * (ca.DM(gain) @ innovation)
        x_filtered = x_pred + correction
        x_next = self._step(x_filtered, u)
        return ca.Function("kalman_update", [x_pred, u, y], [x_filtered, x_next],
                           ["x_pred", "u", "y"], ["x_filtered", "x_next_pred"])

    def predict_function(self, n_steps: int) -> ca.Function:
        """``(x, U) -> Y``: open-loop outputs after each of ``n_steps`` steps from state ``x``.

        ``U`` is (n_inputs × n_steps), ``Y[:, k]`` (°C) the outputs after step k + 1.
        """
        if not (isinstance(n_steps, (int, np.integer)) and n_steps >= 1):
            raise InputError("n_steps", n_steps, "must be an integer >= 1")
        x, U = ca.MX.sym("x", len(self.state_names)), ca.MX.sym("U", len(self.model.input_names), int(n_steps))
        X = self.model.discretise(self.dt_s).simulator(int(n_steps))(x, U)
        Y = ca.DM(self.C) @ X + ca.repmat(ca.DM(self.e), 1, int(n_steps))
        return ca.Function(f"predict_{int(n_steps)}", [x, U], [Y], ["x", "U"], ["Y"])


def heat_flow_process_noise(design_model: ThermalModel, dt_s: float,
                            heat_noise_W: float = DEFAULT_HEAT_NOISE_W) -> np.ndarray:
    r"""Diagonal :math:`Q = \mathrm{diag}((T_s\sigma_P/C_i)^2)` in K² per step: an unknown heat flow
    of standard deviation :math:`\sigma_P` (W) at every capacitive node of heat capacity
    :math:`C_i` (J/K), held over the step."""
    return np.diag((dt_s * heat_noise_W / design_model.heat_capacities()) ** 2)


def _covariance(name: str, value, size: int) -> np.ndarray:
    """A symmetric positive semi-definite (size × size) matrix from a matrix or its diagonal."""
    matrix = np.asarray(value, dtype=float)
    if matrix.ndim == 1:
        matrix = np.diag(matrix)
    if matrix.shape != (size, size) or not np.all(np.isfinite(matrix)):
        raise InputError(name, f"shape {matrix.shape}",
                         f"expected a finite ({size} × {size}) matrix or {size} diagonal values")
    tolerance = 1e-12 * max(1.0, np.abs(matrix).max())
    if not np.allclose(matrix, matrix.T) or np.min(np.linalg.eigvalsh(matrix)) < -tolerance:
        raise InputError(name, matrix.tolist(), "a covariance must be symmetric positive semi-definite")
    return matrix


def embedded_functions(design_model: ThermalModel, dt_s: float = 10.0, predict_steps: int = 180) -> dict:
    """The filter's CasADi functions for the generated C library (steady-state gain).

    Parameters
    ----------
    design_model : ThermalModel
        The linear design model the filter runs on.
    dt_s : float
        Filter step, s.
    predict_steps : int
        Horizon of the n-step prediction, steps (default 180: 30 min at 10 s).

    Returns
    -------
    dict
        ``{"kalman_update": (x_pred, u, y) -> (x_filtered, x_next_pred),
        "predict": (x, U) -> Y}`` for :func:`genthermal.codegen.generate_c`'s ``extra_functions``.
    """
    kalman = KalmanFilter(design_model, dt_s=dt_s)
    return {"kalman_update": kalman.update_function(), "predict": kalman.predict_function(checked_predict_steps(predict_steps))}

