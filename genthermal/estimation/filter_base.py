"""What the Kalman filter and the extended Kalman filter share: checking a record, the loop over
its samples, and the forecast from a filtered state."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..errors import InputError
from ..simulate import input_matrix, uniform_step
from .filter_result import FilterResult


class RecursiveFilter:
    """Base of :class:`~genthermal.estimation.kalman.KalmanFilter` and
    :class:`~genthermal.estimation.ekf.ExtendedKalmanFilter`.

    A subclass sets ``model``, ``dt_s``, ``output_names``, ``state_names`` (the filter's states:
    the model's nodes, then any disturbance states), ``C``, ``e`` (:math:`y = Cx + e` on the
    model's nodes) and ``R``, and provides ``update``, ``predict``, ``initial_state`` and
    ``forecast``.
    """

    #: Names of the disturbance states appended to the model's nodes (none for the linear filter).
    disturbance_names: tuple = ()

    def change_detector(self):
        """A fresh :class:`~genthermal.estimation.change_detection.InnovationChangeDetector` for
        :meth:`run`, or None (default: no change detection)."""
        return None

    @property
    def C_full(self) -> np.ndarray:
        """:math:`\\partial y/\\partial z` on the whole filter state (nodes, then disturbances)."""
        return np.hstack([self.C, np.zeros((len(self.output_names), len(self.disturbance_names)))])

    @property
    def n_nodes(self) -> int:
        """Number of model states (capacitive nodes), the first entries of the filter state."""
        return self.model.n_states

    def run(self, inputs_df: pd.DataFrame, sensors_df: pd.DataFrame, x0=None,
            steady_state: bool = False) -> FilterResult:
        """Filter a record: update with each sample, then predict to the next.

        Parameters
        ----------
        inputs_df : pandas.DataFrame
            ``time_s`` (uniform, step ``dt_s``) and the model inputs.
        sensors_df : pandas.DataFrame
            One row per input row, a column per output name (°C, NaN = no measurement), e.g.
            :attr:`genthermal.measurements.MeasurementData.sensors`.
        x0 : array_like, optional
            Initial filter state (°C for the nodes, W for disturbance states); default
            :meth:`initial_state` of the first row.
        steady_state : bool
            Use the constant steady-state gain (linear filter only).
        """
        time_s, U, Y = self._record(inputs_df, sensors_df)
        n, nz = len(time_s), len(self.state_names)
        z = self.initial_state(Y[0], U[:, 0]) if x0 is None else \
            np.broadcast_to(np.asarray(x0, dtype=float), (nz,)).copy()
        P = None if steady_state else self.P0
        detector = None if steady_state else self.change_detector()
        Z_pred, Z, gains, innovations = np.empty((n, nz)), np.empty((n, nz)), [], np.empty(Y.shape)
        for k in range(n):
            Z_pred[k] = z
            step = self.update(z, P, Y[k])
            Z[k], innovations[k] = step.x, step.innovation
            gains.append(step.gain)
            P_filtered = step.P if detector is None else \
                detector.step(step.innovation, self.C_full @ P @ self.C_full.T + self.R, step.P)
            z, P = self.predict(step.x, P_filtered, U[:, k])
        final_covariance = None if steady_state else P_filtered
        nx = self.n_nodes
        return FilterResult(self.model, time_s, U, Z[:, :nx], Z_pred[:, :nx], Y, innovations, np.array(gains),
                            self.C, self.e, bool(steady_state), disturbances=Z[:, nx:],
                            disturbance_names=tuple(self.disturbance_names),
                            change_alarm_times_s=tuple(float(time_s[k]) for k in (detector.alarms if detector else ())),
                            final_covariance=final_covariance)

    def _record(self, inputs_df, sensors_df):
        time_s = inputs_df["time_s"].to_numpy(dtype=float) if "time_s" in inputs_df else None
        U = input_matrix(inputs_df, self.model)
        step = uniform_step(time_s, "inputs.time_s")
        if abs(step - self.dt_s) > 1e-6 * self.dt_s:
            raise InputError("inputs.time_s", f"step {step:g} s", f"the filter runs at {self.dt_s:g} s; "
                             "resample the data (genthermal.measurements.resample)")
        self._check_sensor_columns(sensors_df)
        if len(sensors_df) != len(time_s):
            raise InputError("sensors", f"{len(sensors_df)} rows", f"the inputs have {len(time_s)} rows")
        return time_s, U, sensors_df[self.output_names].to_numpy(dtype=float)

    def estimate_measurement_noise(self, sensors_df: pd.DataFrame, window_samples: int = 7) -> np.ndarray:
        """Measurement noise covariance R (K², output order) estimated from a record by
        :func:`~genthermal.estimation.kalman.measurement_noise_covariance`; pass it as ``R=``."""
        from .kalman import measurement_noise_covariance

        self._check_sensor_columns(sensors_df)
        return measurement_noise_covariance(sensors_df[self.output_names], window_samples).to_numpy()

    def _check_sensor_columns(self, sensors_df: pd.DataFrame) -> None:
        missing = [name for name in self.output_names if name not in sensors_df.columns]
        if missing:
            raise InputError("sensors", missing, f"missing columns; need {', '.join(self.output_names)} "
                             f"(the sensors of {self.model.name})")


def checked_predict_steps(predict_steps) -> int:
    """``predict_steps`` as an int, or an InputError naming it when it is not a whole number >= 1."""
    if int(predict_steps) != predict_steps or predict_steps < 1:
        raise InputError("predict_steps", predict_steps, "must be a positive whole number of steps")
    return int(predict_steps)
