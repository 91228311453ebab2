"""A CUSUM on the Kalman filter's differential winding innovations: the baseline fault detector,
and the alarm test the flight's fault monitor runs beside the disturbance CUSUM; optionally
whitened by the AR(1) level and correlation it learns in its first updates. Method:
docs/guide/flight-methods.md.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ...diagnose.error_model import ar1
from ...errors import InputError
from ...estimation.kalman import KalmanFilter

#: Fewest updates :attr:`InnovationCusumSettings.learn_updates` may learn from (a mean and a
#: lag-1 correlation from fewer samples say nothing).
MIN_LEARN_UPDATES = 6


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
    inlet_tolerance_K : float or None
        A generator is compared only with references whose mean inlet temperature over the
        cycle is at most this much above its own, K (None: every reference, the original). The
        generators breathe the same air unless a fault heats one's inlet; that one's filter
        then carries a model error of its own, which its references would see mirrored. On
        blockage_large the blocked unit's inlet rose 31 K from 66 min, its filter predicted it
        too warm, and the healthy unit alarmed at 70 min. The unit with the hotter inlet is still
        tested. In flight 1 K (``DetectionSettings.innovation``): any margin above 0 separates
        the shared inlet from a heated one.
    learn_updates : int
        0: the differential innovation :math:`d_g` is the statistic (the original). Otherwise
        each generator's first ``learn_updates`` tested values of :math:`d_g` learn its unit's
        own difference from its sisters: a level :math:`\\mu_g` per squared mean phase current
        :math:`I_g^2` (K/A², least squares through the origin: a unit whose losses or cooling
        differ from its sisters' by a few per cent differs in proportion to its losses) and the
        lag-1 correlation :math:`\\phi_g` of what that leaves
        (:func:`~genthermal.diagnose.error_model.ar1`, the offline error model's estimator). From
        then on the statistic is :math:`(d_g - \\mu_g I_g^2)\\sqrt{(1-\\phi_g)/(1+\\phi_g)}`, whose
        CUSUM sum grows no faster than that of white noise of the same level. While it learns,
        the generator is not tested (the disturbance test watches it). Relearnt when the
        generator's believed effects change. In flight 8 (``DetectionSettings.innovation``): the
        test runs from the second 5-min cycle, so the learning ends at 45 min, before the
        robustness grid's earliest onset.
    """

    drift_K: float = 0.25
    threshold_K: float = 0.2
    inlet_tolerance_K: float | None = None
    learn_updates: int = 0

    def __post_init__(self):
        if not (isinstance(self.learn_updates, (int, np.integer)) and
                (self.learn_updates == 0 or self.learn_updates >= MIN_LEARN_UPDATES)):
            raise InputError("innovation_cusum.learn_updates", self.learn_updates,
                             f"must be 0 (no learning) or a whole number of updates >= {MIN_LEARN_UPDATES}: "
                             "a level and a lag-1 correlation need that many")
        for name in ("drift_K", "threshold_K", "inlet_tolerance_K"):
            value = getattr(self, name)
            if value is None and name == "inlet_tolerance_K":
                continue
            if not (np.isfinite(value) and value >= 0):
                raise InputError(f"innovation_cusum.{name}", value, "must be a finite number of kelvin >= 0")


class InnovationCusum:
    """The test of the module docstring, one management cycle at a time.

    Parameters
    ----------
    n_generators : int
        At least 2 (the test is differential).
    dt_s : float
        Filter step, s.
    ambient_C : float
        Initial node temperatures (the machines start at ambient), °C.
    design_generator : AffineGenerator
        Design model every filter starts on.
    settings : InnovationCusumSettings
    """

    def __init__(self, n_generators: int, dt_s: float, ambient_C: float, design_generator,
                 settings: InnovationCusumSettings = InnovationCusumSettings()):
        if n_generators < 2:
            raise InputError("generators.count", n_generators, "the differential innovation test needs at least 2 "
                             "generators")
        if not (np.isfinite(dt_s) and dt_s > 0):
            raise InputError("dt_s", dt_s, "must be a positive step in seconds")
        self.dt_s, self.ambient_C, self.settings = float(dt_s), float(ambient_C), settings
        self._filters: dict = {}
        self.generators = [design_generator] * n_generators
        kalman = self._filter(design_generator)
        self.x = [np.full(design_generator.model.n_states, self.ambient_C) for _ in range(n_generators)]
        self.P = [kalman.P0 for _ in range(n_generators)]
        self.sums = np.zeros(n_generators)
        #: Differential innovations :math:`d_g` of the last cycle tested, K (NaN: not tested).
        self.last_statistic = np.full(n_generators, np.nan)
        #: Mean inlet temperature of each generator over the steps last predicted, °C.
        self.last_inlet_C = np.full(n_generators, np.nan)
        #: Measurement updates so far: the test runs from the second on.
        self.updates = 0
        #: Per generator, the ``(d_g K, I_g² A²)`` learnt so far (``learn_updates``).
        self.learning = [[] for _ in range(n_generators)]
        #: Per generator, the learnt level :math:`\mu_g` (K/A²) and scale :math:`\sqrt{(1-\phi)/(1+\phi)}`
        #: (NaN until learnt).
        self.level = np.full(n_generators, np.nan)
        self.scale = np.full(n_generators, np.nan)

    def _filter(self, generator) -> KalmanFilter:
        if id(generator) not in self._filters:
            self._filters[id(generator)] = (generator, KalmanFilter(generator.model, self.dt_s))
        return self._filters[id(generator)][1]

    def use(self, g: int, generator, relearn: bool = False) -> None:
        """Continue generator ``g``'s filter on ``generator``'s design model (nodes carried over by
        name, covariance kept when the states are the same) and restart its sum; nothing happens
        when that model is already in use. With ``relearn`` (its believed effects changed) its
        learnt level and scale are learnt again."""
        if relearn:
            self.learning[g], self.level[g], self.scale[g] = [], np.nan, np.nan
        if generator is self.generators[g]:
            return
        old_names = self.generators[g].model.state_names
        new_names = generator.model.state_names
        kalman = self._filter(generator)
        if list(old_names) != list(new_names):
            carried = dict(zip(old_names, self.x[g]))
            self.x[g] = np.array([carried.get(name, self.ambient_C) for name in new_names])
            self.P[g] = kalman.P0
        self.generators[g] = generator
        self.sums[g] = 0.0

    def restart(self, g: int) -> None:
        """Clear generator ``g``'s sum."""
        self.sums[g] = 0.0

    def predict(self, g: int, currents_A, inlet_C) -> None:
        """Predict generator ``g``'s filter over the steps flown: phase currents (A RMS) and inlet
        temperatures (°C) in force during each step."""
        generator = self.generators[g]
        kalman = self._filter(generator)
        if len(inlet_C):
            self.last_inlet_C[g] = float(np.mean(inlet_C))
        for current, inlet in zip(np.asarray(currents_A, dtype=float), np.asarray(inlet_C, dtype=float)):
            self.x[g], self.P[g] = kalman.predict(self.x[g], self.P[g], generator.input(current, inlet,
                                                                                           self.ambient_C))

    def update(self, measured_C, mean_currents_A, references=None) -> list:
        """Correct every filter with the cycle's end readings and run the test.

        Parameters
        ----------
        measured_C : array_like
            (n_generators, n_sensors) readings, °C (winding first; NaN = not measured).
        mean_currents_A : array_like
            (n_generators,) mean phase current over the cycle, A RMS: a generator that carries
            more than its references' median is not tested.
        references : sequence of sequence of int, optional
            Per generator, the generators it is compared with (default: all the others). A
            generator without a reference, or without a winding innovation, is not tested.

        Returns
        -------
        list of (int, float)
            Generators that alarm, with their CUSUM sum (K); their sums restart.
        """
        measured = np.asarray(measured_C, dtype=float)
        load = np.asarray(mean_currents_A, dtype=float)
        n = len(self.x)
        all_innovations = np.full(measured.shape, np.nan)
        for g in range(n):
            step = self._filter(self.generators[g]).update(self.x[g], self.P[g], measured[g])
            self.x[g], self.P[g], all_innovations[g] = step.x, step.P, step.innovation
        innovations = all_innovations[:, 0]
        self.updates += 1
        self.last_statistic = np.full(n, np.nan)
        if self.updates < 2:  # the first update corrects the ambient start: nothing to compare yet
            return []
        alarms = []
        for g in range(n):
            others = [h for h in (range(n) if references is None else references[g])
                      if h != g and np.isfinite(innovations[h])]
            if self.settings.inlet_tolerance_K is not None:
                others = [h for h in others
                          if not self.last_inlet_C[h] > self.last_inlet_C[g] + self.settings.inlet_tolerance_K]
            if not others or not np.isfinite(innovations[g]) or load[g] > np.median(load[others]) + 1e-9:
                continue
            d = innovations[g] - float(np.median(innovations[others]))
            self.last_statistic[g] = d
            statistic = self._whitened(g, d, float(load[g]) ** 2)
            if statistic is None:  # still learning: not tested
                continue
            self.sums[g] = max(0.0, self.sums[g] + statistic - self.settings.drift_K)
            if self.sums[g] > self.settings.threshold_K:
                alarms.append((g, float(self.sums[g])))
                self.sums[g] = 0.0
        return alarms


    def _whitened(self, g: int, d: float, current_squared: float) -> float | None:
        """The statistic of generator ``g``'s differential innovation ``d`` (K) at squared mean
        phase current ``current_squared`` (A²); None while it learns its level and scale
        (``learn_updates``, :class:`InnovationCusumSettings`)."""
        if not self.settings.learn_updates:
            return d
        if np.isfinite(self.level[g]):
            return (d - self.level[g] * current_squared) * self.scale[g]
        self.learning[g].append((d, current_squared))
        if len(self.learning[g]) < self.settings.learn_updates:
            return None
        learnt, squared = np.array(self.learning[g]).T
        self.level[g] = float((learnt @ squared) / (squared @ squared)) if squared @ squared > 0 else 0.0
        _, phi = ar1(learnt - self.level[g] * squared)
        self.scale[g] = float(np.sqrt((1.0 - phi) / (1.0 + phi)))
        return None


def innovation_cusum_alarms(design_generator, currents_A, inlet_C, measured_C, ambient_C: float, dt_s: float,
                            cycle_steps: int, settings: InnovationCusumSettings = InnovationCusumSettings()) -> list:
    """Run the baseline detector (module docstring) on a flight's record: the nominal design
    model throughout, every other generator a reference.

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
    test = InnovationCusum(n_gen, dt_s, ambient_C, design_generator, settings)
    alarms = []
    for start in range(0, n, int(cycle_steps)):
        stop = min(start + int(cycle_steps), n)
        for g in range(n_gen):
            test.predict(g, currents[g, start:stop], inlets[g, start:stop])
        if stop == n:  # the record ends: no measurement update follows in flight
            break
        for g, statistic in test.update(measured[:, :, stop - 1], currents[:, start:stop].mean(axis=1)):
            alarms.append({"time_s": stop * dt_s, "generator": g, "statistic": statistic})
    return alarms
