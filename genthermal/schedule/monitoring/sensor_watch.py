"""Output-sensor faults in flight (winding, iron): tell them from machine faults, then mask or
correct them. Main objects: :class:`SensorWatch`, :class:`SensorWatchSettings`. Method:
docs/guide/flight-methods.md.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ...errors import InputError
from ...sensor_faults import SensorFault
from .monitor import Cusum
from ..state_estimator import believed_model
from .raw_evidence import RawEvidenceSettings, unsupported
from .sensor_patterns import UnconfirmedExcess, frozen_since, opposite_flows

#: The ``action`` of a claimed bias (module docstring, "Acting on a claim").
CORRECTED = "bias subtracted in the filter; masked in the record and the fault test"
#: What is done with a sensor claimed *noisier*: nothing. Its reading is still unbiased, and masked it
#: left its unit's winding unobserved: on the robustness grid's case 45 (a k_flow 0.25 blockage with
#: a 22.7-K inlet rise on gen1 of 3) the record check, run on the minute-averaged record, took the
#: blockage's transient for a winding sensor 2.6 times noisier at 130 min, masked it, and all three
#: schedulers then flew the blocked winding to 135-139 °C (3180-3800 s above θmax).
NOISE_KEPT = "kept in the filter and the fault test: a noisier reading is still unbiased"


@dataclasses.dataclass(frozen=True)
class SensorWatchSettings:
    """Sensor-fault detection in flight.

    Attributes
    ----------
    drift, threshold : float
        :math:`\\nu, h` of the two-sided CUSUM on the differential normalised innovation (units of
        the innovation's standard deviation). A step of 5 σ alarms within one cycle; healthy
        differential innovations (standard deviation about :math:`\\sqrt 2`) rarely stay above
        1 σ: no check on the healthy Fig. 7.7 flight nor on the blockage_large flight. A drift is
        absorbed by the filter's disturbance states faster than it builds an innovation: it is not
        seen at these settings (the opposite-heat-flow test is there for it).
    min_check_interval_s : float
        Shortest time between two record checks of one generator, s.
    max_checks : int
        Record checks per generator and flight (10: a held belief is checked every cycle).
    identify_dt_s : float
        Sample period of the record handed to the check, s: a whole multiple of the flight's
        step, the inputs averaged over each period
        (:meth:`FaultMonitor.fit_record <genthermal.schedule.monitoring.monitor.FaultMonitor.fit_record>`).
    lookback_s : float
        The fault's onset is searched this long before the alarm (a drift alarms late), s.
    min_calibration_s : float
        With at least this much record before the onset window, s, ``calibrate_parameters`` are
        first calibrated on it, so the model's error is not taken for the fault.
    calibrate_parameters : tuple of str
        Parameters calibrated on that record (those the model lacks are skipped). Two, not the five
        of :attr:`DetectionSettings.calibrate_parameters`: the record before the window is short
        (20-60 min of one unit), and with five free parameters the calibrated model left more
        misfit for a heating fault to take, so a 6 K winding bias from 60 min was claimed only at
        85 min, after a re-plan and a shorted turn believed (``tests/test_sensor_watch.py``).
    check_delay_s : float
        The check runs this long after the alarm (one management cycle), s.
    stuck_min_samples : int
        A reading equal over this many consecutive samples, after a noisy one, is a frozen
        channel (:func:`~genthermal.schedule.monitoring.sensor_patterns.frozen_since`): 12 samples, 2 min at
        the 10-s step; with the thesis noise (σ ≈ 0.09 K) two equal samples of a live PT100 are
        already improbable.
    pattern_drift, pattern_threshold : float
        :math:`\nu, h` of the one-sided CUSUM on the opposite-heat-flow statistic :math:`m_g`
        (:mod:`~genthermal.schedule.monitoring.sensor_patterns`, in standard deviations): ν is near the
        largest :math:`m_g` of the healthy flight and of the faulty flights measured there (0.42,
        0.44); a 1.5 K/h iron drift (0.5-0.7 a cycle) builds h = 2 in about an hour.
    max_defer_s : float
        A new belief of the fault monitor on a generator whose heat flows show the sensor
        pattern (its CUSUM above zero) is held back, and its record checked every cycle, for at
        most this long, s; then the belief is taken (the plan changes up to 30 min late). 30 min:
        a 1.5 K/h winding drift was claimed 10 min after the fault monitor's belief and a 3 K/h
        one 25 min after it, on the Fig. 7.7 flight at 88 °C.
    max_drift_K_per_h : float
        Fastest drift the watch may claim, K/h. A sensor drift is a slow ramp (a PT100's drift in
        service is well under 1 K/h; the faults this watch was built for are 1.5-3 K/h); a reading
        running away faster than 10 K/h is the machine heating in a way the model lacks, and
        masking it would blind the manager. Measured on the robustness grid (case 0, a k_flow
        0.16 blockage): without this bound the real blockage was claimed as a +179 K/h winding
        drift and a +52 K/h iron drift, both sensors were masked, and the winding reached 255 °C.
    unconfirmed_winding, unconfirmed_iron : float
        A unit believed healthy whose fault statistic on that node exceeds this (standard
        deviations) is unconfirmed: the plan holds its last heat flows until the fault test alarms
        on it (:class:`~genthermal.schedule.monitoring.sensor_patterns.UnconfirmedExcess`). 0.56 and 1.15
        are the largest statistics of the 54 healthy flights the detector's drifts were set on
        (:mod:`genthermal.schedule.monitoring.detector`): a healthy unit is rarely held, and a fault or a
        sensor fault is held from the cycle it leaves the healthy range.
    max_unconfirmed_s : float
        Longest such hold, s: 60 min, the time the watch takes to claim a 1.5 K/h drift (60-90
        min after its onset, ``benchmarks/bench_sensor_flights.py``) minus the 15-25 min the
        drift takes to leave the healthy range. A statistic that stays above the healthy range
        that long without alarming is a weak excess (below the detector's drift), then taken.
    raw_evidence : RawEvidenceSettings
        What a claimed bias, gain error, stuck or noisier reading, fitted on the fit grid, must show in
        the raw record (:mod:`~genthermal.schedule.monitoring.raw_evidence`): a step at its onset, a grown
        sample-to-sample noise. Without it, 7 of the robustness grid's 48 faulty optimal flights
        claimed a sensor fault of a plant 10-30 % off the model with a real machine fault.
    enabled : bool
        False: faults are injected but not looked for (the comparison case).
    """

    drift: float = 1.0
    threshold: float = 4.0
    min_check_interval_s: float = 900.0
    max_checks: int = 10
    identify_dt_s: float = 60.0
    lookback_s: float = 1800.0
    min_calibration_s: float = 1200.0
    calibrate_parameters: tuple = ("R0", "h_end_air")
    check_delay_s: float = 300.0
    stuck_min_samples: int = 12
    pattern_drift: float = 0.4
    pattern_threshold: float = 2.0
    max_defer_s: float = 1800.0
    max_drift_K_per_h: float = 10.0
    unconfirmed_winding: float = 0.56
    unconfirmed_iron: float = 1.15
    max_unconfirmed_s: float = 3600.0
    raw_evidence: RawEvidenceSettings = RawEvidenceSettings()
    enabled: bool = True


class SensorWatch:
    """Detects, identifies and corrects sensor faults in flight (module docstring).

    Parameters
    ----------
    frame : SystemFrame
        The power system's sensors, generators and generator role (:meth:`PowerSystem.frame
        <genthermal.schedule.power_system.PowerSystem.frame>`).
    node_roles : sequence of str
        Per sensor, its node's role, ``winding`` or ``iron`` (the fault monitor's
        :func:`~genthermal.schedule.monitoring.monitor.detector_node_roles`).
    settings : SensorWatchSettings
    detection : DetectionSettings
        The fault monitor's settings (candidate heating faults of the check).
    injected : sequence of FlightSensorFault
        The scenario's sensor faults (:mod:`~genthermal.schedule.flight.sensor_injection`; reported,
        never read by the detection).

    Attributes
    ----------
    claims : list of dict
        Per claimed sensor fault: ``generator``, ``claimed_at_s``, the fault (onset since the
        mission start) and the check's evidence.
    checks : list of dict
        Every record check: ``time_s``, ``generator``, ``sensor`` alarmed, ``claimed`` and
        ``solve_s``.
    """

    def __init__(self, frame, node_roles, settings: SensorWatchSettings, detection, injected=()):
        self.frame, self.settings, self.detection = frame, settings, detection
        self.injected = tuple(injected)
        self.outputs = tuple(frame.output_names)
        n = frame.n_generators
        self.tests = [[Cusum(settings.drift, settings.threshold, two_sided=True) for _ in self.outputs]
                      for _ in range(n)]
        self.corrections: dict[tuple[int, int], SensorFault] = {}
        #: ``(generator, output)`` claimed noisier (kept, :data:`NOISE_KEPT`; not claimed again).
        self.noisier: set[tuple[int, str]] = set()
        #: ``(generator, row)`` → time the mask starts, s (a drift's: the start of its check window).
        self.mask_from: dict[tuple[int, int], float] = {}
        self.claims, self.checks = [], []
        self.suspects: dict[int, int] = {}
        #: ``(generator, row)`` of claimed biases the filter never took uncorrected (held out from
        #: the innovation alarm to the claim): that unit's heat flows stay trusted.
        self._never_filtered: set = set()
        self.patterns = [Cusum(settings.pattern_drift, settings.pattern_threshold) for _ in range(n)]
        self._pattern_since: dict[int, float] = {}
        self.pattern_alarms: list[dict] = []
        #: Generator → (held-back belief, since s): new beliefs waiting for the sensor check.
        self.deferred: dict[int, tuple] = {}
        self.deferrals: list[dict] = []
        self._last_check = [-math.inf] * n
        #: Warmer coolant-inlet readings the plan held back while unconfirmed (the input watch's
        #: :class:`~genthermal.schedule.monitoring.unconfirmed_inlet.UnconfirmedInlet` events).
        self.inlet_holds: list[dict] = []
        #: The fault test's :math:`r_{gj}` (n_gen, n_nodes) of the last cycle looked at (after its
        #: claims): the input watch confirms a warmer inlet reading on a unit that heats.
        self.last_statistics = np.full((n, len(self.outputs)), np.nan)
        self.unconfirmed = UnconfirmedExcess([getattr(settings, f"unconfirmed_{role}") for role in node_roles],
                                             settings.max_unconfirmed_s, n)

    def correct(self, sample_times_s, sensed, only=None, for_filter: bool = False) -> np.ndarray:
        """``sensed`` (n_gen, 2, n) at ``sample_times_s`` (n,), s, with the claimed faulty sensors (or
        those of ``only``, keys ``(generator, row)``) masked (NaN) from their fitted onsets; with
        ``for_filter``, a claimed bias is subtracted instead (module docstring)."""
        corrected = np.array(sensed, dtype=float, copy=True)
        times = np.asarray(sample_times_s, dtype=float)
        for (g, row), fault in self.corrections.items():
            if only is None or (g, row) in only:
                after = times >= self.mask_from.get((g, row), fault.onset_s)
                if for_filter and fault.kind == "bias":
                    corrected[g, row, after] -= fault.value
                else:
                    corrected[g, row, after] = np.nan
        return corrected

    def cycle(self, t_s: float, estimators, measured, before, monitor, detectors=None) -> list:
        """Run the tests on the cycle's readings, innovations and heat flows; check alarmed
        generators' records; act on claims; take or keep holding deferred beliefs.

        Parameters
        ----------
        t_s : float
            Time of the measurement, s.
        estimators : list of StateEstimator
            Just updated with ``measured``.
        measured : numpy.ndarray
            (n_gen, 2) readings of this update (corrected for earlier claims), °C.
        before : list of (numpy.ndarray, numpy.ndarray)
            Each estimator's predicted state and covariance before the update.
        monitor : FaultMonitor
            Its record is checked; its fault test of a generator restarts on a claim.
        detectors : list of StateEstimator, optional
            The extended Kalman filters of the fault test (default ``estimators``).

        Returns
        -------
        list of int
            Generators with a new claim this cycle.
        """
        if not self.settings.enabled:
            return []
        z = np.array([[e.innovation[r] / e.innovation_std[r] for r in range(len(self.outputs))] for e in estimators])
        claimed, known = [], set(self.corrections)
        pattern_sums = [test.high for test in self.patterns]
        statistics = monitor.statistics(estimators if detectors is None else detectors)
        self.last_statistics = statistics
        flows = opposite_flows(statistics)
        for g in range(len(estimators)):
            if self._frozen(g, t_s, monitor):  # a frozen channel needs no model: claimed at once
                claimed.append(g)
                continue
            pattern = self._pattern_alarm(g, t_s, flows[g])
            if g in self.deferred:
                if self._check_deferred(g, t_s, monitor):
                    claimed.append(g)
                    continue
            elif pattern and self._may_check(g, t_s):
                if self._check(g, t_s, list(self.outputs), monitor, delay_s=0.0, since_s=self._pattern_since[g],
                               peers=True):
                    claimed.append(g)
                    continue
            alarmed = []
            for r in range(len(self.outputs)):
                others = np.delete(z[:, r], g)
                others = others[np.isfinite(others)]
                d = z[g, r] - (float(np.median(others)) if others.size else 0.0)
                # the unit's own innovation must move too: with two units, one with a real fault
                # gives the other the mirrored difference while its own innovation stays small
                d = math.copysign(min(abs(d), abs(z[g, r])), d) if d * z[g, r] > 0 else 0.0
                if self.tests[g][r].update(d):
                    alarmed.append(self.outputs[r])
            if g in self.suspects:  # alarmed a cycle ago: the record now holds a cycle after the change
                row = self.suspects.pop(g)
                if self._check(g, t_s, [self.outputs[row]], monitor):
                    claimed.append(g)
                    if self.corrections.get((g, row)) is not None and self.corrections[(g, row)].kind == "bias":
                        self._never_filtered.add((g, row))  # held out since its alarm, then corrected
            elif len(alarmed) == 1 and self._may_check(g, t_s):
                self.suspects[g] = self.outputs.index(alarmed[0])
        # a check of one unit may claim another's sensor (:meth:`_check` with peers): its filter is redone too
        claimed += [h for h in sorted({h for h, _ in set(self.corrections) - known}) if h not in claimed]
        if self.suspects or claimed:  # this cycle's heat flows took a reading now held out or claimed
            for test, high in zip(self.patterns, pattern_sums):
                test.high = min(test.high, high)
        for g in range(len(estimators)):
            new = set(self.corrections) - known
            if g not in claimed and g not in self.suspects:
                continue
            z_pred, P_pred = before[g]
            estimators[g].z, estimators[g].P = z_pred, P_pred
            y = self.correct([t_s], np.asarray(measured)[:, :, None], new, for_filter=True)[g, :, 0]
            if g in self.suspects:  # one sensor alone moved: hold it out of the filter until checked
                y[self.suspects[g]] = np.nan
            else:  # a claim: the fault monitor restarts its test of this unit
                monitor.detector.restart(g)
                for test in self.tests[g]:
                    test.high = test.low = 0.0
                self.patterns[g].high = 0.0
            estimators[g].update(y)
            # this cycle's innovation mixes the fault and its correction: no test compares against it
            estimators[g].innovation = np.full_like(estimators[g].innovation, np.nan)
        if t_s >= self.detection.detector.settle_s:  # the fault test's own start; after this cycle's claims
            # and held-out sensors (a unit compared with one whose faulty reading the filter took shows it mirrored)
            statistics = monitor.statistics(estimators if detectors is None else detectors)
            self.last_statistics = statistics
            self.unconfirmed.update(t_s, statistics, [not b for b in monitor.beliefs],
                                    {h for h, _ in self.corrections})
        return claimed

    @staticmethod
    def undo_beliefs_since(g: int, onset_s: float, monitor) -> None:
        """Back to the machine believed before ``onset_s``: effects identified on generator ``g``
        from a record the faulty sensor had already spoilt are dropped."""
        kept = [i for i in monitor.identifications if i.generator == g and i.effect and i.detected_at_s < onset_s]
        monitor.beliefs = list(monitor.beliefs)
        monitor.beliefs[g] = kept[-1].effects if kept else ()

    def review(self, t_s: float, previous_beliefs, estimators, monitor, previous_model=None) -> list:
        """After the fault monitor's cycle: a unit whose believed machine just changed is checked
        for a sensor fault of either sensor first; a claim undoes the new belief (the change of
        the reading was the sensor's, not the machine's) and masks the sensor. Without a claim, a
        unit whose heat flows show the sensor pattern (:meth:`_suspicious`) has the new belief held
        back, with the recalibration its alarm made (the model goes back to ``previous_model``),
        and is checked every cycle (:meth:`_check_deferred`): the plan does not move until the
        sensor is cleared or :attr:`SensorWatchSettings.max_defer_s` has passed.

        Returns
        -------
        list of int
            Generators whose new belief was undone.
        """
        if not self.settings.enabled:
            return []
        undone = []
        # only the disturbance test starts an identification, whose belief is reviewed below; an
        # innovation-test alarm is a detection alone, and a sensor drift raises it too
        for g in {a["generator"] for a in monitor.alarms if a["time_s"] == t_s and a.get("test") != "innovation"}:
            self.unconfirmed.release(g, t_s, "fault test alarmed")
        recalibrated = previous_model is not None and monitor.calibrations and \
            monitor.calibrations[-1]["time_s"] == t_s
        alarmed = {a["generator"] for a in monitor.alarms if a["time_s"] == t_s}
        if recalibrated and any(not previous_beliefs[g] and self._suspicious(g, t_s) for g in alarmed):
            monitor.model = previous_model  # an alarm of the sensor pattern: its recalibration waits too
        for g, (before, now) in enumerate(zip(previous_beliefs, monitor.beliefs)):
            if now == before:
                continue
            # only a unit believed healthy: the misfit of an identified effect can take any pattern
            suspicious = not before and self._suspicious(g, t_s)
            if not (self._may_check(g, t_s) or (suspicious and self._checks_left(g))):
                continue
            beliefs, monitor.beliefs = list(monitor.beliefs), list(monitor.beliefs)
            monitor.beliefs[g] = before  # the record is checked on the machine as believed before
            # on the model before this cycle's recalibration: that ran on another unit's record,
            # which may hold the faulty sensor
            known = set(self.corrections)
            if self._check(g, t_s, list(self.outputs), monitor, delay_s=0.0,
                           since_s=self._pattern_since.get(g) if suspicious else None, base_model=previous_model,
                           peers=suspicious):
                undone.append(g)
                estimators[g].innovation = np.full_like(estimators[g].innovation, np.nan)
                self.deferred.pop(g, None)
            elif self._claimed_other(g, known):  # g was compared with the faulty sensor: its belief goes,
                if recalibrated:  # and so does the recalibration made on the other unit's record
                    monitor.model = previous_model
                self.deferrals.append({"generator": g, "time_s": t_s, "belief": [name for name, _ in now[-1:]],
                                       "outcome": "dropped: a sensor of another unit was claimed"})
                undone.append(g)
            elif suspicious:  # the heat flows say "sensor": hold the new belief back, check again
                self.deferred[g] = (now, self.deferred.get(g, (None, t_s))[1])
                if recalibrated:
                    monitor.model = previous_model  # the alarm's recalibration waits with its belief
                self.deferrals.append({"generator": g, "time_s": t_s, "belief": [name for name, _ in now[-1:]],
                                       "outcome": "held"})
                undone.append(g)
            else:
                monitor.beliefs = beliefs
        return undone

    def _frozen(self, g: int, t_s: float, monitor) -> bool:
        """Claim every sensor of generator ``g`` whose reading froze (module
        :mod:`~genthermal.schedule.monitoring.sensor_patterns`); True when one was claimed."""
        times, readings = monitor.readings(g)
        found = False
        for row, output in enumerate(self.outputs):
            if (g, row) in self.corrections:
                continue
            start_s = frozen_since(times, readings[row], self.settings.stuck_min_samples)
            if start_s is None:
                continue
            held = float(readings[row][-1])
            fault = SensorFault(output, "stuck", held, start_s)
            run = int(np.count_nonzero(times >= start_s))
            self._mask(g, row, fault, start_s, monitor)
            self.claims.append({"generator": g, "claimed_at_s": t_s, "fault": fault, "delta_bic": None,
                                "alternative": f"reading frozen at {held:.2f} °C for {run} samples (a live sensor "
                                               "is noisy): no heat flow holds a temperature exactly",
                                "action": "masked", "evidence": "frozen reading"})
            found = True
        return found

    def _pattern_alarm(self, g: int, t_s: float, flow: float) -> bool:
        """Feed generator ``g``'s opposite-heat-flow statistic to its CUSUM; True on an alarm. Not
        run once any sensor is masked: one sensor left has no pattern, and a generator compared with
        one whose sensor is masked shows that one's unobserved heat flow mirrored."""
        if self.corrections:
            return False
        test = self.patterns[g]
        if test.high == 0.0:
            self._pattern_since[g] = t_s
        alarm = test.update(flow)
        if alarm:
            self.pattern_alarms.append({"time_s": t_s, "generator": g, "since_s": self._pattern_since[g]})
        return alarm

    def _suspicious(self, g: int, t_s: float) -> bool:
        """Generator ``g``'s heat flows show the sensor pattern: its CUSUM is building, or it
        alarmed within :attr:`SensorWatchSettings.max_defer_s`."""
        recent = [a for a in self.pattern_alarms
                  if a["generator"] == g and t_s - a["time_s"] <= self.settings.max_defer_s]
        return self.patterns[g].high > 0.0 or bool(recent)

    def _check_deferred(self, g: int, t_s: float, monitor) -> bool:
        """Check generator ``g``'s record again while its new belief is held back; take the belief
        when the pattern is gone or it has waited :attr:`SensorWatchSettings.max_defer_s`. True
        on a claim of ``g``'s; a claim of another unit's sensor drops the held belief
        (:meth:`_mask`)."""
        belief, since_s = self.deferred[g]
        known = set(self.corrections)
        if self._checks_left(g) and self._check(g, t_s, list(self.outputs), monitor, delay_s=0.0,
                                                since_s=self._pattern_since.get(g, since_s), peers=True):
            self.deferred.pop(g, None)
            self.deferrals.append({"generator": g, "time_s": t_s, "outcome": "sensor fault claimed"})
            return True
        if self._claimed_other(g, known):
            return False
        if not self._suspicious(g, t_s) or t_s - since_s >= self.settings.max_defer_s:
            self.deferred.pop(g)
            monitor.beliefs = list(monitor.beliefs)
            monitor.beliefs[g] = belief
            self.deferrals.append({"generator": g, "time_s": t_s, "outcome": "belief taken"})
        return False

    def trusts_heat_flows(self, g: int, t_s: float) -> bool:
        """Whether the planner may take generator ``g``'s estimated disturbance heat flows at
        ``t_s`` (offset-free planning, :func:`~genthermal.schedule.state_estimator.planning_generator`).

        Not while one of its sensors is claimed faulty (the filter learnt them partly from the
        faulty samples, and with the sensor masked they are no longer observed), unless that is a
        bias held out of the filter from its innovation alarm and corrected since its claim; nor
        while its heat flows show the sensor pattern, its excess is unconfirmed
        (:class:`~genthermal.schedule.monitoring.sensor_patterns.UnconfirmedExcess`) or a new belief waits for
        the sensor check: those heat flows may be a sensor's doing. The planner then holds the last
        trusted ones
        (:class:`~genthermal.schedule.flight.closed_loop.TrustedHeatFlows`). Measured on the stuck and
        drifting winding sensors of ``tests/test_sensor_watch.py``: with the heat flows handed over
        regardless, the stuck sensor caused a re-plan 50 min after its claim and the drift two.
        """
        if not self.settings.enabled:
            return True
        if any(key[0] == g and key not in self._never_filtered for key in self.corrections) \
                or g in self.deferred or self.unconfirmed.holds(g):
            return False
        return not self._suspicious(g, t_s)

    def _checks_left(self, g: int) -> bool:
        return sum(1 for c in self.checks if c["generator"] == g) < self.settings.max_checks

    def _may_check(self, g: int, t_s: float) -> bool:
        return self._checks_left(g) and t_s - self._last_check[g] >= self.settings.min_check_interval_s

    def _check(self, g: int, t_s: float, alarmed, monitor, delay_s: float | None = None,
               since_s: float | None = None, base_model=None, peers: bool = False) -> bool:
        """Fit the alarmed sensor's faults (onset within :attr:`SensorWatchSettings.lookback_s` of
        the alarm, or of ``since_s``, s, when earlier: the start of the heat-flow pattern; on
        ``base_model`` with the unit's beliefs when given, else the monitor's model) against the
        heating faults on generator ``g``'s record, the model first calibrated on the record before
        that window; claim and correct. With ``peers`` (the heat-flow pattern, which the units a
        unit is compared with show mirrored), the other units without a masked sensor are fitted
        the same way, also when ``g``'s own record shows no sensor fault (a sensor of another unit
        reading low makes ``g`` look hot next to it), and the fault is claimed on the unit where it
        is strongest, only when it beats every other unit's by
        :data:`~genthermal.diagnose.sensor_faults.PREFERENCE_BIC` (a unit without one is no
        competitor: a lone claim meets the check's own criterion, as without ``peers``). Measured on
        ``benchmarks/bench_sensor_flights.py``'s -1.5 K/h winding drift of gen2 from 70 min: gen1
        looked hot next to it, its fault test alarmed and the identification named a blockage and
        then shorted turns; held as suspicious, only gen1's clean record was checked, and the belief
        taken after :attr:`SensorWatchSettings.max_defer_s` moved 5 cycles' loads, the drift never
        claimed. Returns True when a fault of ``g`` was claimed (:meth:`_claimed_other` tells
        whether one of another unit was)."""
        from ...diagnose.sensor_faults import PREFERENCE_BIC

        self._last_check[g] = t_s
        found = self._fit(g, t_s, alarmed, monitor, delay_s, since_s, base_model)
        if not peers:
            return self._claim(g, t_s, found, monitor)
        others = [h for h in range(len(self._last_check)) if h != g
                  and not any((h, r) in self.corrections for r in range(len(self.outputs)))]
        rivals = {h: self._fit(h, t_s, alarmed, monitor, delay_s, since_s, base_model) for h in others}
        rivals = {h: f for h, f in rivals.items() if f}
        strongest = min(rivals, key=lambda h: rivals[h][0].delta_bic, default=None)
        if strongest is None or (found and found[0].delta_bic < rivals[strongest][0].delta_bic - PREFERENCE_BIC):
            return self._claim(g, t_s, found, monitor)
        runners_up = [found[0].delta_bic] if found else []
        runners_up += [f[0].delta_bic for h, f in rivals.items() if h != strongest]
        if not runners_up or rivals[strongest][0].delta_bic < min(runners_up) - PREFERENCE_BIC:
            self._claim(strongest, t_s, rivals[strongest], monitor)
        return False

    def _claimed_other(self, g: int, known) -> bool:
        """Whether a sensor of a unit other than ``g`` was claimed since the corrections were
        ``known`` (a set of ``(generator, row)``)."""
        return any(h != g for h, _ in set(self.corrections) - set(known))

    def _fit(self, g: int, t_s: float, alarmed, monitor, delay_s, since_s, base_model) -> list:
        """The check of :meth:`_check` on generator ``g``'s record, recorded in :attr:`checks`;
        the hypotheses to claim (onsets since the mission start), not acted on."""
        import time

        from ...diagnose.calibrate import calibrate
        from ...diagnose.discover import series_for
        from ...diagnose.search import EffectSearch
        from ...diagnose.sensor_screen import SensorScreen

        started = time.perf_counter()
        record = monitor.fit_record(g, self.settings.identify_dt_s)
        model = monitor.flown_model(g) if base_model is None else believed_model(base_model, monitor.beliefs[g])
        alarm_s = t_s - (self.settings.check_delay_s if delay_s is None else delay_s)
        window_s = min(alarm_s, t_s if since_s is None else since_s) - self.settings.lookback_s
        before = record[record["time_s"] < window_s]
        span_s = before["time_s"].iloc[-1] - before["time_s"].iloc[0] if before["time_s"].size else 0.0
        models = [model]
        if span_s >= self.settings.min_calibration_s:
            models.insert(0, calibrate(model, before, [p for p in self.settings.calibrate_parameters
                                                       if p in model.parameters],
                                       self.settings.identify_dt_s).model)  # the unit as it was before the change
        for model in models:
            # a calibration on a short stretch can leave a model with no physical steady state at the
            # record's load (measured: a 10-min stretch before a blockage with a +31-K inlet, the
            # steady state -1048 °C): the check then runs on the model before that calibration
            try:
                series = series_for(model, record, self.settings.identify_dt_s)
                search = EffectSearch(model, series).fit_found()
                break
            except InputError as error:
                failure = str(error)
        else:
            self.checks.append({"time_s": t_s, "generator": g, "alarmed": list(alarmed), "claimed": False,
                                "refused": [], "best_machine_fault": None, "error": failure,
                                "solve_s": time.perf_counter() - started})
            return []
        screen = SensorScreen(record, series, model.spec.interface)
        names = [n for n in search.candidates() if n in self.detection.fault_effects]
        ranked = search.rank(names) if names else []
        onsets = np.flatnonzero((series.time_s >= window_s)
                                & (series.time_s <= alarm_s + self.settings.identify_dt_s))
        onsets = onsets[(onsets > 0) & (onsets < series.time_s.size - 2)]
        masked = {self.outputs[r] for (h, r) in self.corrections if h == g}
        outputs = [a for a in alarmed if a not in masked]
        # input sensors are checked by the input watch, on a disagreement between units (input_watch)
        found = (screen.against_model(search, ranked, search.noise, outputs, onsets, on_top=True, inputs=False)
                 if outputs and onsets.size else None)
        noisy = [h for h in screen.found if h.evidence == "noise" and h.output in outputs
                 and (g, h.output) not in self.noisier]
        start_s = float(series.time_s[0])  # onsets from the mission start, sensors named by output
        new = [dataclasses.replace(h, fault=dataclasses.replace(h.fault, sensor=h.output,
                                                                 onset_s=start_s + h.fault.onset_s))
               for h in ([found] if found is not None else noisy[:1])]
        refused = [f"{h.fault.sensor} {h.fault.kind} {h.fault.value:+.1f} K/h: faster than "
                   f"{self.settings.max_drift_K_per_h:g} K/h, a heating, not a drift"
                   if h.fault.kind == "drift" and abs(h.fault.value) > self.settings.max_drift_K_per_h
                   else self._not_in_raw_record(g, h.fault, monitor) for h in new]
        new = [h for h, reason in zip(new, refused) if reason is None]
        self.checks.append({"time_s": t_s, "generator": g, "alarmed": list(alarmed), "claimed": bool(new),
                            "refused": [reason for reason in refused if reason is not None],
                            "best_machine_fault": ranked[0].effect if ranked else None,
                            "solve_s": time.perf_counter() - started})
        return new

    def _not_in_raw_record(self, g: int, fault: SensorFault, monitor) -> str | None:
        """Why generator ``g``'s raw readings (every simulation step) do not show ``fault``, fitted
        on the fit grid, or None (:func:`~genthermal.schedule.monitoring.raw_evidence.unsupported`)."""
        times, readings = monitor.readings(g)
        return unsupported(fault, times, readings[self.outputs.index(fault.sensor)], self.settings.raw_evidence)

    def _claim(self, g: int, t_s: float, new, monitor) -> bool:
        """Act on the hypotheses ``new`` of :meth:`_fit` on generator ``g``: mask (a noisier sensor:
        keep, :data:`NOISE_KEPT`), record. True when a sensor was masked: its fault, not heat,
        explains the alarm."""
        masked = False
        for hypothesis in new:
            fault = hypothesis.fault
            if fault.kind == "noise":
                self.noisier.add((g, fault.sensor))
            else:
                self._mask(g, self.outputs.index(fault.sensor), fault, fault.onset_s, monitor)
                masked = True
            self.claims.append({"generator": g, "claimed_at_s": t_s, "fault": fault,
                                "delta_bic": hypothesis.delta_bic, "alternative": hypothesis.alternative,
                                "action": {"bias": CORRECTED, "noise": NOISE_KEPT}.get(fault.kind, "masked")})
        return masked

    def _mask(self, g: int, row: int, fault: SensorFault, from_s: float, monitor) -> None:
        """Mask generator ``g``'s sensor ``row`` from ``from_s`` in the flight to come and in the
        fault monitor's record and test; drop the beliefs its faulty samples may have caused."""
        self.corrections[(g, row)] = fault
        self.mask_from[(g, row)] = from_s
        monitor.mask(g, row, from_s)
        self.undo_beliefs_since(g, from_s, monitor)
        for test in self.patterns:  # the opposite-flow test stops (:meth:`_pattern_alarm`): a sum left
            test.high = 0.0  # standing would keep every unit "suspicious" for the rest of the flight
        self.unconfirmed.release(g, self.claims[-1]["claimed_at_s"] if self.claims else from_s, "sensor claimed")
        self.deferred.pop(g, None)
        for other in list(self.deferred):  # a belief held on a unit compared with this sensor's
            self.deferred.pop(other)
            self.deferrals.append({"generator": other, "time_s": self.claims[-1]["claimed_at_s"] if self.claims
                                   else from_s, "outcome": f"dropped: a sensor of unit {g + 1} was claimed"})

    def to_dict(self, names) -> dict:
        """The flight JSON ``sensor_faults`` entry: injected, claimed (with the action) and checks."""
        return {"injected": [{"generator": names[f.generator], **f.fault.to_dict()} for f in self.injected],
                "claimed": [{"generator": names[c["generator"]], "claimed_at_s": c["claimed_at_s"],
                             **c["fault"].to_dict(), "delta_ic": c["delta_bic"], "alternative": c["alternative"],
                             "evidence": c.get("evidence", "record check"), "action": c["action"]}
                            for c in self.claims],
                "checks": [{**c, "generator": names[c["generator"]]} for c in self.checks],
                "pattern_alarms": [{**a, "generator": names[a["generator"]]} for a in self.pattern_alarms],
                "beliefs_held": [{**d, "generator": names[d["generator"]]} for d in self.deferrals],
                "heat_flows_unconfirmed": [{**e, "generator": names[e["generator"]]} for e in self.unconfirmed.events],
                "inlet_readings_unconfirmed": [{**e, "generator": names[e["generator"]]} for e in self.inlet_holds],
                "load_plan": "unchanged by sensor faults: the believed machine is not changed by a claim"}
