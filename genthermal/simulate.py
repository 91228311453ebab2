"""Whole-horizon simulation of a ThermalModel on an input time series → pandas DataFrame.

Input frames have the model's inputs (``model.input_names``) plus ``time_s`` on a
uniform grid; the value at row k is held over ``[t_k, t_k + dt)`` (zero-order hold). The output has
one row per input row: ``time_s``, the inputs, ``T_<state node>`` for every state, the sensor
outputs (``model.output_names``) and the outlet sensor's column when the machine has one, all °C.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .errors import InputError
from .model import ThermalModel


def uniform_step(time_s: np.ndarray, field: str = "time_s") -> float:
    """Return the sampling step (s) of a uniform time grid, or raise InputError naming ``field``."""
    time_s = np.asarray(time_s, dtype=float)
    if time_s.size < 2:
        raise InputError(field, time_s.size, "need at least two samples")
    steps = np.diff(time_s)
    dt = float(np.median(steps))
    if dt <= 0 or np.max(np.abs(steps - dt)) > 1e-6 * max(dt, 1.0):
        bad = int(np.argmax(np.abs(steps - dt)))
        raise InputError(f"{field}[{bad + 1}]", float(time_s[bad + 1]),
                         f"times must be uniformly spaced (step {dt:g} s); resample first")
    return dt


def input_matrix(inputs: pd.DataFrame, model: ThermalModel) -> np.ndarray:
    """Return the inputs of ``model`` as an array of shape (n_inputs, n_samples), checking columns
    and values."""
    names = list(model.input_names)
    missing = [c for c in ("time_s", *names) if c not in inputs.columns]
    if missing:
        raise InputError("inputs", missing, f"missing columns; {model.name} needs time_s and {', '.join(names)}")
    U = inputs[names].to_numpy(dtype=float).T
    bad = np.argwhere(~np.isfinite(U))
    if bad.size:
        row, col = bad[0][1], bad[0][0]
        raise InputError(f"inputs.{names[col]}[{row}]", U[col, row], "inputs must be finite numbers")
    return U


def initial_state(model: ThermalModel, u0: np.ndarray, x0=None) -> np.ndarray:
    """The initial state: ``x0`` if given (a scalar fills every node), else every node at the
    ambient temperature of the first input sample (a cold machine)."""
    if x0 is None:
        return np.full(model.n_states, float(u0[model.input_names.index(model.spec.interface.ambient_input)]))
    x0 = np.broadcast_to(np.asarray(x0, dtype=float), (model.n_states,)).copy()
    if not np.all(np.isfinite(x0)):
        raise InputError("x0", x0.tolist(), "initial temperatures must be finite numbers in °C")
    return x0


def simulate(model: ThermalModel, inputs: pd.DataFrame, x0=None, switches=None) -> pd.DataFrame:
    """Simulate ``model`` over the input time series.

    Parameters
    ----------
    model : ThermalModel
        Nonlinear simulation model or linear design model.
    inputs : pandas.DataFrame
        ``time_s`` (uniform) and the model inputs (A RMS, A, °C, °C).
    x0 : array_like or float, optional
        Initial state temperatures (°C); default: every node at the first ambient temperature.
    switches : sequence of (float, ThermalModel)
        Models that take over at an onset time in s (a fault, an effect with an onset): from the
        first sample at or after the onset, the state is propagated by that model. All models must
        have the same states. Default: the switches of the effects' onsets the model carries
        (:func:`genthermal.onsets.onset_switches`, onsets counted from the first sample).

    Returns
    -------
    pandas.DataFrame
        See the module docstring for the columns.
    """
    time_s = inputs["time_s"].to_numpy(dtype=float) if "time_s" in inputs else None
    U = input_matrix(inputs, model)
    dt = uniform_step(time_s)
    if model.spec.onsets:
        if switches:
            raise InputError("switches", len(switches), f"{model.name} carries effect onsets already; "
                             "give either the onsets or switches")
        from .onsets import onset_switches

        model, switches = onset_switches(model, float(time_s[0]))
    x0 = initial_state(model, U[:, 0], x0)
    segments = _segments(model, time_s, switches or ())
    n = U.shape[1]
    X = np.empty((model.n_states, n))
    X[:, 0] = x0
    for segment_model, start, end in segments:  # its steps start..end-1 give states start+1..end
        last = min(end, n - 1)
        if last > start:
            X[:, start + 1:last + 1] = np.asarray(
                segment_model.discretise(dt).simulator(last - start)(X[:, start], U[:, start:last]))
    _check_finite(X, time_s)
    frames = [results_frame(m, time_s[a:b], U[:, a:b], X[:, a:b]) for m, a, b in segments]
    return pd.concat(frames, ignore_index=True)


def _check_finite(X: np.ndarray, time_s: np.ndarray) -> None:
    """A state that is not a finite number means inputs or parameters beyond what the model can
    take: refuse the run rather than report inf or NaN temperatures."""
    bad = np.flatnonzero(~np.isfinite(X).all(axis=0))
    if bad.size:
        raise InputError("simulation", f"t = {time_s[bad[0]]:g} s",
                         "the temperatures are no longer finite numbers from this time on: the inputs "
                         "(currents, temperatures) or parameters are beyond anything the machine can carry")


def _segments(model: ThermalModel, time_s: np.ndarray, switches) -> list[tuple[ThermalModel, int, int]]:
    """Split the sample indices into (model, first index, end index) runs at the switch times."""
    bounds, models = [0], [model]
    for k, (onset, new_model) in enumerate(sorted(switches, key=lambda item: item[0])):
        if new_model.state_names != model.state_names:
            raise InputError(f"switches[{k}]", new_model.name, "the switched-to model must have the same states")
        if not np.isfinite(onset) or onset < time_s[0]:
            raise InputError(f"switches[{k}].onset_s", onset, f"must be a time >= {time_s[0]:g} s")
        index = int(np.searchsorted(time_s, onset - 1e-9))
        if index >= len(time_s):
            continue  # after the end of the run: never takes over
        if index == bounds[-1]:
            models[-1] = new_model
        else:
            bounds.append(index)
            models.append(new_model)
    bounds.append(len(time_s))
    return [(models[i], bounds[i], bounds[i + 1]) for i in range(len(models))]


def results_frame(model: ThermalModel, time_s: np.ndarray, U: np.ndarray, X: np.ndarray) -> pd.DataFrame:
    """Assemble the output DataFrame from times, inputs (n_inputs × n) and states (n_states × n)."""
    nodes = np.asarray(model.functions["nodes"].map(X.shape[1])(X, U, model.p0))
    order = model.node_order
    columns = {"time_s": time_s}
    columns.update({name: U[i] for i, name in enumerate(model.input_names)})
    columns.update({f"T_{name}": X[i] for i, name in enumerate(model.state_names)})
    for output, node in model.spec.sensors.items():
        columns[output] = nodes[order.index(node)]
    outlet = model.spec.interface.outlet_sensor
    if outlet is not None:
        columns[outlet.output] = nodes[order.index(outlet.node)]
    return pd.DataFrame(columns)
