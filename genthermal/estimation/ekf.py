r"""Extended Kalman filter on the nonlinear model, with disturbance states (offset-free prediction).

:class:`ExtendedKalmanFilter` estimates the node temperatures together with unknown heat flows at
the sensor nodes (constant, load-scaled and coolant-scaled) and an offset of the coolant inlet. It
steps the same discrete model as simulation, with exact CasADi Jacobians, and an innovation change
test opens the disturbance covariance when a fault appears. Equations, noise settings and how
they were measured: ``docs/guide/extended-kalman-filter.md``.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import scipy.linalg

from ..discretise import check_step_accuracy
from ..errors import InputError
from ..model import ThermalModel
from .change_detection import InnovationChangeDetector, forgetting_factor
from .disturbance_prior import DisturbancePrior
from .filter_base import RecursiveFilter, checked_predict_steps
from .kalman import (
    DEFAULT_INITIAL_STD_K,
    Update,
    _LARGEST_MEASUREMENT,
    _covariance,
    heat_flow_process_noise,
    initial_state_from_measurements,
    output_matrices,
)

#: Standard deviation of the unmodelled heat flow at every node, W (held over a step).
DEFAULT_NODE_HEAT_NOISE_W = 5.0
#: How far each disturbance heat flow may drift in one hour (1 sigma of the random walk), W.
DEFAULT_DISTURBANCE_DRIFT_W = 1.0
#: How far each load-scaled disturbance (W at rated current, scaled by the load squared) may drift
#: in one hour, W; 0 leaves those states out.
DEFAULT_LOAD_SCALED_DRIFT_W = 2.0
#: Initial standard deviation of each disturbance heat flow, W.
DEFAULT_INITIAL_DISTURBANCE_W = 10.0
#: How far each coolant-scaled disturbance (W at COOLANT_REFERENCE_RISE_K above the coolant inlet)
#: may drift in one hour, W; 0 leaves those states out.
DEFAULT_COOLANT_DRIFT_W = 1.0
#: Temperature rise above the coolant inlet at which a coolant-scaled disturbance is quoted, K.
COOLANT_REFERENCE_RISE_K = 50.0
#: How far the coolant inlet offset may drift in one hour, K; 0 leaves it out.
DEFAULT_INLET_DRIFT_K = 0.2
#: Initial standard deviation of the coolant inlet offset, K.
DEFAULT_INITIAL_INLET_K = 2.0
#: Alarm level of the innovation change test (chi-square, n_y dof); None: no change detection.
DEFAULT_CHANGE_THRESHOLD = 13.8
#: Window of the innovation change test (the window with the same variance as its weighted mean), min.
DEFAULT_CHANGE_WINDOW_MIN = 5.0
#: Standard deviation added to each disturbance when a change is detected (W; inlet K).
DEFAULT_JUMP_STD = {"constant": 10.0, "load": 10.0, "coolant": 80.0, "inlet": 20.0}
#: The disturbance bases, in state order.
DISTURBANCE_BASES = ("constant", "load", "coolant")
#: State name prefix of each basis (then the node name).
BASIS_PREFIX = {"constant": "q_", "load": "q_load_", "coolant": "q_coolant_"}


def node_heat_capacities(model: ThermalModel) -> np.ndarray:
    """Heat capacity :math:`C_i` (J/K) of every state node, in ``state_names`` order."""
    return model.heat_capacities()


class ExtendedKalmanFilter(RecursiveFilter):
    """Extended Kalman filter with disturbance heat flows (equations: docs/guide/extended-kalman-filter.md).

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
    load_scaled_drift_W, coolant_drift_W : float
        Hourly drift of each load-scaled flow (W at rated current) and each coolant-scaled flow (W
        at :data:`COOLANT_REFERENCE_RISE_K` above the inlet); 0 leaves those states out.
    node_heat_noise_W, disturbance_drift_W, initial_disturbance_W : float
        :math:`\\sigma_P`, the hourly drift of each constant heat flow and the initial standard
        deviation of every heat-flow coefficient, W.
    inlet_drift_K, initial_inlet_K : float
        Hourly drift and initial standard deviation of the coolant inlet offset ``dT_inlet``, K;
        a drift of 0 leaves it out.
    change_threshold : float or None
        Alarm level of the innovation change test (:mod:`~genthermal.estimation.change_detection`),
        a :math:`\\chi^2_{n_y}` value; None: no test (the disturbances only drift).
    change_window_min : float
        Window of that test, min.
    jump_std : dict, optional
        Standard deviation added on an alarm per basis (``constant``, ``load``, ``coolant``: W;
        ``inlet``: K); missing keys take :data:`DEFAULT_JUMP_STD`.
    R : array_like, optional
        Measurement noise covariance, K², output order; default thesis eq. 6.10.
    P0 : array_like, optional
        Initial covariance of the whole state; default :data:`DEFAULT_INITIAL_STD_K` ² on the
        nodes, ``initial_disturbance_W`` ² on the heat-flow coefficients and ``initial_inlet_K`` ²
        on the inlet offset, or the prior's covariance on the disturbances (below).
    disturbance_prior : DisturbancePrior, None or "model"
        Where the disturbance states start (:mod:`~genthermal.estimation.disturbance_prior`): its
        mean, and its covariance unless ``P0`` is given. Default ``"model"``: the prior the model
        carries (``model.disturbance_prior``, written by ``calibrate``), if any; None: zero mean.
        A prior learnt on other disturbance states (another basis set) is not used
        (:attr:`prior_used` is then False).
    """

    def __init__(self, model: ThermalModel, dt_s: float = 10.0, disturbance_nodes=None,
                 load_scaled_drift_W: float = DEFAULT_LOAD_SCALED_DRIFT_W,
                 node_heat_noise_W: float = DEFAULT_NODE_HEAT_NOISE_W,
                 disturbance_drift_W: float = DEFAULT_DISTURBANCE_DRIFT_W,
                 initial_disturbance_W: float = DEFAULT_INITIAL_DISTURBANCE_W, R=None, P0=None,
                 coolant_drift_W: float = DEFAULT_COOLANT_DRIFT_W,
                 inlet_drift_K: float = DEFAULT_INLET_DRIFT_K, initial_inlet_K: float = DEFAULT_INITIAL_INLET_K,
                 change_threshold: float | None = DEFAULT_CHANGE_THRESHOLD,
                 change_window_min: float = DEFAULT_CHANGE_WINDOW_MIN, jump_std=None,
                 disturbance_prior="model"):
        for name, value in (("node_heat_noise_W", node_heat_noise_W), ("disturbance_drift_W", disturbance_drift_W),
                            ("load_scaled_drift_W", load_scaled_drift_W), ("coolant_drift_W", coolant_drift_W),
                            ("initial_disturbance_W", initial_disturbance_W), ("inlet_drift_K", inlet_drift_K),
                            ("initial_inlet_K", initial_inlet_K)):
            if not (np.isfinite(value) and value >= 0):
                raise InputError(name, value, "must be >= 0 (a heat flow in W; the inlet offset in K)")
        check_step_accuracy(model, dt_s)
        discrete = model.discretise(dt_s)
        self.model, self.dt_s = model, float(dt_s)
        nodes = list(model.spec.sensors.values()) if disturbance_nodes is None else list(disturbance_nodes)
        unknown = [node for node in nodes if node not in model.state_names]
        if unknown or not nodes:
            raise InputError("disturbance_nodes", unknown or nodes,
                             f"must be capacitive nodes of {model.name}: {', '.join(model.state_names)}")
        self.disturbance_nodes = nodes
        drifts = {"constant": disturbance_drift_W, "load": load_scaled_drift_W, "coolant": coolant_drift_W}
        #: The bases in use, in state order: ``"constant"`` always, ``"load"`` and ``"coolant"``
        #: when their drift is > 0 (module docstring).
        self.bases = tuple(b for b in DISTURBANCE_BASES if b == "constant" or drifts[b] > 0)
        self.load_scaled = "load" in self.bases
        self.inlet_offset = inlet_drift_K > 0
        self.disturbance_names = tuple(f"{BASIS_PREFIX[b]}{node}" for b in self.bases for node in nodes) + \
            (("dT_inlet",) if self.inlet_offset else ())
        self.output_names = list(model.output_names)
        self.state_names = [*model.state_names, *self.disturbance_names]
        nx, nd, ny = model.n_states, len(self.disturbance_names), len(self.output_names)
        self.rated_current_A = float(model.spec.rated_current_A)
        self.coolant_input = model.spec.interface.coolant_input
        capacity = node_heat_capacities(model)
        self.M = np.zeros((nx, len(nodes)))
        for j, node in enumerate(nodes):
            index = model.state_names.index(node)
            self.M[index, j] = 1.0 / capacity[index]
        C, self.e = output_matrices(model)
        self.C = C
        self.H = np.hstack([C, np.zeros((ny, nd))])
        self.transition, self.state_step = self._transition_functions(discrete)
        drift = np.concatenate([np.repeat([drifts[b] for b in self.bases], len(nodes)),
                                [inlet_drift_K] if self.inlet_offset else []])
        self.Q = scipy.linalg.block_diag(heat_flow_process_noise(model, dt_s, node_heat_noise_W),
                                         np.diag(drift**2 * self.dt_s / 3600.0))
        self.R = _covariance("R", model.spec.interface.noise_variances_K2 if R is None else R, ny)
        if np.min(np.linalg.eigvalsh(self.R)) <= 0:
            raise InputError("R", self.R.tolist(), "the measurement noise covariance must be positive definite")
        default_P0 = np.concatenate([np.full(nx, DEFAULT_INITIAL_STD_K**2),
                                     np.full(len(self.bases) * len(nodes), initial_disturbance_W**2),
                                     [initial_inlet_K**2] if self.inlet_offset else []])
        prior = model.disturbance_prior if isinstance(disturbance_prior, str) and disturbance_prior == "model" \
            else disturbance_prior
        if prior is not None and not isinstance(prior, DisturbancePrior):
            raise InputError("disturbance_prior", prior, "must be a DisturbancePrior, None or 'model'")
        #: True when the filter starts from a calibration's disturbance prior (its states match).
        self.prior_used = prior is not None and tuple(prior.names) == self.disturbance_names
        self.initial_disturbances = prior.mean.copy() if self.prior_used else np.zeros(nd)
        if P0 is None:
            default_P0 = np.diag(default_P0)
            if self.prior_used:
                default_P0[nx:, nx:] = prior.covariance
        self.P0 = _covariance("P0", default_P0 if P0 is None else P0, nx + nd)
        self._forecasters: dict = {}
        if change_threshold is not None and not (np.isfinite(change_threshold) and change_threshold > 0):
            raise InputError("change_threshold", change_threshold, "must be a positive chi-square value or None")
        if not (np.isfinite(change_window_min) and change_window_min * 60.0 >= dt_s):
            raise InputError("change_window_min", change_window_min, f"must be at least one step ({dt_s:g} s)")
        unknown_bases = sorted(set(jump_std or {}) - set(DEFAULT_JUMP_STD))
        if unknown_bases:
            raise InputError("jump_std", unknown_bases[0], f"unknown basis; use {', '.join(DEFAULT_JUMP_STD)}")
        jump = dict(DEFAULT_JUMP_STD, **(jump_std or {}))
        if not all(np.isfinite(v) and v >= 0 for v in jump.values()):
            raise InputError("jump_std", jump, "each must be >= 0 (W; inlet K)")
        self.change_threshold, self.change_window_min = change_threshold, float(change_window_min)
        self.jump_covariance = np.diag(np.concatenate([
            np.zeros(nx), np.repeat([jump[b] for b in self.bases], len(nodes)),
            [jump["inlet"]] if self.inlet_offset else []]) ** 2)

    def change_detector(self):
        """The jump detector of :mod:`~genthermal.estimation.change_detection` with this filter's
        settings, or None when ``change_threshold`` is None."""
        if self.change_threshold is None:
            return None
        return InnovationChangeDetector(self.change_window_samples, self.change_threshold, self.jump_covariance)

    @property
    def change_window_samples(self) -> int:
        """:math:`W` of the change test, samples."""
        return max(1, int(round(self.change_window_min * 60.0 / self.dt_s)))

    def basis_values(self, x_nodes, u):
        """:math:`\\phi_b(x, u)` of every disturbance state (state order): 1 for ``constant``,
        :math:`\\ell(u)` for ``load``, :math:`(x_j - T_{in})/\\Delta T_{ref}` for ``coolant``.
        Works on numbers and on CasADi symbols."""
        values = []
        for basis in self.bases:
            for node in self.disturbance_nodes:
                if basis == "constant":
                    values.append(1.0)
                elif basis == "load":
                    phases = [u[self.model.input_names.index(name)]
                              for name in self.model.spec.interface.load_currents]
                    values.append(sum(current**2 for current in phases) / (len(phases) * self.rated_current_A**2))
                else:
                    inlet = u[self.model.input_names.index(self.coolant_input)]
                    values.append((x_nodes[self.model.state_names.index(node)] - inlet) / COOLANT_REFERENCE_RISE_K)
        return values

    def _transition_functions(self, discrete) -> tuple[ca.Function, ca.Function]:
        """``(z, u) -> (z_next, F)``, the discrete step with the disturbances and its exact
        Jacobian, and ``(z, u) -> z_next`` alone (for forecasts)."""
        nx, nd, n_nodes = self.model.n_states, len(self.disturbance_names), self.M.shape[1]
        z, u = ca.SX.sym("z", nx + nd), ca.SX.sym("u", len(self.model.input_names))
        phi = self.basis_values(z[:nx], u)  # the coolant basis uses the measured inlet
        heat = ca.vertcat(*[sum(z[nx + b * n_nodes + j] * phi[b * n_nodes + j] for b in range(len(self.bases)))
                            for j in range(n_nodes)])
        u_model = u  # the inputs the model sees: the inlet raised by the offset state, if any
        if self.inlet_offset:
            u_model = u + z[-1] * ca.DM([float(name == self.coolant_input) for name in self.model.input_names])
        z_next = ca.vertcat(discrete.forced_step(z[:nx], u_model, ca.DM(self.M) @ heat), z[nx:])
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
        """Nodes from :func:`initial_state_from_measurements`, disturbances at the prior's mean
        (zero without a prior)."""
        return np.concatenate([initial_state_from_measurements(self.model, y0, u0), self.initial_disturbances])

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
        """``(z_pred, P_pred, u, y, measured, change_mean) -> (z, P, z_next_pred, P_next_pred,
        change_mean_next, change_statistic)``: one update with the measurement, the innovation
        change test, and the prediction to the next sample, as :meth:`run` does with
        :meth:`update`, :meth:`change_detector` and :meth:`predict`.

        ``measured`` holds 1 for each sensor read at this sample and 0 for a missing one (its
        ``y`` is then ignored whatever its value, NaN and infinity included): the sensor's row of
        :math:`H` and its innovation are zeroed and its row and column of :math:`R` replaced by the
        identity's, which gives exactly the update without that sensor. A flag other than 1 counts
        as missing, and so does a non-finite ``y`` flagged 1 (as :meth:`update` skips a NaN).
        ``change_mean`` is the test's memory :math:`m` (K, one per sensor; zeros at the start of a
        record), ``change_statistic`` its :math:`T_k`
        (:mod:`~genthermal.estimation.change_detection`); on an alarm (:math:`T_k` above
        ``change_threshold``, every sensor read) ``P`` is the covariance already opened by the
        jump covariance and ``change_mean_next`` is zero. Without a threshold the test is computed
        but never fires.
        """
        nz, ny = len(self.state_names), len(self.output_names)
        z, P = ca.SX.sym("z_pred", nz), ca.SX.sym("P_pred", nz, nz)
        u, y_read, flags = ca.SX.sym("u", len(self.model.input_names)), ca.SX.sym("y", ny), ca.SX.sym("measured", ny)
        mean = ca.SX.sym("change_mean", ny)
        # select, never multiply: 0 * NaN is NaN, a comparison with NaN is false
        measured = ca.vertcat(*(ca.if_else((flags[i] == 1) * (ca.fabs(y_read[i]) <= _LARGEST_MEASUREMENT), 1.0, 0.0)
                                for i in range(ny)))
        y = ca.vertcat(*(ca.if_else(measured[i], y_read[i], 0.0) for i in range(ny)))
        mask = ca.diag(measured)
        H = mask @ ca.DM(self.H)
        R = mask @ ca.DM(self.R) @ mask + ca.diag(1 - measured)
        full_innovation = y - ca.DM(self.H) @ z - ca.DM(self.e)
        innovation = measured * full_innovation
        K = ca.solve(H @ P @ H.T + R, H @ P).T
        z_filtered = z + K @ innovation
        I_KH = ca.DM.eye(nz) - K @ H
        P_filtered = I_KH @ P @ I_KH.T + K @ R @ K.T
        # the change test on every sensor: skipped (memory held, no alarm) when one is missing
        all_measured = ca.mmin(measured)
        lam = forgetting_factor(self.change_window_samples)
        candidate = lam * mean + (1.0 - lam) * full_innovation
        S = ca.DM(self.H) @ P @ ca.DM(self.H).T + ca.DM(self.R)
        statistic = all_measured * (1.0 + lam) / (1.0 - lam) * ca.dot(candidate, ca.solve(S, candidate))
        threshold = np.inf if self.change_threshold is None else self.change_threshold
        alarm = all_measured * ca.if_else(statistic > threshold, 1.0, 0.0) if np.isfinite(threshold) else 0.0
        mean_next = ca.if_else(all_measured > 0, (1.0 - alarm) * candidate, mean)
        P_filtered = P_filtered + alarm * ca.DM(self.jump_covariance)
        z_next, F = self.transition(z_filtered, u)
        P_next = F @ P_filtered @ F.T + ca.DM(self.Q)
        return ca.Function("ekf_update", [z, P, u, y_read, flags, mean],
                           [z_filtered, P_filtered, z_next, P_next, mean_next, statistic],
                           ["z_pred", "P_pred", "u", "y", "measured", "change_mean"],
                           ["z", "P", "z_next_pred", "P_next_pred", "change_mean_next", "change_statistic"])

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
