r"""The baseline fault detector: a CUSUM on the Kalman filter's differential winding innovations.

This is the detector the closed loop flew first (commit 9399c62, replaced by the disturbance
detector of :mod:`genthermal.schedule.detector`), and the simplest one an engineer would write:
per generator g a Kalman filter on the nominal linear design model (thesis 6.2,
:class:`~genthermal.estimation.kalman.KalmanFilter`), updated once per management cycle with the
measured winding and iron temperatures. Its winding innovation :math:`e_g = y_g - \hat y_g^-` (K)
is compared with the other generators', which share the model's error,

.. math::
    d_g = e_g - \operatorname{median}_{h \ne g} e_h,

and fed to a one-sided CUSUM (Page 1954) :math:`S_k = \max(0, S_{k-1} + d_k - \nu)`, alarm when
:math:`S_k > h` (then the sum restarts). As in the original, a generator is tested only when its
mean current over the cycle is not above the others' median (a generator that took load on sees
the model's load-dependent error as a fault), from the second cycle on.

:func:`innovation_cusum_alarms` runs it on a flight's record (the currents applied, the measured
inlet and the noisy sensors the manager saw), so it sees exactly what the flight's own detector
saw; on a flight that does not re-plan (``ManagerSettings.replan`` False) the record does not
depend on the detector, and the two are compared on the same flights.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import InputError
from ..estimation.kalman import KalmanFilter


@dataclasses.dataclass(frozen=True)
class InnovationCusumSettings:
    """Drift and threshold of the differential-innovation CUSUM.

    Attributes
    ----------
    drift_K : float
        :math:`\\nu`, K. Default 0.25 K, threshold 0.2 K: the values the detector flew with
        (``DetectionSettings.fault_drift``/``fault_threshold`` of commit 9399c62).
    threshold_K : float
        :math:`h`, K.
    """

    drift_K: float = 0.25
    threshold_K: float = 0.2

    def __post_init__(self):
        for name in ("drift_K", "threshold_K"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise InputError(f"innovation_cusum.{name}", value, "must be a finite number of kelvin >= 0")


def innovation_cusum_alarms(design_generator, currents_A, inlet_C, measured_C, ambient_C: float, dt_s: float,
                            cycle_steps: int, settings: InnovationCusumSettings = InnovationCusumSettings()) -> list:
    """Run the baseline detector (module docstring) on a flight's record.

    Parameters
    ----------
    design_generator : AffineGenerator
        The nominal design model the filters run on (``PowerSystem.design_generator_for(())``).
    currents_A : array_like
        (n_generators, n) phase current applied during each step, A RMS.
    inlet_C : array_like
        (n_generators, n) measured coolant inlet temperature during each step, °C.
    measured_C : array_like
        (n_generators, n_sensors, n) sensor temperatures measured at the end of each step, °C
        (winding first).
    ambient_C : float
    dt_s : float
        Step, s.
    cycle_steps : int
        Steps per management cycle: the filters are updated at the end of every cycle.
    settings : InnovationCusumSettings

    Returns
    -------
    list of dict
        ``time_s`` (end of the cycle, s from the record's start), ``generator`` (index) and
        ``statistic`` (the CUSUM sum, K) of every alarm.
    """
    currents, inlets, measured = (np.asarray(a, dtype=float) for a in (currents_A, inlet_C, measured_C))
    n_gen, n = currents.shape
    if n_gen < 2:
        raise InputError("currents_A", f"{n_gen} generator", "the differential test needs at least 2 generators")
    if inlets.shape != currents.shape or measured.shape[0] != n_gen or measured.shape[2] != n:
        raise InputError("measured_C", measured.shape, f"must be ({n_gen}, n_sensors, {n}) with inlet_C {currents.shape}")
    if int(cycle_steps) != cycle_steps or cycle_steps < 1:
        raise InputError("cycle_steps", cycle_steps, "must be a whole number of steps >= 1")
    kalman = KalmanFilter(design_generator.model, dt_s)
    x = [np.full(design_generator.model.n_states, float(ambient_C)) for _ in range(n_gen)]
    P = [kalman.P0 for _ in range(n_gen)]
    sums, alarms = np.zeros(n_gen), []
    for cycle, start in enumerate(range(0, n, int(cycle_steps))):
        stop = min(start + int(cycle_steps), n)
        for g in range(n_gen):
            for i in range(start, stop):
                x[g], P[g] = kalman.predict(x[g], P[g], design_generator.input(currents[g, i], inlets[g, i], ambient_C))
        if stop == n:  # the record ends: no measurement update follows in flight
            break
        innovations = np.empty(n_gen)
        for g in range(n_gen):
            step = kalman.update(x[g], P[g], measured[g, :, stop - 1])
            x[g], P[g], innovations[g] = step.x, step.P, step.innovation[0]
        if cycle == 0:  # the flight's monitor tests from its second record on
            continue
        load = currents[:, start:stop].mean(axis=1)
        for g in range(n_gen):
            others = np.delete(np.arange(n_gen), g)
            if load[g] > np.median(load[others]) + 1e-9:
                continue
            sums[g] = max(0.0, sums[g] + innovations[g] - np.median(innovations[others]) - settings.drift_K)
            if sums[g] > settings.threshold_K:
                alarms.append({"time_s": stop * dt_s, "generator": g, "statistic": float(sums[g])})
                sums[g] = 0.0
    return alarms
