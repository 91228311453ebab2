"""Input-sensor faults told by the reading alone: a coolant-inlet or ambient PT100 that froze or got noisier.

:func:`screen_input_readings` claims a stuck reading (:func:`~genthermal.diagnose.onset_signatures.frozen_tail`)
or a noise increase (:func:`~genthermal.diagnose.sensor_faults.fit_noise_increase`) without a
model, on readings with real noise (at least :data:`MIN_READING_NOISE_K`); a reading logged without
noise that stays constant is what a healthy one looks like. Guide: ``docs/guide/evidence.md``.
"""

from __future__ import annotations

import numpy as np

from ..sensor_faults import SensorFault
from .onset_signatures import FROZEN_MIN_S, FROZEN_MIN_SAMPLES, frozen_tail
from .search import noise_std
from .sensor_faults import MIN_NOISE_FACTOR, PREFERENCE_BIC, SensorHypothesis, fit_noise_increase

#: Noise standard deviation a working input PT100 shows at least, K: the resolution of a logger
#: reading to 0.01 K (:data:`~genthermal.diagnose.onset_signatures.FROZEN_TOLERANCE`). A
#: noise-free logged input that wanders smoothly (a 3-K, 2-h wander sampled at 60 s) shows 0.003 K
#: in its second differences, below it.
MIN_READING_NOISE_K = 0.01


def screen_input_readings(inputs, names, elapsed_s: np.ndarray, exclude=()) -> list:
    """Input sensors whose reading froze or got noisier (module docstring).

    Parameters
    ----------
    inputs : pandas.DataFrame
        The record's inputs on the diagnosis grid.
    names : sequence of str
        The input sensors (:func:`~genthermal.diagnose.input_sensors.input_sensors`).
    elapsed_s : numpy.ndarray
        Time from the start, s.
    exclude : collection of str
        Sensors already explained.

    Returns
    -------
    list of SensorHypothesis
        ``evidence`` ``"frozen"`` (stuck, held value in °C) or ``"noise"`` (factor).
    """
    found = []
    dt_s = float(elapsed_s[1] - elapsed_s[0]) if elapsed_s.size > 1 else float("nan")
    for name in (n for n in names if n in inputs and n not in exclude):
        reading = inputs[name].to_numpy(float)
        onset, held, noise_before = frozen_tail(reading)
        samples = int(np.isfinite(reading[onset:]).sum())
        if 0 < onset < reading.size and samples * dt_s >= FROZEN_MIN_S and samples >= FROZEN_MIN_SAMPLES \
                and noise_before >= MIN_READING_NOISE_K:
            fault = SensorFault(name, "stuck", held, float(elapsed_s[onset]))
            found.append(SensorHypothesis(fault, onset, float("nan"), float("nan"), float("nan"), "frozen",
                                          np.zeros(elapsed_s.size),
                                          f"{samples} equal samples after a noise of {noise_before:.2f} K",
                                          columns=(name,), output=""))
            continue
        factor, onset, delta = fit_noise_increase(reading, elapsed_s)
        noise_after = noise_std(reading[None, onset:])
        if factor >= MIN_NOISE_FACTOR and delta < -PREFERENCE_BIC and noise_after >= MIN_READING_NOISE_K:
            fault = SensorFault(name, "noise", float(factor), float(elapsed_s[onset]))
            found.append(SensorHypothesis(fault, onset, float("nan"), float("nan"), delta, "noise",
                                          np.zeros(elapsed_s.size), "", columns=(name,), output=""))
    return found
