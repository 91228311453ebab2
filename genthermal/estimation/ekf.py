r"""Extended Kalman filter on the nonlinear model, with disturbance states (offset-free prediction).

The filter state is :math:`z = (x, d, m)`: the node temperatures :math:`x` (°C), one unknown
heat flow :math:`d_j` (W) into each sensor node (for the thesis generator: into the stator winding
and into the stator iron) and, for the same nodes, one unknown loss :math:`m_j` (W at rated
current) that scales with the load squared, :math:`\ell(u) = \overline{I^2}/I_{rated}^2` (mean
over the phases). They stand for what the model lacks: :math:`d` for a blockage or a wrong
convection coefficient, :math:`m` for a wrong copper or load-dependent iron loss, which a
constant heat flow cannot carry from one load to another. They enter the nodes as
:math:`\dot x_i \mathrel{+}= (d_j + \ell(u) m_j)/C_i` and drift as random walks,

.. math::
    x_{k+1} = \Phi(x_k, u_k, M (d_k + \ell(u_k) m_k)) + w_k, \qquad
    (d, m)_{k+1} = (d, m)_k + \eta_k, \qquad y_k = C x_k + e + v_k,

:math:`\Phi` the *same* discrete step that simulation uses (:attr:`DiscreteModel.forced_step` of
:mod:`genthermal.discretise`, with the forcing :math:`w = M(d + \ell(u) m)`, :math:`M_{ij} = 1/C_i`
for node i of disturbance j), so filter and simulation cannot drift apart. The Jacobian
:math:`F_k = \partial z_{k+1}/\partial z_k` at :math:`(\hat z_k, u_k)` is exact
(CasADi automatic differentiation of that step), as is :math:`H = \partial y/\partial z = (C, 0)`.
Update and prediction are those of :mod:`genthermal.estimation.kalman` with :math:`F_k` in place
of :math:`A` (Joseph-form covariance update; missing sensors drop their rows).

Process noise, in K² and W² per step:

* nodes: :math:`Q_x = \mathrm{diag}((T_s\sigma_P/C_i)^2)` with :math:`\sigma_P` =
  :data:`DEFAULT_NODE_HEAT_NOISE_W` (an unmodelled heat flow at every node, as the linear filter,
  but smaller because the systematic part now has its own states);
* disturbances: :math:`Q_d = \sigma_d^2\,T_s/3600\,I`, a random walk that moves by
  :math:`\sigma_d` = :data:`DEFAULT_DISTURBANCE_DRIFT_W` (W) in one hour, and the same for
  :math:`m` with :data:`DEFAULT_LOAD_SCALED_DRIFT_W`; initial standard deviation
  :data:`DEFAULT_INITIAL_DISTURBANCE_W` for both. The scale: the winding's copper loss at rated
  current is about 180 W; a model calibrated on a healthy record is typically a few W to a few
  tens of W off at a load it was not fitted at, and the thesis's large blockage removes some tens
  of W of cooling.

The values were chosen by measurement on the plants of ``benchmarks/bench_prediction.py``
(calibrated model, three records it was not fitted on; winding RMS at 15/30/60 min). With the
constant heat flows alone (15 W/h, initial 30 W) the varying-load record gave 0.48/1.06/1.03 K,
worse than the open loop's 0.57/0.48/0.49 K at 30-60 min: the heat flow learnt at one load was
carried to the next. Adding :math:`m` (15 W/h) with initial 10 W and the constant walk at 8 W/h
gives 0.41/0.68/0.55 K there, 0.17/0.34/0.43 K (was 0.19/0.39/0.57) on the Fig. 3.2 flight and
an unchanged 1.0/2.6/6.3 K on the large blockage. A larger node noise (10 W) brings the
varying-load record to 0.39/0.53/0.48 K but the blockage to 1.2/2.8/6.5 K; an initial 30 W on
:math:`m` lets it wander (30 min: 1.2 K). A disturbance that decays (first-order Markov, 10-30
min) loses the blockage (30 min: 6.6-9.6 K); unknown conductances to the coolant were worse on
the Fig. 3.2 flight (60 min: 0.7-1.3 K). Both are left out.

Predictions hold the disturbance at its last estimate (:meth:`ExtendedKalmanFilter.forecast`):
a constant model error is carried into the future, which is what makes them offset-free.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import scipy.linalg

from ..discretise import check_step_accuracy
from ..errors import InputError
from ..model import ThermalModel
from .filter_base import RecursiveFilter, checked_predict_steps
from .kalman import (
    DEFAULT_INITIAL_STD_K,
    Update,
    _covariance,
    heat_flow_process_noise,
    initial_state_from_measurements,
    output_matrices,
)

#: Standard deviation of the unmodelled heat flow at every node, W (held over a step).
DEFAULT_NODE_HEAT_NOISE_W = 5.0
#: How far each disturbance heat flow may drift in one hour (1 sigma of the random walk), W.
DEFAULT_DISTURBANCE_DRIFT_W = 8.0
#: How far each load-scaled disturbance (W at rated current, scaled by the load squared) may drift
#: in one hour, W; 0 leaves those states out.
DEFAULT_LOAD_SCALED_DRIFT_W = 15.0
#: Initial standard deviation of each disturbance heat flow, W.
DEFAULT_INITIAL_DISTURBANCE_W = 10.0


def node_heat_capacities(model: ThermalModel) -> np.ndarray:
    """Heat capacity :math:`C_i` (J/K) of every state node, in ``state_names`` order."""
    return model.heat_capacities()


class ExtendedKalmanFilter(RecursiveFilter):
    """Extended Kalman filter with disturbance heat flows (module docstring for the equations).

    Same interface as :class:`~genthermal.estimation.kalman.KalmanFilter`: :meth:`update`,
    :meth:`predict`, :meth:`run`, :meth:`forecast`; the state has the model's nodes (°C) first and
    the disturbances (W) after them.

    Parameters
    ----------
    model : ThermalModel
        Any model: the nonlinear simulation model, a calibrated or diagnosed model file, or the
        linear design model (then :math:`F` is constant).
    dt_s : float
        Filter step, s (the data must be sampled at this step); checked by
        :func:`~genthermal.discretise.check_step_accuracy`.
    disturbance_nodes : sequence of str, optional
        Nodes that receive an unknown heat flow; default the sensor nodes
        (``model.spec.sensors``), one per measured output, so the disturbances are observable.
    load_scaled_drift_W : float
        Hourly drift of each load-scaled loss :math:`m_j`, W at rated current; 0 leaves those
        states out.
    node_heat_noise_W, disturbance_drift_W, initial_disturbance_W : float
        :math:`\\sigma_P`, :math:`\\sigma_d` and the initial standard deviation of :math:`d`
        and :math:`m`, W.
    R : array_like, optional
        Measurement noise covariance, K², output order; default thesis eq. 6.10.
    P0 : array_like, optional
        Initial covariance of the whole state; default :data:`DEFAULT_INITIAL_STD_K` ² on the
        nodes and ``initial_disturbance_W`` ² on the disturbances.
    """

    def __init__(self, model: ThermalModel, dt_s: float = 10.0, disturbance_nodes=None,
                 load_scaled_drift_W: float = DEFAULT_LOAD_SCALED_DRIFT_W,
                 node_heat_noise_W: float = DEFAULT_NODE_HEAT_NOISE_W,
                 disturbance_drift_W: float = DEFAULT_DISTURBANCE_DRIFT_W,
                 initial_disturbance_W: float = DEFAULT_INITIAL_DISTURBANCE_W, R=None, P0=None):
        for name, value in (("node_heat_noise_W", node_heat_noise_W), ("disturbance_drift_W", disturbance_drift_W),
                            ("load_scaled_drift_W", load_scaled_drift_W),
                            ("initial_disturbance_W", initial_disturbance_W)):
            if not (np.isfinite(value) and value >= 0):
                raise InputError(name, value, "must be a heat flow in W >= 0")
        check_step_accuracy(model, dt_s)
        discrete = model.discretise(dt_s)
        self.model, self.dt_s = model, float(dt_s)
        nodes = list(model.spec.sensors.values()) if disturbance_nodes is None else list(disturbance_nodes)
        unknown = [node for node in nodes if node not in model.state_names]
        if unknown or not nodes:
            raise InputError("disturbance_nodes", unknown or nodes,
                             f"must be capacitive nodes of {model.name}: {', '.join(model.state_names)}")
        self.disturbance_nodes = nodes
        self.load_scaled = load_scaled_drift_W > 0
        self.disturbance_names = tuple(f"q_{node}" for node in nodes) + \
            (tuple(f"q_load_{node}" for node in nodes) if self.load_scaled else ())
        self.output_names = list(model.output_names)
        self.state_names = [*model.state_names, *self.disturbance_names]
        nx, nd, ny = model.n_states, len(self.disturbance_names), len(self.output_names)
        self.rated_current_A = float(model.spec.rated_current_A)
        capacity = node_heat_capacities(model)
        self.M = np.zeros((nx, len(nodes)))
        for j, node in enumerate(nodes):
            index = model.state_names.index(node)
            self.M[index, j] = 1.0 / capacity[index]
        C, self.e = output_matrices(model)
        self.C = C
        self.H = np.hstack([C, np.zeros((ny, nd))])
        self.transition, self.state_step = self._transition_functions(discrete)
        drift = np.repeat([disturbance_drift_W, load_scaled_drift_W][:1 + self.load_scaled], len(nodes))
        self.Q = scipy.linalg.block_diag(heat_flow_process_noise(model, dt_s, node_heat_noise_W),
                                         np.diag(drift**2 * self.dt_s / 3600.0))
        self.R = _covariance("R", model.spec.interface.noise_variances_K2 if R is None else R, ny)
        if np.min(np.linalg.eigvalsh(self.R)) <= 0:
            raise InputError("R", self.R.tolist(), "the measurement noise covariance must be positive definite")
        default_P0 = np.concatenate([np.full(nx, DEFAULT_INITIAL_STD_K**2), np.full(nd, initial_disturbance_W**2)])
        self.P0 = _covariance("P0", default_P0 if P0 is None else P0, nx + nd)
        self._forecasters: dict = {}

    def _transition_functions(self, discrete) -> tuple[ca.Function, ca.Function]:
        """``(z, u) -> (z_next, F)``, the discrete step with the disturbances and its exact
        Jacobian, and ``(z, u) -> z_next`` alone (for forecasts)."""
        nx, nd, n_nodes = self.model.n_states, len(self.disturbance_names), self.M.shape[1]
        z, u = ca.SX.sym("z", nx + nd), ca.SX.sym("u", len(self.model.input_names))
        heat = z[nx:nx + n_nodes]
        if self.load_scaled:
            phases = [u[self.model.input_names.index(name)] for name in self.model.spec.interface.load_currents]
            load_squared = sum(current**2 for current in phases) / (len(phases) * self.rated_current_A**2)
            heat = heat + load_squared * z[nx + n_nodes:]
        z_next = ca.vertcat(discrete.forced_step(z[:nx], u, ca.DM(self.M) @ heat), z[nx:])
        return (ca.Function("ekf_transition", [z, u], [z_next, ca.jacobian(z_next, z)], ["z", "u"], ["z_next", "F"]),
                ca.Function("ekf_state_step", [z, u], [z_next], ["z", "u"], ["z_next"]))

    # --- one step --------------------------------------------------------------------------
    def update(self, x_pred, P, y) -> Update:
        """Correct the predicted state ``x_pred`` (nodes °C, disturbances W) with the measurement
        ``y`` (°C, NaN = none); ``P`` is the predicted covariance (required: no steady state)."""
        if P is None:
            raise InputError("P", None, "the extended Kalman filter has no steady-state gain; pass a covariance")
        z, y = np.asarray(x_pred, dtype=float), np.asarray(y, dtype=float)
        measured = np.isfinite(y)
        innovation = np.where(measured, y - self.H @ z - self.e, np.nan)
        gain = np.zeros((len(z), len(y)))
        if not measured.any():
            return Update(z, P, gain, innovation)
        H, R = self.H[measured], self.R[np.ix_(measured, measured)]
        gain[:, measured] = np.linalg.solve(H @ P @ H.T + R, H @ P).T
        K = gain[:, measured]
        I_KH = np.eye(len(z)) - K @ H
        return Update(z + K @ innovation[measured], I_KH @ P @ I_KH.T + K @ R @ K.T, gain, innovation)

    def predict(self, x, P, u) -> tuple[np.ndarray, np.ndarray]:
        """One step ahead: :math:`(\\Phi(z, u),\\ F P F^T + Q)` with the exact Jacobian :math:`F`."""
        z_next, F = self.transition(np.asarray(x, dtype=float), np.asarray(u, dtype=float))
        F = np.asarray(F)
        return np.asarray(z_next).ravel(), None if P is None else F @ P @ F.T + self.Q

    # --- starting and forecasting ----------------------------------------------------------
    def initial_state(self, y0, u0) -> np.ndarray:
        """Nodes from :func:`initial_state_from_measurements`, disturbances zero."""
        return np.concatenate([initial_state_from_measurements(self.model, y0, u0),
                               np.zeros(len(self.disturbance_names))])

    def forecast(self, x_start, U: np.ndarray) -> np.ndarray:
        """Outputs (°C, n × n_outputs) from the filter state ``x_start`` run open loop with inputs
        ``U`` (n_inputs × n), the disturbances held: row k is :math:`C x_k + e`."""
        n = U.shape[1]
        z0 = np.asarray(x_start, dtype=float)
        if n not in self._forecasters:
            self._forecasters[n] = self.state_step.mapaccum("forecast", n)
        Z = np.column_stack([z0, np.asarray(self._forecasters[n](z0, U))[:, :-1]]) if n > 1 else z0[:, None]
        return (self.H @ Z).T + self.e

    # --- CasADi functions for code generation ----------------------------------------------
    def update_function(self) -> ca.Function:
        """``(z_pred, P_pred, u, y, measured) -> (z, P, z_next_pred, P_next_pred)``: one update
        with the measurement and the prediction to the next sample, as :meth:`update` then
        :meth:`predict`.

        ``measured`` holds 1 for each sensor read at this sample and 0 for a missing one (its
        ``y`` is then ignored): the sensor's row of :math:`H` and its innovation are zeroed and its
        row and column of :math:`R` replaced by the identity's, which gives exactly the update
        without that sensor.
        """
        nz, ny = len(self.state_names), len(self.output_names)
        z, P = ca.SX.sym("z_pred", nz), ca.SX.sym("P_pred", nz, nz)
        u, y, measured = ca.SX.sym("u", len(self.model.input_names)), ca.SX.sym("y", ny), ca.SX.sym("measured", ny)
        mask = ca.diag(measured)
        H = mask @ ca.DM(self.H)
        R = mask @ ca.DM(self.R) @ mask + ca.diag(1 - measured)
        innovation = measured * (y - ca.DM(self.H) @ z - ca.DM(self.e))
        K = ca.solve(H @ P @ H.T + R, H @ P).T
        z_filtered = z + K @ innovation
        I_KH = ca.DM.eye(nz) - K @ H
        P_filtered = I_KH @ P @ I_KH.T + K @ R @ K.T
        z_next, F = self.transition(z_filtered, u)
        P_next = F @ P_filtered @ F.T + ca.DM(self.Q)
        return ca.Function("ekf_update", [z, P, u, y, measured], [z_filtered, P_filtered, z_next, P_next],
                           ["z_pred", "P_pred", "u", "y", "measured"], ["z", "P", "z_next_pred", "P_next_pred"])

    def predict_function(self, n_steps: int) -> ca.Function:
        """``(z, U) -> Y``: outputs after each of ``n_steps`` steps from the filter state ``z``, the
        disturbances held (:meth:`forecast`); ``U`` is (n_inputs × n_steps), ``Y[:, k]`` (°C) the
        outputs after step k + 1."""
        if not (isinstance(n_steps, (int, np.integer)) and n_steps >= 1):
            raise InputError("n_steps", n_steps, "must be an integer >= 1")
        z, U = ca.MX.sym("z", len(self.state_names)), ca.MX.sym("U", len(self.model.input_names), int(n_steps))
        Z = self.state_step.mapaccum("forecast", int(n_steps))(z, U)
        Y = ca.DM(self.H) @ Z + ca.repmat(ca.DM(self.e), 1, int(n_steps))
        return ca.Function(f"ekf_predict_{int(n_steps)}", [z, U], [Y], ["z", "U"], ["Y"])


def embedded_functions(model: ThermalModel, dt_s: float = 10.0, predict_steps: int = 180) -> dict:
    """The EKF's CasADi functions for the generated C library.

    Parameters
    ----------
    model : ThermalModel
        The model the filter runs on (its own discrete step, with disturbance heat flows).
    dt_s : float
        Filter step, s.
    predict_steps : int
        Horizon of the n-step prediction, steps (default 180: 30 min at 10 s).

    Returns
    -------
    dict
        ``{"ekf_update": ExtendedKalmanFilter.update_function(), "ekf_predict":
        ExtendedKalmanFilter.predict_function(predict_steps)}`` for
        :func:`genthermal.codegen.generate_c`'s ``extra_functions``.
    """
    ekf = ExtendedKalmanFilter(model, dt_s)
    return {"ekf_update": ekf.update_function(), "ekf_predict": ekf.predict_function(checked_predict_steps(predict_steps))}
