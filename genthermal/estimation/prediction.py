"""n-step prediction from the Kalman-filtered state (thesis 6.2.4, 6.3.2).

The filter updates the state up to the prediction start, then the model runs open loop (thesis
eqs. 6.16-6.17). :func:`prediction_study` returns a :class:`PredictionStudy`: how long the prediction beats
the open-loop model by a margin (:func:`improved_period`, thesis Fig. 6.10, censored at the end
of the record) and the RMS and maximum error by horizon over many starts (:func:`horizon_errors`). Method:
``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd

from ..errors import InputError
from ..measurements import MeasurementData, dataframe_to_measurements, resample
from ..model import ThermalModel
from ..simulate import input_matrix
from .ekf import ExtendedKalmanFilter
from .filter_base import RecursiveFilter
from .filter_result import FilterResult, rms

#: Prediction start times of thesis Fig. 6.10, min from the start of the record.
THESIS_STARTS_MIN = (50, 75, 100, 125, 150, 175)
#: Trailing window over which the errors are averaged before they are compared, min.
DEFAULT_SMOOTHING_MIN = 5.0
#: Smallest improvement over the open-loop model counted as an improvement, K.
DEFAULT_MARGIN_K = 0.25
#: Prediction horizons of the error-by-horizon table, min.
DEFAULT_HORIZONS_MIN = (15, 30, 60)
#: Interval between the prediction starts of the error-by-horizon table, min.
DEFAULT_EVERY_MIN = 10.0


def check_start_times(starts_min, duration_min: float, field: str = "starts_min") -> tuple[float, ...]:
    """Return the start times (min) as floats, or raise InputError naming ``field`` and the value:
    each must be a finite number, >= 0 and before the end of the record (``duration_min``)."""
    checked = []
    for value in starts_min:
        try:
            start = float(value)
        except (TypeError, ValueError):
            raise InputError(field, value, "a start time must be a number of minutes") from None
        if not np.isfinite(start) or start < 0:
            raise InputError(field, value, "a start time must be a finite number of minutes >= 0")
        if start >= duration_min:
            raise InputError(field, value, f"beyond the data: the record lasts {duration_min:g} min")
        checked.append(start)
    if not checked:
        raise InputError(field, list(starts_min), "give at least one start time")
    return tuple(checked)


def on_grid(data: MeasurementData, dt_s: float) -> MeasurementData:
    """``data`` itself if it is sampled every ``dt_s`` already (so its missing samples stay
    missing), else :func:`genthermal.measurements.resample` of it."""
    steps = np.diff(data.time_s)
    if steps.size and np.max(np.abs(steps - dt_s)) <= 1e-6 * dt_s:
        return data
    return resample(data, dt_s)


def check_sensors(model: ThermalModel, data: MeasurementData, field: str = "data sensors") -> None:
    """Raise InputError naming ``field`` when the record lacks a sensor of the model (a model of
    another machine than the data)."""
    missing = [name for name in model.output_names if name not in data.sensors.columns]
    if missing:
        raise InputError(field, missing, f"{model.name} measures {', '.join(model.output_names)}; "
                         "is the model for another machine than the data?")


def horizon_starts(n_samples: int, dt_s: float, horizons_min, every_min: float = DEFAULT_EVERY_MIN) -> np.ndarray:
    """Start samples every ``every_min`` (from ``every_min`` on) whose longest horizon ends in the record.

    Raises
    ------
    InputError
        If a horizon or the interval is not a positive number of minutes, or the record is too short
        for one start (field ``data``).
    """
    horizons = _positive_minutes("horizons_min", horizons_min)
    every = _positive_minutes("every_min", [every_min])[0]
    longest = int(round(max(horizons) * 60.0 / dt_s))
    stride = max(1, int(round(every * 60.0 / dt_s)))
    starts = np.arange(stride, n_samples - longest, stride)
    if starts.size == 0:
        duration = (n_samples - 1) * dt_s / 60.0
        raise InputError("data", f"{duration:g} min", f"too short: a prediction needs {every:g} min of filtering "
                         f"and the longest horizon ({max(horizons):g} min) inside the record")
    return starts


def _positive_minutes(field: str, values) -> list[float]:
    checked = []
    for value in values:
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise InputError(field, value, "must be a positive number of minutes") from None
        if not (np.isfinite(number) and number > 0):
            raise InputError(field, value, "must be a positive number of minutes")
        checked.append(number)
    if not checked:
        raise InputError(field, list(values), "give at least one value")
    return checked


def horizon_errors(estimator: RecursiveFilter, result: FilterResult, open_loop: np.ndarray, starts: np.ndarray,
                   horizons_min, dt_s: float) -> dict:
    """Errors of the predictions from each start at each horizon, and of the open loop there.

    Returns
    -------
    dict
        ``"prediction"`` and ``"open_loop"``: horizon label → (n_starts × n_outputs) errors, K
        (model − measured, NaN where not measured); ``"forecasts"``: (n_starts × (longest + 1) ×
        n_outputs) predicted outputs from each start to the longest horizon, °C.
    """
    steps = {f"{h:g}": int(round(float(h) * 60.0 / dt_s)) for h in horizons_min}
    longest = max(steps.values())
    U, Y = result.inputs, result.measured
    prediction = {label: np.empty((len(starts), Y.shape[1])) for label in steps}
    forecasts = np.empty((len(starts), longest + 1, Y.shape[1]))
    for i, k in enumerate(starts):
        forecasts[i] = estimator.forecast(result.filter_state(k), U[:, k:k + longest + 1])
        for label, n in steps.items():
            prediction[label][i] = forecasts[i, n] - Y[k + n]
    open_loop_error = {label: open_loop[starts + n] - Y[starts + n] for label, n in steps.items()}
    return {"prediction": prediction, "open_loop": open_loop_error, "forecasts": forecasts}


def _by_sensor(errors: np.ndarray, names, statistic) -> dict:
    return {name: statistic(errors[:, i]) for i, name in enumerate(names)}


def _max_abs(values: np.ndarray) -> float:
    finite = values[np.isfinite(values)]
    return float(np.max(np.abs(finite))) if finite.size else float("nan")


def improved_period(prediction_error, open_loop_error, window_samples: int,
                    margin_K: float = DEFAULT_MARGIN_K) -> tuple[int, bool]:
    """Samples from the start until the prediction stops beating the open loop (module docstring).

    Parameters
    ----------
    prediction_error, open_loop_error : array_like
        Errors (K) from the start sample on, NaN where not measured.
    window_samples : int
        Length of the trailing mean.
    margin_K : float
        :math:`\\delta`, K.

    Returns
    -------
    (int, bool)
        Number of samples of the period and whether it was censored by the end of the record.
        A sample whose window holds no measurement is not judged (it does not end the period).
    """
    errors = pd.DataFrame({"p": prediction_error, "o": open_loop_error})
    smooth = errors.rolling(window_samples, min_periods=1).mean()
    not_better = np.flatnonzero(smooth["p"].abs() >= smooth["o"].abs() - margin_K)
    if not_better.size == 0:
        return len(smooth) - 1, True
    return int(not_better[0]), False


@dataclasses.dataclass(frozen=True, eq=False)
class PredictionStudy:
    """Filter, open-loop and n-step prediction errors on one record (thesis 6.3).

    Attributes
    ----------
    filter_result : FilterResult
    open_loop : numpy.ndarray
        Open-loop model outputs, °C (n × n_outputs).
    predictions : dict of float to numpy.ndarray
        Start (min) → predicted outputs from the start sample to the end, °C.
    start_indices : dict of float to int
        Start (min) → start sample.
    improved_minutes : dict of float to dict of str to float
        Start → sensor → period of increased accuracy, min (lower bound when censored).
    censored : dict of float to list of str
        Start → sensors whose period had not ended when the record did.
    smoothing_min, margin_K : float
        Settings of the period (module docstring).
    horizon_errors : dict
        :func:`horizon_errors`: ``"prediction"`` / ``"open_loop"`` → horizon label (min) →
        (n_starts × n_outputs) errors, K; ``"forecasts"`` the predicted outputs, °C.
    horizon_start_indices : numpy.ndarray
        Start samples of the error-by-horizon table (every ``every_min``).
    every_min : float
        Interval between those starts, min.
    filter_kind : str
        ``"ekf"`` or ``"kf"``.
    """

    filter_result: FilterResult
    open_loop: np.ndarray
    predictions: dict
    start_indices: dict
    improved_minutes: dict
    censored: dict
    smoothing_min: float
    margin_K: float
    horizon_errors: dict
    horizon_start_indices: np.ndarray
    every_min: float
    filter_kind: str

    @property
    def output_names(self) -> list[str]:
        """Names of the sensors compared."""
        return self.filter_result.output_names

    @property
    def filter_rmse(self) -> dict[str, float]:
        """RMS of filtered − measured per sensor, K."""
        return self.filter_result.rmse()

    @property
    def open_loop_rmse(self) -> dict[str, float]:
        """RMS of open-loop − measured per sensor, K."""
        error = self.open_loop - self.filter_result.measured
        return {name: rms(error[:, i]) for i, name in enumerate(self.output_names)}

    def by_horizon(self, which: str = "prediction", statistic=rms) -> dict:
        """Horizon label (min) → sensor → ``statistic`` (default RMS, K) of the errors over the
        starts; ``which`` is ``"prediction"`` or ``"open_loop"``."""
        return {label: _by_sensor(errors, self.output_names, statistic)
                for label, errors in self.horizon_errors[which].items()}

    def to_json(self) -> dict:
        """A JSON-ready dict: ``prediction_rmse_by_horizon``, ``prediction_max_by_horizon``,
        ``open_loop_rmse_by_horizon``, ``open_loop_max_by_horizon`` (horizon min → sensor → K),
        ``one_step_rmse``, ``filter_rmse``, ``open_loop_rmse`` (sensor → K), ``improved_minutes``
        (start label → sensor → min), ``improved_minutes_censored``, the settings and a
        ``definition`` of every figure."""
        label = {start: f"{start:g}" for start in self.improved_minutes}
        return {
            "filter": self.filter_kind,
            "prediction_rmse_by_horizon": self.by_horizon("prediction"),
            "prediction_max_by_horizon": self.by_horizon("prediction", _max_abs),
            "open_loop_rmse_by_horizon": self.by_horizon("open_loop"),
            "open_loop_max_by_horizon": self.by_horizon("open_loop", _max_abs),
            "horizon_starts": int(len(self.horizon_start_indices)),
            "horizon_every_min": self.every_min,
            "one_step_rmse": self.filter_result.rmse(one_step=True),
            "filter_rmse": self.filter_rmse,
            "open_loop_rmse": self.open_loop_rmse,
            "improved_minutes": {label[s]: dict(v) for s, v in self.improved_minutes.items()},
            "improved_minutes_censored": {label[s]: list(v) for s, v in self.censored.items() if v},
            "smoothing_min": self.smoothing_min,
            "margin_K": self.margin_K,
            "change_alarms_min": [(t - self.filter_result.time_s[0]) / 60.0
                                  for t in self.filter_result.change_alarm_times_s],
            "definition": {
                "prediction_rmse_by_horizon": (
                    f"RMS over starts every {self.every_min:g} min of (prediction made at the start for "
                    "start + horizon) - (measurement at start + horizon), K; _max_ the largest |error|"),
                "open_loop_rmse_by_horizon": "the same target samples, the model run open loop from the "
                                             "start of the record (never corrected), K",
                "one_step_rmse": "RMS of the innovations: one-step-ahead prediction - measurement, K",
                "filter_rmse": ("RMS of filtered - measured at the same sample, after the update with that very "
                                "measurement: it says little (a filter that copies its measurement scores "
                                "the sensor noise); use one_step_rmse and prediction_rmse_by_horizon"),
                "change_alarms_min": ("minutes from the start of the record at which the extended Kalman "
                                      "filter's innovation change test found a change in what the model lacks "
                                      "and opened its disturbance covariance (a fault; none on a healthy record)"),
                "improved_minutes": (f"minutes from the start until the {self.smoothing_min:g}-min trailing mean "
                                     "of the |prediction error| first comes within margin_K of that of the "
                                     "|open-loop error|; censored values are lower bounds (the record ended first)"),
            },
        }

    def plot_horizons(self, path=None, sensor: str | None = None):
        """Prediction vs measurement: the measured ``sensor`` (default the first output) with the
        prediction from every start of the error-by-horizon table up to the longest horizon and the
        open-loop model, and the RMS error by horizon of the prediction and the open loop."""
        from ..plots import finish_figure, plt

        result = self.filter_result
        i = self.output_names.index(sensor or self.output_names[0])
        name = self.output_names[i]
        minutes = (result.time_s - result.time_s[0]) / 60.0
        fig, (ax_t, ax_e) = plt.subplots(2, 1, figsize=(9, 7), gridspec_kw={"height_ratios": [2, 1]})
        ax_t.plot(minutes, result.measured[:, i], ".", color="0.6", ms=2, label=f"{name} measured")
        ax_t.plot(minutes, self.open_loop[:, i], "--", color="0.3", lw=1, label="open-loop model")
        forecasts = self.horizon_errors["forecasts"]
        for j, k in enumerate(self.horizon_start_indices):
            ax_t.plot(minutes[k:k + forecasts.shape[1]], forecasts[j, :, i], lw=1.3, color=f"C{j % 10}",
                      label="prediction from each start" if j == 0 else None)
            ax_t.plot(minutes[k], forecasts[j, 0, i], "o", ms=3, color=f"C{j % 10}")
        kind = "extended Kalman filter" if self.filter_kind == "ekf" else "Kalman filter"
        ax_t.set(xlabel="time [min]", ylabel="temperature [°C]",
                 title=f"{name}: predictions every {self.every_min:g} min ({kind} on {result.model.name})")
        ax_t.legend(fontsize=8)
        labels = list(self.horizon_errors["prediction"])
        positions = np.arange(len(labels))
        for offset, (which, text) in zip((-0.2, 0.2), (("prediction", "prediction"), ("open_loop", "open loop"))):
            values = [self.by_horizon(which)[h][name] for h in labels]
            bars = ax_e.bar(positions + offset, values, 0.4, label=f"{text} RMS")
            ax_e.bar_label(bars, fmt="%.2f", fontsize=8)
        ax_e.set(xticks=positions, xticklabels=[f"{h} min" for h in labels], ylabel=f"{name} RMS error [K]",
                 title="error by horizon over all starts")
        ax_e.legend(fontsize=8)
        for ax in (ax_t, ax_e):
            ax.grid(alpha=0.3)
        return finish_figure(fig, path)

    def plot(self, path=None):
        """Prediction errors per sensor against the open-loop and filter errors (thesis Figs 6.8,
        6.9) and the periods of increased accuracy against the start time (Fig. 6.10)."""
        from ..plots import finish_figure, plt

        result = self.filter_result
        minutes = (result.time_s - result.time_s[0]) / 60.0
        names = self.output_names
        fig, axes = plt.subplots(len(names) + 1, 1, figsize=(9, 3.2 * (len(names) + 1)))
        for i, (name, ax) in enumerate(zip(names, axes)):
            measured = result.measured[:, i]
            ax.plot(minutes, self.open_loop[:, i] - measured, color="0.4", lw=1, label="open loop")
            ax.plot(minutes, result.outputs[:, i] - measured, color="k", lw=0.6,
                    label="extended Kalman filter" if self.filter_kind == "ekf" else "Kalman filter")
            for start, predicted in self.predictions.items():
                k = self.start_indices[start]
                ax.plot(minutes[k:], predicted[:, i] - measured[k:], lw=1.2, label=f"prediction from {start:g} min")
            ax.axhline(0, color="0.7", lw=0.5)
            ax.set(ylabel=f"{name} error [K]", title=f"{name}: model − measured")
            ax.grid(alpha=0.3)
        axes[0].legend(fontsize=7, ncol=3)
        axes[len(names) - 1].set_xlabel("time [min]")
        starts = list(self.improved_minutes)
        for name in names:
            values = [self.improved_minutes[s][name] for s in starts]
            line, = axes[-1].plot(starts, values, "o-", label=name)
            censored = [(s, v) for s, v in zip(starts, values) if name in self.censored[s]]
            if censored:
                axes[-1].plot(*zip(*censored), "^", color=line.get_color(), ms=9, mfc="none")
        axes[-1].set(xlabel="prediction start [min]", ylabel="increased accuracy [min]",
                     title=f"Period of increased accuracy (margin {self.margin_K:g} K; ^ = record ended first)")
        axes[-1].legend(fontsize=8)
        axes[-1].grid(alpha=0.3)
        return finish_figure(fig, path)


def prediction_study(model: ThermalModel, data, starts_min=THESIS_STARTS_MIN, dt_s: float = 10.0,
                     kalman: RecursiveFilter | None = None, smoothing_min: float = DEFAULT_SMOOTHING_MIN,
                     margin_K: float = DEFAULT_MARGIN_K, steady_state: bool = False,
                     horizons_min=DEFAULT_HORIZONS_MIN, every_min: float = DEFAULT_EVERY_MIN) -> PredictionStudy:
    r"""Filter a record, run the open-loop model, and predict from each start (thesis 6.3).

    Parameters
    ----------
    model : ThermalModel
        The model the filter runs on (any model for the EKF; the linear design model for the
        linear filter).
    data : MeasurementData or pandas.DataFrame
        The record (CSV schema of :mod:`genthermal.measurements`), put on the ``dt_s`` grid by
        :func:`on_grid`.
    starts_min : sequence of float
        Start times of the period of increased accuracy, min after the first sample (see
        :func:`check_start_times`).
    dt_s : float
        Model and filter step, s.
    kalman : KalmanFilter or ExtendedKalmanFilter, optional
        The filter to use (its ``dt_s`` must equal ``dt_s``); default
        ``ExtendedKalmanFilter(model, dt_s)`` with its default noise settings.
    smoothing_min, margin_K : float
        Window of the trailing mean (min) and margin :math:`\delta` (K) of the period of
        increased accuracy (module docstring).
    steady_state : bool
        Filter with the steady-state gain (linear filter only).
    horizons_min : sequence of float
        Horizons of the error-by-horizon table, min.
    every_min : float
        Interval between its starts, min.

    Raises
    ------
    InputError
        Data without the model's sensors, a record shorter than the longest horizon, bad settings.
    """
    data = on_grid(data if isinstance(data, MeasurementData) else dataframe_to_measurements(data), dt_s)
    check_sensors(model, data)
    kalman = kalman or ExtendedKalmanFilter(model, dt_s)
    if abs(kalman.dt_s - dt_s) > 1e-9 * dt_s:
        raise InputError("kalman.dt_s", kalman.dt_s, f"must equal dt_s = {dt_s:g} s")
    if not (np.isfinite(smoothing_min) and smoothing_min > 0):
        raise InputError("smoothing_min", smoothing_min, "must be a positive number of minutes")
    if not (np.isfinite(margin_K) and margin_K >= 0):
        raise InputError("margin_K", margin_K, "must be a number of kelvin >= 0")
    time_s = data.time_s
    starts = check_start_times(starts_min, (time_s[-1] - time_s[0]) / 60.0)
    horizon_start_indices = horizon_starts(len(time_s), dt_s, horizons_min, every_min)
    inputs = data.frame[["time_s", *model.input_names]]
    result = kalman.run(inputs, data.sensors, steady_state=steady_state)
    U, Y = input_matrix(inputs, model), result.measured
    open_start = np.asarray(kalman.initial_state(Y[0], U[:, 0]), dtype=float).copy()
    open_start[kalman.n_nodes:] = 0.0  # the model as simulation runs it: no disturbance, no prior
    open_loop = kalman.forecast(open_start, U)
    window = max(1, int(round(smoothing_min * 60.0 / dt_s)))
    predictions, indices, improved, censored = {}, {}, {}, {}
    for start in starts:
        k = int(round(start * 60.0 / dt_s))
        indices[start] = k
        predictions[start] = kalman.forecast(result.filter_state(k), U[:, k:])
        improved[start], censored[start] = {}, []
        for i, name in enumerate(result.output_names):
            samples, was_censored = improved_period(predictions[start][:, i] - Y[k:, i],
                                                    open_loop[k:, i] - Y[k:, i], window, margin_K)
            improved[start][name] = samples * dt_s / 60.0
            if was_censored:
                censored[start].append(name)
    errors = horizon_errors(kalman, result, open_loop, horizon_start_indices, horizons_min, dt_s)
    kind = "ekf" if isinstance(kalman, ExtendedKalmanFilter) else "kf"
    return PredictionStudy(result, open_loop, predictions, indices, improved, censored,
                           float(smoothing_min), float(margin_K), errors, horizon_start_indices,
                           float(every_min), kind)
