"""Synthetic rig data: a model driven by a mission, read through noisy sensors.

:func:`synthesize` simulates the plant with the true inputs and writes what the rig's logger would
record in the machine's :mod:`genthermal.measurements` schema: every sensor column with its own
white noise (thesis eq. 6.10), measured currents with a relative noise (``current_noise``, default
1 %), other inputs without noise. Guide: ``docs/guide/estimation.md``; the noise model:
``docs/guide/methods.md``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .errors import InputError
from .machines import DEFAULT_MACHINE, MACHINES
from .machines.interface import InputKind
from .measurements import required_columns
from .mission import Mission
from .model import ThermalModel
from .simulate import simulate, uniform_step

#: Sensor noise variances of the default machine, K² (thesis eq. 6.10: winding, iron).
THESIS_NOISE_VARIANCE_K2 = MACHINES[DEFAULT_MACHINE].interface.noise_variances_K2
#: Relative (1 sigma) noise of the measured currents.
DEFAULT_CURRENT_NOISE = 0.01


def synthesize(model: ThermalModel, mission_or_inputs, dt_s: float = 10.0, seed: int = 0,
               noise_var=None, current_noise: float = DEFAULT_CURRENT_NOISE,
               x0=None, switches=()) -> pd.DataFrame:
    r"""Simulate ``model`` on a mission and return what the rig's sensors would record.

    Parameters
    ----------
    model : ThermalModel
        The plant; its interface gives the sensors, their CSV columns and noise.
    mission_or_inputs : Mission or pandas.DataFrame
        A mission (sampled with :meth:`Mission.to_inputs` at ``dt_s``) or an input frame with
        ``time_s`` and the model inputs on a uniform grid (then its own step is used and ``dt_s``
        must agree with it).
    dt_s : float
        Sample period, s.
    seed : int
        Seed of the random generator (:func:`numpy.random.default_rng`); same seed, same data.
    noise_var : sequence of float, optional
        Noise variance of each sensor in K², in ``model.output_names`` order (the thesis
        generator: winding, iron), optionally followed by the outlet sensor's; default the
        variances of the machine's sensors.
    current_noise : float
        Relative standard deviation :math:`c` of the measured currents (0.01 = 1 %).
    x0 : array_like or float, optional
        Initial plant state, °C (default: the machine cold at the first ambient temperature).
    switches : sequence of (float, ThermalModel)
        Plant models that take over at an onset (a fault), as in :func:`genthermal.simulate.simulate`.

    Returns
    -------
    pandas.DataFrame
        ``time_s``, the inputs, the sensor columns and the outlet column if the machine has one
        (the thesis generator: ``time_s, I_u, I_v, I_w, I_exc, T_inlet, T_ambient, T_winding_u,
        T_winding_v, T_winding_w, T_iron, T_outlet``; s, A, °C).
    """
    interface = model.spec.interface
    variances = _noise_variances(noise_var, interface)
    if not (np.isfinite(current_noise) and current_noise >= 0):
        raise InputError("current_noise", current_noise, "must be a relative standard deviation >= 0")
    if isinstance(mission_or_inputs, Mission):
        inputs = mission_or_inputs.to_inputs(dt_s)
    elif isinstance(mission_or_inputs, pd.DataFrame):
        inputs = mission_or_inputs.reset_index(drop=True)
        step = uniform_step(inputs["time_s"].to_numpy(), "inputs.time_s") if "time_s" in inputs else None
        if step is not None and abs(step - dt_s) > 1e-9 * dt_s:
            raise InputError("dt_s", dt_s, f"the input frame is sampled every {step:g} s; pass dt_s={step:g}")
    else:
        raise InputError("mission_or_inputs", type(mission_or_inputs).__name__,
                         "expected a Mission or an input DataFrame")
    truth = simulate(model, inputs, x0=x0, switches=switches)
    rng = np.random.default_rng(seed)
    n = len(truth)
    frame = pd.DataFrame({"time_s": truth["time_s"].to_numpy()})
    for spec in interface.inputs:
        values = truth[spec.name].to_numpy()
        if spec.kind is InputKind.CURRENT:
            values = values * (1.0 + current_noise * rng.standard_normal(n))
            values = values if spec.signed else np.clip(values, 0.0, None)
        frame[spec.name] = values
    sensors = [*interface.sensors, *([interface.outlet_sensor] if interface.outlet_sensor else [])]
    for sensor, variance in zip(sensors, variances):
        if sensor.output not in truth:
            continue
        for column in sensor.columns:
            frame[column] = truth[sensor.output].to_numpy() + np.sqrt(variance) * rng.standard_normal(n)
    optional = [c for c in interface.optional_columns if c in frame]
    return frame[[*required_columns(interface), *optional]]


def _noise_variances(noise_var, interface) -> tuple[float, ...]:
    """Check the per-sensor variances (K²) and complete them with the interface's (outlet last)."""
    defaults = [*interface.noise_variances_K2,
                *([interface.outlet_sensor.noise_variance_K2] if interface.outlet_sensor else [])]
    if noise_var is None:
        return tuple(defaults)
    try:
        given = [float(v) for v in noise_var]
    except (TypeError, ValueError):
        raise InputError("noise_var", noise_var, f"expected one variance in K² per sensor "
                         f"({', '.join(interface.output_names)})") from None
    if not len(interface.output_names) <= len(given) <= len(defaults):
        raise InputError("noise_var", noise_var, f"expected one variance in K² per sensor "
                         f"({', '.join(interface.output_names)}), optionally one more for the outlet")
    for name, value in zip([*interface.output_names, "outlet"], given):
        if not (np.isfinite(value) and value >= 0):
            raise InputError(f"noise_var ({name})", value, "a variance must be a number >= 0 (K²)")
    return tuple(given + defaults[len(given):])
