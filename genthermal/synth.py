r"""Synthetic rig data: a model driven by a mission, read through noisy sensors.

The *plant* (usually the nonlinear simulation model, possibly with changed parameters to stand for
the real machine) is simulated with the true inputs. What the rig's logger would record is then
written in the :mod:`genthermal.measurements` CSV schema:

* ``T_winding_u``, ``T_winding_v``, ``T_winding_w``: the three stator-winding PT100s all read the
  stator winding node, each with its own white Gaussian noise of variance
  :math:`\sigma_w^2` (thesis eq. 6.10: 0.0082 K²);
* ``T_iron`` (stator iron node) and ``T_outlet`` (outlet air): white Gaussian noise of variance
  :math:`\sigma_i^2` (thesis eq. 6.10: 0.013 K², used for both PT100 channels);
* ``I_u, I_v, I_w, I_exc``: the measured currents are
  :math:`I_{meas} = I_{true}\,(1 + \epsilon)`, :math:`\epsilon \sim N(0, c^2)` (``current_noise``
  :math:`c`, default 1 %), clipped at 0 A. The plant itself sees the true currents, so a model
  driven by the recorded currents sees slightly wrong losses, as it would on the rig;
* ``T_inlet``, ``T_ambient``: recorded without noise (they are boundary inputs, not states).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .errors import InputError
from .losses import INPUT_NAMES, PHASE_CURRENTS
from .measurements import REQUIRED_COLUMNS, WINDING_SENSORS
from .mission import Mission
from .model import ThermalModel
from .simulate import simulate, uniform_step

#: Sensor noise variances of thesis eq. 6.10, K²: (stator winding, stator iron).
THESIS_NOISE_VARIANCE_K2 = (0.0082, 0.013)
#: Relative (1 sigma) noise of the measured currents.
DEFAULT_CURRENT_NOISE = 0.01
CURRENT_COLUMNS = (*PHASE_CURRENTS, "I_exc")


def synthesize(model: ThermalModel, mission_or_inputs, dt_s: float = 10.0, seed: int = 0,
               noise_var=THESIS_NOISE_VARIANCE_K2, current_noise: float = DEFAULT_CURRENT_NOISE,
               x0=None, switches=()) -> pd.DataFrame:
    r"""Simulate ``model`` on a mission and return what the rig's sensors would record.

    Parameters
    ----------
    model : ThermalModel
        The plant (a model with ``T_winding`` and ``T_iron`` outputs).
    mission_or_inputs : Mission or pandas.DataFrame
        A mission (sampled with :meth:`Mission.to_inputs` at ``dt_s``) or an input frame with
        ``time_s`` and the model inputs on a uniform grid (then its own step is used and ``dt_s``
        must agree with it).
    dt_s : float
        Sample period, s.
    seed : int
        Seed of the random generator (:func:`numpy.random.default_rng`); same seed, same data.
    noise_var : (float, float)
        Variances :math:`(\sigma_w^2, \sigma_i^2)` in K² of each winding sensor and of the iron
        (and outlet) sensor.
    current_noise : float
        Relative standard deviation :math:`c` of the measured currents (0.01 = 1 %).
    x0 : array_like or float, optional
        Initial plant state, °C (default: the machine cold at the first ambient temperature).
    switches : sequence of (float, ThermalModel)
        Plant models that take over at an onset (a fault), as in :func:`genthermal.simulate.simulate`.

    Returns
    -------
    pandas.DataFrame
        Columns ``time_s, I_u, I_v, I_w, I_exc, T_inlet, T_ambient, T_winding_u, T_winding_v,
        T_winding_w, T_iron, T_outlet`` (s, A, °C).
    """
    winding_var, iron_var = _noise_variances(noise_var)
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
    for output in ("T_winding", "T_iron"):
        if output not in model.output_names:
            raise InputError("model", model.name, f"has no output {output}; outputs: {model.output_names}")
    truth = simulate(model, inputs, x0=x0, switches=switches)
    rng = np.random.default_rng(seed)
    n = len(truth)
    frame = pd.DataFrame({"time_s": truth["time_s"].to_numpy()})
    for name in INPUT_NAMES:
        values = truth[name].to_numpy()
        if name in CURRENT_COLUMNS:
            values = np.clip(values * (1.0 + current_noise * rng.standard_normal(n)), 0.0, None)
        frame[name] = values
    for sensor in WINDING_SENSORS:
        frame[sensor] = truth["T_winding"].to_numpy() + np.sqrt(winding_var) * rng.standard_normal(n)
    frame["T_iron"] = truth["T_iron"].to_numpy() + np.sqrt(iron_var) * rng.standard_normal(n)
    if "T_outlet" in truth:
        frame["T_outlet"] = truth["T_outlet"].to_numpy() + np.sqrt(iron_var) * rng.standard_normal(n)
    return frame[[*REQUIRED_COLUMNS, *(["T_outlet"] if "T_outlet" in frame else [])]]


def _noise_variances(noise_var) -> tuple[float, float]:
    """Check and unpack ``(winding, iron)`` variances, K²."""
    try:
        winding_var, iron_var = (float(v) for v in noise_var)
    except (TypeError, ValueError):
        raise InputError("noise_var", noise_var, "expected two variances (winding, iron) in K²") from None
    for name, value in (("noise_var[0] (winding)", winding_var), ("noise_var[1] (iron)", iron_var)):
        if not (np.isfinite(value) and value >= 0):
            raise InputError(name, value, "a variance must be a number >= 0 (K²)")
    return winding_var, iron_var
