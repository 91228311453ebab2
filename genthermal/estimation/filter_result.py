"""The record of a Kalman filter run: filtered and predicted states of every node, innovations
and gains, with tables and a plot."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd

from ..model import ThermalModel
from ..simulate import results_frame


@dataclasses.dataclass(frozen=True, eq=False)
class FilterResult:
    """What :meth:`KalmanFilter.run` found, one row per sample.

    Attributes
    ----------
    model : ThermalModel
        The model filtered (the linear design model for the Kalman filter, any model for the EKF).
    time_s : numpy.ndarray
        Sample times, s.
    inputs : numpy.ndarray
        Inputs (n_inputs × n).
    states : numpy.ndarray
        Filtered states :math:`\\hat x_k` of every node, °C (n × n_states), the unmeasured ones
        (rotor, shaft, end windings, frame) included.
    predicted_states : numpy.ndarray
        One-step predictions :math:`\\hat x_k^-`, °C (n × n_states).
    measured : numpy.ndarray
        Measured outputs, °C, NaN where missing (n × n_outputs).
    innovations : numpy.ndarray
        :math:`y_k - C\\hat x_k^- - e`, K, NaN where missing (n × n_outputs).
    gains : numpy.ndarray
        Gain used at each sample (n × n_states × n_outputs); zero columns for missing sensors.
    C, e : numpy.ndarray
        Output map :math:`y = Cx + e`.
    steady_state : bool
        True when the constant steady-state gain was used.
    disturbances : numpy.ndarray
        Filtered disturbance states, W (n × n_disturbances; no columns for the linear filter).
    disturbance_names : tuple of str
        Their names (``q_<node>``: unknown heat flow into that node; ``q_load_<node>``,
        ``q_coolant_<node>``: scaled by the load squared or by the node's rise above the coolant
        inlet; ``dT_inlet``: coolant inlet offset, K).
    change_alarm_times_s : tuple of float
        Times (s) at which the innovation change test opened the disturbance covariance
        (:mod:`genthermal.estimation.change_detection`); empty without the test.
    final_covariance : numpy.ndarray or None
        Covariance of the whole filter state after the last update (nodes K², disturbances W²),
        None for the steady-state gain.
    """

    model: ThermalModel
    time_s: np.ndarray
    inputs: np.ndarray
    states: np.ndarray
    predicted_states: np.ndarray
    measured: np.ndarray
    innovations: np.ndarray
    gains: np.ndarray
    C: np.ndarray
    e: np.ndarray
    steady_state: bool
    disturbances: np.ndarray | None = None
    disturbance_names: tuple = ()
    change_alarm_times_s: tuple = ()
    final_covariance: np.ndarray | None = None

    def filter_state(self, k: int) -> np.ndarray:
        """The filter's whole state after the update at sample ``k``: nodes (°C) then disturbances (W)."""
        if self.disturbances is None:
            return self.states[k]
        return np.concatenate([self.states[k], self.disturbances[k]])

    @property
    def output_names(self) -> list[str]:
        """Names of the outputs (columns of ``measured``, ``innovations``, ``outputs``)."""
        return list(self.model.output_names)

    @property
    def outputs(self) -> np.ndarray:
        """Filtered outputs :math:`C\\hat x_k + e`, °C (n × n_outputs)."""
        return self.states @ self.C.T + self.e

    @property
    def predicted_outputs(self) -> np.ndarray:
        """One-step-ahead outputs :math:`C\\hat x_k^- + e`, °C (n × n_outputs)."""
        return self.predicted_states @ self.C.T + self.e

    @property
    def samples_without_measurement(self) -> int:
        """Number of samples at which every sensor was missing (prediction only)."""
        return int(np.sum(~np.isfinite(self.measured).any(axis=1)))

    @property
    def missing_counts(self) -> dict[str, int]:
        """Per output, the number of samples without its measurement."""
        return {name: int(np.sum(~np.isfinite(self.measured[:, i]))) for i, name in enumerate(self.output_names)}

    def rmse(self, one_step: bool = False) -> dict[str, float]:
        """Root mean square of (filtered − measured) per output, K, over the measured samples;
        with ``one_step`` of the innovations (one-step-ahead prediction − measured)."""
        error = -self.innovations if one_step else self.outputs - self.measured
        return {name: rms(error[:, i]) for i, name in enumerate(self.output_names)}

    def to_pandas(self) -> pd.DataFrame:
        """``time_s``, the inputs, ``T_<state>`` for every state, the filtered outputs (and
        ``T_outlet``) as :func:`genthermal.simulate.simulate` names them, then
        ``measured_<output>`` and ``innovation_<output>`` per output."""
        frame = results_frame(self.model, self.time_s, self.inputs, self.states.T)
        for i, name in enumerate(self.output_names):
            frame[f"measured_{name}"] = self.measured[:, i]
            frame[f"innovation_{name}"] = self.innovations[:, i]
        for j, name in enumerate(self.disturbance_names):
            frame[f"{name}_W"] = self.disturbances[:, j]
        return frame

    def plot(self, path=None):
        """Measured and filtered outputs, the unmeasured states, and the filter error over time
        (thesis Figs 6.6/6.7); returns the matplotlib figure, saved to ``path`` if given."""
        minutes = (self.time_s - self.time_s[0]) / 60.0
        from ..plots import finish_figure, plt

        fig, (ax_t, ax_e) = plt.subplots(2, 1, figsize=(9, 7), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
        for i, name in enumerate(self.output_names):
            ax_t.plot(minutes, self.measured[:, i], ".", ms=2, alpha=0.4, label=f"{name} measured")
            ax_t.plot(minutes, self.outputs[:, i], lw=1.5, label=f"{name} filtered")
            ax_e.plot(minutes, self.outputs[:, i] - self.measured[:, i], lw=0.8, label=name)
        sensor_nodes = set(self.model.spec.sensors.values())
        for j, node in enumerate(self.model.state_names):
            if node not in sensor_nodes:
                ax_t.plot(minutes, self.states[:, j], lw=0.8, ls="--", label=f"{node} (estimated)")
        mode = "steady-state gain" if self.steady_state else "time-varying gain"
        kind = "extended Kalman filter" if self.disturbance_names else "Kalman filter"
        ax_t.set(ylabel="temperature [°C]", title=f"{kind} on {self.model.name} ({mode})")
        ax_t.legend(fontsize=7, ncol=2)
        ax_e.set(xlabel="time [min]", ylabel="filtered − measured [K]")
        ax_e.legend(fontsize=7)
        for ax in (ax_t, ax_e):
            ax.grid(alpha=0.3)
        return finish_figure(fig, path)


def rms(values: np.ndarray) -> float:
    """Root mean square of the finite values (NaN when none)."""
    finite = values[np.isfinite(values)]
    return float(np.sqrt(np.mean(finite**2))) if finite.size else float("nan")
