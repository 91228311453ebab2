"""Model against measurement: simulate on the measured inputs, measure the error, find where it fails.

:func:`compare` runs the model open loop on the measured inputs from an initial state matched to
the first measurement (:func:`initial_state`) and returns a :class:`Comparison`: RMSE, MAE, max
error, bias and R² per sensor (model minus measurement, K), split by load band, temperature band,
heating/steady/cooling and hour, and the error trend (K/h). Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import math
import os

import numpy as np
import pandas as pd

from ..errors import InputError
from ..machines.interface import Role
from ..measurements import MeasurementData, dataframe_to_measurements, load_measurements, resample
from ..model import ThermalModel
from ..simulate import simulate

#: Load bands, % of rated phase current (upper edges).
LOAD_BANDS = ((40.0, "low load (< 40 %)"), (70.0, "medium load (40-70 %)"), (math.inf, "high load (>= 70 %)"))
#: |dθ_w/dt| below which the machine counts as steady, K/min.
STEADY_RATE_K_PER_MIN = 0.05
#: Window of the smoothed winding temperature derivative, s.
RATE_WINDOW_S = 300.0


def regressors(interface) -> dict:
    """Candidate regressors of the residual of a machine (column of the comparison frame → label):
    the mean squared load current, the first sensor's temperature and its rate, the excitation
    current when the machine has one, and the coolant temperature."""
    columns = {"I_squared": "mean I² [A²]", "theta_winding": "measured θ_w [°C]"}
    if interface.has_role(Role.EXCITATION_CURRENT):
        excitation = interface.role(Role.EXCITATION_CURRENT)
        columns[excitation] = f"{excitation} [A]"
    columns[interface.coolant_input] = f"{interface.coolant_input} [°C]"
    columns["dtheta_dt"] = "dθ_w/dt [K/min]"
    return columns


@dataclasses.dataclass(frozen=True)
class MeasuredSeries:
    """Measurements on a uniform grid as arrays.

    Attributes
    ----------
    time_s : numpy.ndarray
        Sample times, s (uniform).
    dt_s : float
        Sample period, s.
    inputs : pandas.DataFrame
        ``time_s`` and the model inputs in input-vector order (units of the machine's interface).
    outputs : numpy.ndarray
        Measured ``T_winding`` and ``T_iron``, shape (2, N), °C; NaN = missing.
    source : str
        Where the data came from.
    """

    time_s: np.ndarray
    dt_s: float
    inputs: pd.DataFrame
    outputs: np.ndarray
    source: str

    @property
    def input_matrix(self) -> np.ndarray:
        """Inputs as an array (n_inputs, N)."""
        return self.inputs.drop(columns="time_s").to_numpy(dtype=float).T


def as_measurements(data, interface=None) -> MeasurementData:
    """Accept a :class:`MeasurementData`, a DataFrame in the CSV schema or a CSV path; ``interface``
    (a :class:`~genthermal.machines.interface.MachineInterface`) gives the schema, default the
    default machine's."""
    if isinstance(data, MeasurementData):
        return data
    if isinstance(data, pd.DataFrame):
        return dataframe_to_measurements(data, interface=interface)
    if isinstance(data, (str, os.PathLike)):
        return load_measurements(data, interface=interface)
    raise InputError("data", type(data).__name__, "expected a CSV path, a DataFrame or MeasurementData")


def measured_series(data, dt_s: float | None = None, output_names=None, interface=None) -> MeasuredSeries:
    """Measurements on a uniform grid.

    Parameters
    ----------
    data : MeasuredSeries, MeasurementData, pandas.DataFrame or path
    dt_s : float, optional
        Resample to this period (s). Default: keep the data's grid when uniform, else resample to
        the median sample period.
    output_names : sequence of str, optional
        Model outputs to read from the measured sensors; default every sensor of the schema.
    interface : MachineInterface, optional
        Schema of frames and files (``model.spec.interface``); default the default machine's.
    """
    if isinstance(data, MeasuredSeries):
        if dt_s is not None and abs(dt_s - data.dt_s) > 1e-9 * data.dt_s:
            raise InputError("dt_s", dt_s, f"the series is already on a {data.dt_s:g} s grid; resample the "
                             "measurements instead")
        return data
    data = as_measurements(data, interface)
    output_names = list(data.interface.output_names if output_names is None else output_names)
    steps = np.diff(data.time_s)
    if steps.size == 0:
        raise InputError("data", data.source, "need at least two samples")
    median = float(np.median(steps))
    if dt_s is not None or np.max(np.abs(steps - median)) > 1e-6 * median:
        data = resample(data, median if dt_s is None else dt_s)
    sensors = data.sensors
    per_phase = [n for n in output_names if n not in sensors and n in data.frame]  # T_winding_u/v/w
    if per_phase:
        sensors = pd.concat([sensors.reset_index(drop=True), data.frame[per_phase].reset_index(drop=True)], axis=1)
    missing = [n for n in output_names if n not in sensors]
    if missing:
        raise InputError("model outputs", missing, "the data have no sensor for these outputs")
    outputs = sensors[list(output_names)].to_numpy(dtype=float).T
    complete = np.flatnonzero(np.isfinite(outputs).all(axis=0))
    if complete.size == 0:
        raise InputError("data", data.source, f"no sample with every sensor ({', '.join(output_names)}) measured")
    if complete[0] > 0:  # start where the initial state can be matched to a full measurement
        data = dataclasses.replace(data, frame=data.frame.iloc[complete[0]:].reset_index(drop=True))
        outputs = outputs[:, complete[0]:]
    time_s = data.time_s
    inputs = pd.concat([data.frame[["time_s"]], data.inputs], axis=1)
    return MeasuredSeries(time_s, float(np.median(np.diff(time_s))), inputs, outputs, data.source)


def initial_coefficients(model: ThermalModel, series: MeasuredSeries, p=None) -> np.ndarray:
    """The ``(a, c)`` of the initial state that reproduce the first measured sensor temperatures.

    Returns
    -------
    numpy.ndarray
        ``[a, c]`` with :math:`x_0 = c\\mathbf 1 + a(x_{ss}(u_0) - T_{inlet,0}\\mathbf 1)`.
    """
    u0 = series.input_matrix[:, 0]
    t_ref = float(u0[model.input_names.index(model.spec.interface.coolant_input)])
    loaded = model.steady_state(u0, p) - t_ref
    y_uniform_0 = model.outputs(np.zeros(model.n_states), u0, p)
    y_per_kelvin = model.outputs(np.ones(model.n_states), u0, p) - y_uniform_0
    y_per_a = model.outputs(loaded, u0, p) - y_uniform_0
    measured = series.outputs[:, 0]
    if abs(y_per_a[0] - y_per_a[-1]) < 0.5:  # steady state does not separate the sensors
        return np.array([0.0, float(np.mean(measured - y_uniform_0) / np.mean(y_per_kelvin))])
    design = np.column_stack([y_per_a, y_per_kelvin])
    coefficients, *_ = np.linalg.lstsq(design, measured - y_uniform_0, rcond=None)
    return coefficients


def initial_state(model: ThermalModel, series: MeasuredSeries, coefficients=None) -> np.ndarray:
    """Initial state (°C) for ``(a, c)`` = ``coefficients`` (default: first-sample match)."""
    a, c = initial_coefficients(model, series) if coefficients is None else coefficients
    u0 = series.input_matrix[:, 0]
    t_ref = float(u0[model.input_names.index(model.spec.interface.coolant_input)])
    return c + a * (model.steady_state(u0) - t_ref)


def error_metrics(predicted, measured) -> dict:
    """RMSE, MAE, max |error|, bias (K), R² and the sample count over the finite pairs."""
    predicted, measured = np.asarray(predicted, float), np.asarray(measured, float)
    valid = np.isfinite(measured) & np.isfinite(predicted)
    if not valid.any():
        return {"n": 0, "rmse": None, "mae": None, "max_abs": None, "bias": None, "r2": None}
    e = predicted[valid] - measured[valid]
    spread = float(np.sum((measured[valid] - measured[valid].mean()) ** 2))
    r2 = 1.0 - float(np.sum(e ** 2)) / spread if spread > 0 else None
    return {"n": int(valid.sum()), "rmse": float(np.sqrt(np.mean(e ** 2))), "mae": float(np.mean(np.abs(e))),
            "max_abs": float(np.max(np.abs(e))), "bias": float(np.mean(e)), "r2": r2}


def winding_rate_K_per_min(time_s: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Smoothed :math:`d\\theta/dt` (K/min): difference of moving averages half a window apart."""
    dt = float(np.median(np.diff(time_s)))
    half = max(1, int(round(RATE_WINDOW_S / dt / 2)))
    smooth = pd.Series(theta).interpolate(limit_direction="both").rolling(half, center=True, min_periods=1).mean()
    values = smooth.to_numpy()
    ahead, behind = np.roll(values, -half), np.roll(values, half)
    idx = np.arange(values.size)
    ahead[idx + half >= values.size] = values[-1]
    behind[idx - half < 0] = values[0]
    span = (np.minimum(idx + half, values.size - 1) - np.maximum(idx - half, 0)) * dt / 60.0
    return (ahead - behind) / np.maximum(span, dt / 60.0)


@dataclasses.dataclass
class Comparison:
    """Result of :func:`compare`.

    Attributes
    ----------
    model_name : str
    source : str
    frame : pandas.DataFrame
        ``time_s``, inputs, ``<sensor>_measured``, ``<sensor>_model``, ``<sensor>_residual``
        (model − measured, K) and the regressors (``regressor_labels``).
    metrics : dict
        JSON-ready: ``overall`` per sensor, ``by_load_band``, ``by_temperature_band``,
        ``by_heating``, ``by_hour`` (band → sensor → metrics), ``trend_K_per_h`` per sensor,
        ``initial_state``.
    output_names : list of str
    regressor_labels : dict
        Column of ``frame`` → label of the candidate regressors (:func:`regressors`).
    """

    model_name: str
    source: str
    frame: pd.DataFrame
    metrics: dict
    output_names: list
    regressor_labels: dict = dataclasses.field(default_factory=dict)

    def rmse(self) -> float:
        """Root-mean-square error over every valid sample of every sensor, K."""
        residuals = self.frame[[f"{n}_residual" for n in self.output_names]].to_numpy()
        return float(np.sqrt(np.nanmean(residuals ** 2)))


def _split(frame: pd.DataFrame, labels: pd.Series, outputs) -> dict:
    result = {}
    for label in pd.unique(labels):
        rows = frame[labels == label]
        result[str(label)] = {n: error_metrics(rows[f"{n}_model"], rows[f"{n}_measured"]) for n in outputs}
    return result


def _temperature_bands(theta: np.ndarray) -> pd.Series:
    edges = np.nanquantile(theta, [1 / 3, 2 / 3])
    names = [f"cool (< {edges[0]:.0f} °C)", f"warm ({edges[0]:.0f}-{edges[1]:.0f} °C)", f"hot (>= {edges[1]:.0f} °C)"]
    return pd.Series(np.array(names)[np.searchsorted(edges, np.nan_to_num(theta, nan=edges[0]), side="right")])


def compare(model: ThermalModel, data, dt_s: float | None = None) -> Comparison:
    """Simulate ``model`` on the measured inputs and measure where it fails.

    Parameters
    ----------
    model : ThermalModel
    data : MeasurementData, pandas.DataFrame or path
        Measurements in the CSV schema of :mod:`genthermal.measurements`.
    dt_s : float, optional
        Resample the data to this period first, s.

    Returns
    -------
    Comparison
    """
    from ..onsets import onset_switches

    series = measured_series(data, dt_s, model.output_names, model.spec.interface)
    first_model, _ = onset_switches(model)
    coefficients = initial_coefficients(first_model, series)
    result = simulate(model, series.inputs, x0=initial_state(first_model, series, coefficients))
    frame = series.inputs.copy()
    for i, name in enumerate(model.output_names):
        frame[f"{name}_measured"] = series.outputs[i]
        frame[f"{name}_model"] = result[name].to_numpy()
        frame[f"{name}_residual"] = frame[f"{name}_model"] - frame[f"{name}_measured"]
    theta = series.outputs[0]
    currents = list(model.spec.interface.load_currents)
    frame["I_squared"] = np.mean([frame[p] ** 2 for p in currents], axis=0)
    frame["theta_winding"] = theta
    frame["dtheta_dt"] = winding_rate_K_per_min(series.time_s, theta)
    outputs = list(model.output_names)
    load_percent = 100.0 * frame[currents].abs().mean(axis=1) / model.spec.rated_current_A
    load = pd.Series([next(label for edge, label in LOAD_BANDS if v < edge) for v in load_percent])
    rate = frame["dtheta_dt"]
    heating = pd.Series(np.where(rate > STEADY_RATE_K_PER_MIN, "heating",
                                 np.where(rate < -STEADY_RATE_K_PER_MIN, "cooling", "steady")))
    hours = ((series.time_s - series.time_s[0]) // 3600).astype(int)
    hour = pd.Series([f"hour {h + 1}" for h in hours])
    elapsed_h = (series.time_s - series.time_s[0]) / 3600.0
    trend = {}
    for name in outputs:
        e = frame[f"{name}_residual"].to_numpy()
        ok = np.isfinite(e)
        trend[name] = float(np.polyfit(elapsed_h[ok], e[ok], 1)[0]) if ok.sum() > 2 and np.ptp(elapsed_h[ok]) > 0 else 0.0
    metrics = {
        "model": model.name, "data": series.source, "samples": int(series.time_s.size), "dt_s": series.dt_s,
        "overall": {n: error_metrics(frame[f"{n}_model"], frame[f"{n}_measured"]) for n in outputs},
        "rmse_all_sensors": None,
        "by_load_band": _split(frame, load, outputs),
        "by_temperature_band": _split(frame, _temperature_bands(theta), outputs),
        "by_heating": _split(frame, heating, outputs),
        "by_hour": _split(frame, hour, outputs),
        "trend_K_per_h": trend,
        "initial_state": {"a": float(coefficients[0]), "c_C": float(coefficients[1]),
                          "method": "blend of soaked and loaded steady state matching the first sample"},
    }
    comparison = Comparison(model.name, series.source, frame, metrics, outputs, regressors(model.spec.interface))
    metrics["rmse_all_sensors"] = comparison.rmse()
    return comparison
