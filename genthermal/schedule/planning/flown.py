"""Planning on the model the manager flies: the filter's nonlinear model, its state and
disturbances, with a back-off from its covariance. Main object: :class:`FlownPlanning`. Method:
docs/guide/flight-methods.md.
"""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np

from ...errors import InputError
from ...estimation.ekf import ExtendedKalmanFilter

#: Steps per call of the prediction's accumulated map (the last chunk is padded): one map is
#: built per filter and reused for every horizon.
PREDICTION_CHUNK_STEPS = 60
#: Standard deviations of the predicted temperature kept below θmax (one-sided 97.7 % for a
#: Gaussian error). Choice of this project: two sigma of the filter's own uncertainty.
DEFAULT_CONFIDENCE_SIGMAS = 2.0


def covariance_steps(ekf: ExtendedKalmanFilter) -> ca.Function:
    """``(z, P, U, update) -> (Z, P_all, variance)``: :data:`PREDICTION_CHUNK_STEPS` filter steps
    with the covariance recursion of the module docstring (``update`` 1 where the filter makes its
    measurement update before the step): the states, the covariances and the outputs' variances
    (K²) after each step side by side. Built once per filter."""
    cached = getattr(ekf, "_planning_covariance_steps", None)
    if cached is not None:
        return cached
    nz, chunk = len(ekf.state_names), PREDICTION_CHUNK_STEPS
    z, u, update = ca.SX.sym("z", nz), ca.SX.sym("u", len(ekf.model.input_names)), ca.SX.sym("update")
    P = ca.SX.sym("P", nz, nz)
    H, R = ca.DM(ekf.H), ca.DM(ekf.R)
    gain = ca.solve(H @ P @ H.T + R, H @ P).T
    P_updated = P - update * gain @ H @ P
    z_next, F = ekf.transition(z, u)
    P_next = F @ P_updated @ F.T + ca.DM(ekf.Q)
    variance = ca.diag(H @ P_next @ H.T)
    step = ca.Function("planning_covariance_step", [z, P, u, update], [z_next, P_next, variance])
    steps = step.mapaccum("planning_prediction", chunk, 2, {})
    z0, P0 = ca.MX.sym("z", nz), ca.MX.sym("P", nz, nz)
    U, updates = ca.MX.sym("U", len(ekf.model.input_names), chunk), ca.MX.sym("update", 1, chunk)
    Z, P_all, V = steps(z0, P0, U, updates)
    ekf._planning_covariance_steps = ca.Function(
        "planning_prediction_chunk", [z0, P0, U, updates], [Z, P_all, V],
        ["z", "P", "U", "update"], ["Z", "P_all", "variance"])
    return ekf._planning_covariance_steps


def update_steps(n_steps: int, dt_s: float, cycle_s: float) -> np.ndarray:
    """(n_steps,) 1.0 at the steps before which the closed loop updates the filter (one cycle of
    ``cycle_s`` after another from now, the first one cycle ahead: the filter's covariance now is
    already updated), else 0.0."""
    if not (np.isfinite(dt_s) and dt_s > 0 and np.isfinite(cycle_s) and cycle_s > 0):
        raise InputError("cycle_s", cycle_s, f"and dt_s {dt_s!r} must be positive numbers of seconds")
    every = max(int(round(cycle_s / dt_s)), 1)
    steps = np.arange(n_steps)
    return ((steps > 0) & (steps % every == 0)).astype(float)


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
        back-off (n_generators, n_outputs, n_steps + 1), °C and K; the filter updated once per
        ``problem.window_s`` (the management cycle) along it."""
        n = timeline.n_steps
        n_out = self.filters[0].H.shape[0]
        outputs = np.empty((problem.n_generators, n_out, n + 1))
        backoff = np.empty_like(outputs)
        for g in range(problem.n_generators):
            outputs[g], backoff[g], _ = self.run(problem, g, self.z0[g], self.P0[g], timeline.currents_A[g])
        return np.arange(n + 1) * problem.dt_s, outputs, backoff

    def run(self, problem, g: int, z: np.ndarray, P: np.ndarray, currents_A: np.ndarray,
            first_step: int = 0) -> tuple[np.ndarray, np.ndarray, tuple]:
        """Generator ``g``'s filter model from state ``z`` and covariance ``P`` through the phase
        currents ``currents_A`` (n_steps,), A, starting ``first_step`` steps after the planning
        instant (which sets where along it the filter's updates fall).

        Returns
        -------
        (numpy.ndarray, numpy.ndarray, tuple)
            Outputs (°C) and back-off (K), each (n_outputs, n_steps + 1) with the start first, and
            ``(z, P, first_step)`` after the last step.
        """
        ekf, chunk = self.filters[g], PREDICTION_CHUNK_STEPS
        n, nz = len(currents_A), len(ekf.state_names)
        n_padded = int(np.ceil(n / chunk)) * chunk
        updates = update_steps(first_step + n_padded, problem.dt_s, problem.window_s)[first_step:]
        U = problem.inputs(g, np.concatenate([currents_A, np.full(n_padded - n, currents_A[-1])])).T
        step_chunk = covariance_steps(ekf)
        z_now, P_now, parts = np.asarray(z, dtype=float), np.asarray(P, dtype=float), []
        for start in range(0, n_padded, chunk):
            Z_part, P_part, variance_part = (np.asarray(m) for m in step_chunk(
                z_now, P_now, U[:, start:start + chunk], updates[start:start + chunk].reshape(1, -1)))
            z_now, P_now = Z_part[:, -1], P_part[:, -nz:]
            if start + chunk >= n:  # the state and covariance after step n
                last = n - start - 1
                z_end, P_end = Z_part[:, last], P_part[:, last * nz:(last + 1) * nz]
            parts.append((Z_part, variance_part))
        Z = np.column_stack([z, np.hstack([p[0] for p in parts])[:, :n]])
        variance = np.column_stack([np.diag(ekf.H @ P @ ekf.H.T), np.hstack([p[1] for p in parts])[:, :n]])
        outputs = (ekf.H @ Z) + ekf.e[:, None]
        backoff = self.confidence_sigmas * np.sqrt(np.clip(variance, 0.0, None))
        return outputs, backoff, (z_end, P_end, first_step + n)
