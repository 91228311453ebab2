r"""Planning on the model the manager flies: the filter's nonlinear model, its state and its covariance.

The closed loop's extended Kalman filter (:class:`~genthermal.estimation.ekf.ExtendedKalmanFilter`)
runs on the nonlinear model the manager believes in (the calibrated or identified model with the
effects identified so far) and estimates the node temperatures and the disturbance heat flows
:math:`(d, m)`. :class:`FlownPlanning` predicts a schedule with the filter's own step
:math:`z_{k+1} = \Phi(z_k, u_k)` (:mod:`genthermal.discretise`'s ETD2RK step with the disturbances
held, as :meth:`~genthermal.estimation.ekf.ExtendedKalmanFilter.forecast`) and derives the
**back-off** from the filter's uncertainty instead of a fixed margin:

.. math::
    P^{a}_{k+1} = F_k P^{a}_k F_k^T,\qquad
    P^{w}_{k+1} = F_k \bigl(P^{w}_k [k \notin W]\bigr) F_k^T + Q,\qquad
    b_k = z_\alpha \sqrt{\operatorname{diag}\bigl(H (P^{a}_k + P^{w}_k) H^T\bigr)},

with :math:`F_k` the exact Jacobian of the step along the predicted trajectory (CasADi), :math:`Q`
the filter's process noise, :math:`P^a_0` the filter's covariance now and :math:`W` the steps
that start a management window (:meth:`~genthermal.schedule.plan.Segment.windows`): the
estimate's present uncertainty is carried along the whole plan (it includes the disturbance
states, so an uncertain heat flow becomes a growing temperature uncertainty), and the process
noise builds up over one window only, because the filter corrects the state once per cycle and the
manager re-plans as soon as the corrected prediction crosses the limit. Every generator, healthy
ones included, is held to :math:`\theta + b \le \theta_{max}`.

:math:`z_\alpha` = :data:`DEFAULT_CONFIDENCE_SIGMAS` (one-sided 97.7 % for a Gaussian error).
"""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np

from ..errors import InputError
from ..estimation.ekf import ExtendedKalmanFilter

#: Steps per call of the prediction's accumulated map (the last chunk is padded): one map is
#: built per filter and reused for every horizon.
PREDICTION_CHUNK_STEPS = 60
#: Standard deviations of the predicted temperature kept below θmax (one-sided 97.7 % for a
#: Gaussian error). Choice of this project: two sigma of the filter's own uncertainty.
DEFAULT_CONFIDENCE_SIGMAS = 2.0


def covariance_steps(ekf: ExtendedKalmanFilter) -> ca.Function:
    """``(z, Pa, Pw, U, restart) -> (Z, Pa, Pw, variance)``: :data:`PREDICTION_CHUNK_STEPS` filter
    steps with the two covariance recursions of the module docstring (``restart`` 1 at a window's
    first step): the states and the outputs' variances (K²) after each step side by side, the
    covariances after the last. Built once per filter."""
    cached = getattr(ekf, "_planning_covariance_steps", None)
    if cached is not None:
        return cached
    nz, chunk = len(ekf.state_names), PREDICTION_CHUNK_STEPS
    z, u, restart = ca.SX.sym("z", nz), ca.SX.sym("u", len(ekf.model.input_names)), ca.SX.sym("restart")
    Pa, Pw = ca.SX.sym("Pa", nz, nz), ca.SX.sym("Pw", nz, nz)
    z_next, F = ekf.transition(z, u)
    Pa_next, Pw_next = F @ Pa @ F.T, F @ ((1 - restart) * Pw) @ F.T + ca.DM(ekf.Q)
    H = ca.DM(ekf.H)
    variance = ca.diag(H @ (Pa_next + Pw_next) @ H.T)
    step = ca.Function("planning_covariance_step", [z, Pa, Pw, u, restart], [z_next, Pa_next, Pw_next, variance])
    steps = step.mapaccum("planning_prediction", chunk, 3, {})
    z0, Pa0, Pw0 = ca.MX.sym("z", nz), ca.MX.sym("Pa", nz, nz), ca.MX.sym("Pw", nz, nz)
    U, restarts = ca.MX.sym("U", len(ekf.model.input_names), chunk), ca.MX.sym("restart", 1, chunk)
    Z, Pa_all, Pw_all, V = steps(z0, Pa0, Pw0, U, restarts)
    ekf._planning_covariance_steps = ca.Function(
        "planning_prediction_chunk", [z0, Pa0, Pw0, U, restarts],
        [Z, Pa_all[:, -nz:], Pw_all[:, -nz:], V], ["z", "Pa", "Pw", "U", "restart"],
        ["Z", "Pa_end", "Pw_end", "variance"])
    return ekf._planning_covariance_steps


@dataclasses.dataclass
class FlownPlanning:
    """What a scheduler needs to plan on the flown model (module docstring).

    Attributes
    ----------
    filters : list of ExtendedKalmanFilter
        Per generator, the manager's filter (its model is the one the manager believes in).
    z0 : numpy.ndarray
        (n_generators, n_filter_states) filter state now: nodes (°C), then disturbances (W).
    P0 : numpy.ndarray
        (n_generators, n_filter_states, n_filter_states) its covariance.
    confidence_sigmas : float
        :math:`z_\\alpha`, standard deviations kept below θmax (>= 0).
    """

    filters: list
    z0: np.ndarray
    P0: np.ndarray
    confidence_sigmas: float = DEFAULT_CONFIDENCE_SIGMAS

    def __post_init__(self):
        if not all(isinstance(f, ExtendedKalmanFilter) for f in self.filters):
            raise InputError("filter", [type(f).__name__ for f in self.filters],
                             "planning on the flown model needs the extended Kalman filter (--filter ekf)")
        if not (np.isfinite(self.confidence_sigmas) and self.confidence_sigmas >= 0):
            raise InputError("confidence_sigmas", self.confidence_sigmas,
                             "must be a number of standard deviations >= 0")
        self.z0 = np.asarray(self.z0, dtype=float)
        self.P0 = np.asarray(self.P0, dtype=float)
        if self.z0.shape[0] != len(self.filters) or self.P0.shape[0] != len(self.filters):
            raise InputError("z0", self.z0.shape, f"needs one filter state per generator ({len(self.filters)})")

    def predict(self, problem, timeline) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(time_s, outputs, backoff_K)`` of ``timeline`` from the filter states: outputs and
        back-off (n_generators, n_outputs, n_steps + 1), °C and K."""
        n = timeline.n_steps
        restart = np.zeros(n)
        restart[np.unique(timeline.window_start)] = 1.0
        n_out = self.filters[0].H.shape[0]
        outputs = np.empty((problem.n_generators, n_out, n + 1))
        backoff = np.empty_like(outputs)
        chunk = PREDICTION_CHUNK_STEPS
        n_padded = int(np.ceil(n / chunk)) * chunk
        restart = np.concatenate([restart, np.zeros(n_padded - n)])
        for g, ekf in enumerate(self.filters):
            currents = np.concatenate([timeline.currents_A[g], np.full(n_padded - n, timeline.currents_A[g, -1])])
            U = problem.inputs(g, currents).T
            run = covariance_steps(ekf)
            z, Pa, Pw = self.z0[g], self.P0[g], np.zeros_like(self.P0[g])
            parts = []
            for start in range(0, n_padded, chunk):
                part = run(z, Pa, Pw, U[:, start:start + chunk], restart[start:start + chunk].reshape(1, -1))
                Z_part, Pa, Pw, variance_part = (np.asarray(m) for m in part)
                z = Z_part[:, -1]
                parts.append((Z_part, variance_part))
            Z = np.column_stack([self.z0[g], np.hstack([p[0] for p in parts])[:, :n]])
            variance = np.column_stack([np.diag(ekf.H @ self.P0[g] @ ekf.H.T), np.hstack([p[1] for p in parts])[:, :n]])
            outputs[g] = (ekf.H @ Z) + ekf.e[:, None]
            backoff[g] = self.confidence_sigmas * np.sqrt(np.clip(variance, 0.0, None))
        return np.arange(n + 1) * problem.dt_s, outputs, backoff
