"""Faulty input sensors: the coolant-inlet and ambient PT100s feed the model, not its outputs.

A fault of an input sensor drives the model with a wrong input, so every output moves by the
model's own response to the error (:func:`input_step_response`). Bias and drift of each input are
fitted at every onset and scored on the RSS over all outputs like a single-sensor fault. Stuck
and noisier readings are claimed from the reading alone (:mod:`~genthermal.diagnose.input_readings`).
Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import math

import numpy as np

from ..simulate import simulate
from ..sensor_faults import SensorFault
from .sensor_faults import ONSET_GRID, SensorHypothesis, _onset_grid

#: Shapes of an input sensor's fault.
INPUT_KINDS = ("bias", "drift")


def input_sensors(interface) -> list:
    """The temperature inputs measured by a sensor: the coolant inlet and the ambient (those the
    machine has)."""
    names = [getattr(interface, "coolant_input", None), getattr(interface, "ambient_input", None)]
    known = {i.name for i in interface.inputs}
    return [n for n in dict.fromkeys(names) if n and n in known]


def input_step_response(model, inputs, name: str, output_names) -> np.ndarray:
    """Response of the outputs to a 1-K step of input ``name`` at the first sample, K.

    Parameters
    ----------
    model : ThermalModel
    inputs : pandas.DataFrame
        ``time_s`` and the model inputs (the record's).
    name : str
        The input stepped.
    output_names : sequence of str
        Outputs returned, in order.

    Returns
    -------
    numpy.ndarray
        (n_outputs, N), K per K, 0 at the first sample.
    """
    x0 = float(inputs[name].iloc[0])
    base = simulate(model, inputs, x0=x0)
    stepped = inputs.copy()
    stepped[name] = stepped[name] + 1.0
    raised = simulate(model, stepped, x0=x0)
    return np.array([raised[o].to_numpy(float) - base[o].to_numpy(float) for o in output_names])


def _shifted(response: np.ndarray, onset: int) -> np.ndarray:
    shifted = np.zeros_like(response)
    shifted[:, onset:] = response[:, :response.shape[1] - onset]
    return shifted


def screen_inputs(model, series, residual: np.ndarray, output_names, onsets=None) -> SensorHypothesis | None:
    """The best bias or drift of an input sensor, scored on the RSS over all outputs.

    Parameters
    ----------
    model : ThermalModel
        The model the residual is of (its outputs are ``output_names``).
    series : MeasuredSeries
        The record on the diagnosis grid (its inputs drive the model).
    residual : numpy.ndarray
        (n_outputs, N) measured minus predicted, K.
    output_names : sequence of str
    onsets : array_like, optional
        Onset samples to try (default: the grid over the record, then every sample near the best).

    Returns
    -------
    SensorHypothesis or None
        ``fault.sensor`` the input's column, ``value`` how much it reads high (K, K/h),
        ``signal`` the fitted input error (N,), ``evidence`` ``"input"``; None when the model has
        no measured temperature input.
    """
    valid = np.isfinite(residual)
    n = int(valid.sum())
    if n < 10:
        return None
    target = np.where(valid, residual, 0.0)
    rss_before = float(target.ravel() @ target.ravel())
    elapsed = series.time_s - series.time_s[0]
    best = None
    for name in input_sensors(model.spec.interface):
        step = input_step_response(model, series.inputs, name, output_names)
        shapes = {"bias": step, "drift": np.cumsum(step, axis=1) * series.dt_s / 3600.0}
        for kind in INPUT_KINDS:
            response = shapes[kind]

            def fitted(onset, response=response):
                column = np.where(valid, -_shifted(response, onset), 0.0)
                norm = float(column.ravel() @ column.ravel())
                if norm <= 0.0:
                    return rss_before, 0.0
                value = float(column.ravel() @ target.ravel()) / norm
                return rss_before - value * value * norm, value

            if onsets is None:
                grid = list(range(0, 1)) + list(_onset_grid(elapsed.size, 1))
                coarse = {int(o): fitted(int(o)) for o in grid}
                centre = min(coarse, key=lambda o: coarse[o][0])
                near = range(max(0, centre - ONSET_GRID), min(elapsed.size - 3, centre + ONSET_GRID + 1))
                results = {**coarse, **{o: fitted(o) for o in near if o not in coarse}}
            else:
                results = {int(o): fitted(int(o)) for o in onsets}
            onset = min(results, key=lambda o: results[o][0])
            rss_after, value = results[onset]
            delta = n * math.log(max(rss_after, 1e-300) / max(rss_before, 1e-300)) + 2 * math.log(n)
            if best is None or delta < best.delta_bic:
                after = (np.arange(elapsed.size) >= onset).astype(float)
                error = value * (after if kind == "bias" else after * (elapsed - elapsed[onset]) / 3600.0)
                best = SensorHypothesis(SensorFault(name, kind, value, float(elapsed[onset])), onset,
                                        math.sqrt(rss_before / n), math.sqrt(max(rss_after, 0.0) / n), delta,
                                        "input", error, columns=(name,), output="")
    return best


def corrected_inputs(inputs, hypotheses):
    """``inputs`` (pandas.DataFrame) with the fitted errors of the input-sensor ``hypotheses``
    removed."""
    corrected = inputs.copy()
    for hypothesis in hypotheses:
        if hypothesis.evidence == "input" and hypothesis.fault.sensor in corrected:
            corrected[hypothesis.fault.sensor] = corrected[hypothesis.fault.sensor].to_numpy(float) - hypothesis.signal
    return corrected
