"""Faulty input sensors in flight (the coolant-inlet and ambient PT100s that drive each unit's
filter): detect, identify and substitute them. Main objects: :class:`InputWatch`,
:class:`InputWatchSettings`. Method: docs/guide/flight-methods.md.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from ...diagnose.sensor_faults import PREFERENCE_BIC
from ...errors import InputError
from ...estimation.ekf import ExtendedKalmanFilter
from ...sensor_faults import SensorFault
from ..planning.plan import DEFAULT_MARGIN_K
from .unconfirmed_inlet import UnconfirmedInlet


@dataclasses.dataclass(frozen=True)
class InputWatchSettings:
    """Input-sensor faults in flight.

    Attributes
    ----------
    disagreement_K : float
        A unit's cycle-mean input reading this far from the other units' median is checked, K.
        1 K: two healthy PT100s in the same air agree within a few tenths (class B tolerance
        ±0.3 K at 0 °C, IEC 60751), and a 1-K input error moves the predicted winding by about 1 K
        at steady state, what the plan's margin (2.5 K) can take.
    max_checks : int
        Record checks per unit and input.
    lookback_s : float
        The fault's onset is searched this long before the cycle that disagreed, s.
    enabled : bool
        False: input faults are injected but not looked for.
    shared_step_K : float
        An ambient reading that steps by more than ``disagreement_K`` in one sample is its sensor's
        when every other unit's reading moved less than this in that sample, K (the units see one
        ambient; 0.3 K, the class-B tolerance at 0 °C, IEC 60751: what two readings of one air
        may differ by).
    unconfirmed_rise_K : float
        Most of a warmer coolant-inlet reading the plan holds back while it is unconfirmed, K, on a
        flight planned with the default 2.5-K margin
        (:data:`~genthermal.schedule.planning.plan.DEFAULT_MARGIN_K`); a flight planned with a
        smaller margin holds back proportionally less, none at 0 (the thesis-reproduction
        scenarios, which plan to θmax itself) (:mod:`~genthermal.schedule.monitoring.unconfirmed_inlet`). 4 K:
        the largest step whose real rise heats the thesis generator's winding by no more than the
        2.5-K margin over ``max_unconfirmed_s`` plus one 5-min cycle (0.59 K per K after 15 min, the
        planning model's response to an inlet step,
        :func:`~genthermal.diagnose.input_sensors.input_step_response`).
    max_unconfirmed_s : float
        Longest such hold, from the first held plan, s. 600 s: the record check decided a 3-K bias
        two cycles after its onset (ΔBIC -7.6 after one, -36 after two, Fig. 7.7 flight).
    """

    disagreement_K: float = 1.0
    max_checks: int = 6
    lookback_s: float = 1800.0
    enabled: bool = True
    shared_step_K: float = 0.3
    unconfirmed_rise_K: float = 4.0
    max_unconfirmed_s: float = 600.0

    def __post_init__(self):
        for name in ("disagreement_K", "lookback_s", "shared_step_K"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise InputError(f"input_watch.{name}", value, "must be a finite number > 0")
        for name in ("unconfirmed_rise_K", "max_unconfirmed_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise InputError(f"input_watch.{name}", value, "must be a finite number >= 0 (0: no hold)")
        if isinstance(self.max_checks, bool) or not isinstance(self.max_checks, int) or self.max_checks < 0:
            raise InputError("input_watch.max_checks", self.max_checks, "must be a whole number >= 0")


class InputWatch:
    """Detects, identifies and substitutes faulty input sensors in flight (module docstring).

    Parameters
    ----------
    watch : SensorWatch
        The output sensors' watch: claims and checks are reported with its own, its record-check
        settings (calibration, sample period) are used.
    settings : InputWatchSettings
    input_names : sequence of str
        The measured temperature inputs (inlet, ambient).
    n_generators : int
    margin_K : float, optional
        The flight's planning margin, K (:attr:`~genthermal.schedule.flight.role_settings.MonitorSettings.margin_K`;
        default :data:`~genthermal.schedule.planning.plan.DEFAULT_MARGIN_K`): scales the inlet
        hold (:attr:`InputWatchSettings.unconfirmed_rise_K`).

    Attributes
    ----------
    claimed : dict
        ``(generator, input)`` → SensorFault (onset since the mission start).
    unconfirmed_inlet : UnconfirmedInlet
        Warmer coolant-inlet readings held back from the plan while under check.
    """

    def __init__(self, watch, settings: InputWatchSettings, input_names, n_generators: int,
                 margin_K: float | None = None):
        self.watch, self.settings = watch, settings
        self.input_names, self.n_generators = tuple(input_names), n_generators
        self.claimed: dict[tuple[int, str], SensorFault] = {}
        self._checks: dict[tuple[int, str], int] = {}
        self._agreed: dict[tuple[int, str], np.ndarray] = {}
        #: ``(generator, input)`` → the last check's Δ (own reading against the shared one).
        self._own_fits: dict[tuple[int, str], float] = {}
        #: Per generator, (time s, state names, disturbance states) after each cycle's update.
        self._flows: list[list] = [[] for _ in range(n_generators)]
        generator = watch.frame.role
        #: The input every unit reads the same air of (the ambient: the mission has one).
        self.shared_air_input = generator.ambient_input
        #: The coolant-inlet input, whose warmer reading is held while unconfirmed.
        self.coolant_input = generator.coolant_input
        #: Most of a warmer inlet reading held back, K: the setting scaled to the flight's margin.
        margin_K = DEFAULT_MARGIN_K if margin_K is None else float(margin_K)
        self.held_K = settings.unconfirmed_rise_K * min(max(margin_K, 0.0) / DEFAULT_MARGIN_K, 1.0)
        self.unconfirmed_inlet = UnconfirmedInlet(self.held_K, settings.max_unconfirmed_s, n_generators)
        watch.inlet_holds = self.unconfirmed_inlet.events  # reported with the sensor watch's figures
        self._now_s = 0.0
        #: ``(generator, input)`` whose warmer reading the unit's heating confirmed (until they agree).
        self._heating: set = set()
        #: ``(generator, input)`` → first sample its filter was driven with the held reading, s;
        #: those in ``_filter_partial`` were held only in part (the error exceeded the hold).
        self._filter_held_since: dict[tuple[int, str], float] = {}
        self._filter_partial: set = set()

    def substitute(self, sample_times_s, readings: dict) -> dict:
        """``readings`` (input name → (n_gen, n) °C at ``sample_times_s``) with every claimed sensor's
        reading replaced from its fitted onset (module docstring)."""
        used = {name: np.array(v, dtype=float, copy=True) for name, v in readings.items()}
        times = np.asarray(sample_times_s, dtype=float)
        for (g, name), fault in self.claimed.items():
            if name in used:
                used[name][g] = self.replacement(g, name, times, used[name])
        return used

    def replacement(self, g: int, name: str, times, values) -> np.ndarray:
        """Generator ``g``'s reading of input ``name`` (row of ``values``, (n_gen, n) °C at ``times``)
        with its claimed fault replaced: the other units' median, else the reading minus the fault."""
        fault = self.claimed[(g, name)]
        after = np.asarray(times) >= fault.onset_s
        row = np.array(values[g], dtype=float, copy=True)
        sources = [h for h in range(values.shape[0]) if h != g and (h, name) not in self.claimed]
        if sources:
            row[after] = np.median(values[sources][:, after], axis=0)
        elif fault.kind == "bias":
            row[after] -= fault.value
        elif fault.kind == "drift":
            row[after] -= fault.value * (np.asarray(times)[after] - fault.onset_s) / 3600.0
        return row

    def for_plan(self, readings: dict, t_s: float | None = None) -> dict:
        """The inputs the plan holds (input name → (n_gen, 1) readings at the planning time ``t_s``,
        s, by default the end of the last cycle checked; claimed sensors substituted).

        A unit whose reading disagrees with the other units' median by more than
        :attr:`InputWatchSettings.disagreement_K` and is still under check (checks left, and no
        check found its record fitting its own reading markedly better than the shared one) plans
        with its last reading that agreed where that is the warmer one, until a check claims its
        sensor or runs out: a reading colder than the air was otherwise reaches the plan the cycle
        it happens, before the filter or a check could tell it from the air, and would let the plan
        load the unit. A warmer coolant-inlet reading under check is *unconfirmed*
        (:mod:`~genthermal.schedule.monitoring.unconfirmed_inlet`): the plan holds back at most
        :attr:`InputWatchSettings.unconfirmed_rise_K` of it for at most
        :attr:`InputWatchSettings.max_unconfirmed_s`, so that a sensor reading high moves no load
        before its claim while a real rise (a blockage recirculating hot air) stays within the
        plan's margin until the check confirms it. A warmer reading of any other input is planned
        at once.
        """
        now = self._now_s if t_s is None else float(t_s)
        planned = {name: np.array(v, dtype=float, copy=True) for name, v in readings.items()}
        if not self.settings.enabled or self.n_generators < 2:
            return planned
        for name, values in planned.items():
            for g in range(self.n_generators):
                others = [h for h in range(self.n_generators) if h != g and (h, name) not in self.claimed]
                if (g, name) in self.claimed or not others:
                    continue
                shared = np.median(readings[name][others], axis=0)
                if not np.any(np.abs(readings[name][g] - shared) > self.settings.disagreement_K):
                    self._agreed[(g, name)] = np.array(readings[name][g], dtype=float)
                    self._heating.discard((g, name))
                    self._filter_held_since.pop((g, name), None)
                    self._filter_partial.discard((g, name))
                    if name == self.coolant_input:
                        self.unconfirmed_inlet.agrees(g, now)
                    continue
                under_check = self._under_check(g, name)
                if name == self.coolant_input and not under_check:
                    self.unconfirmed_inlet.release(g, now, "confirmed by the record check: its own reading fits "
                                                   "markedly better" if self._own_fits.get((g, name), -math.inf)
                                                   > PREFERENCE_BIC else "no check left")
                if not under_check:
                    continue
                trusted = self._agreed[(g, name)]
                if name == self.coolant_input and np.any(values[g] > trusted):
                    values[g] = self.unconfirmed_inlet.planned(g, now, values[g], trusted)
                else:
                    values[g] = np.maximum(values[g], trusted)  # never a cooler plan
        return planned

    def _under_check(self, g: int, name: str) -> bool:
        """True while generator ``g``'s disagreeing reading of ``name`` is neither claimed nor
        confirmed: it agreed before, checks are left, no check found its own reading fitting
        markedly better, and its unit does not heat (:meth:`_confirm_by_heating`)."""
        return (g, name) in self._agreed and (g, name) not in self.claimed \
            and self._checks.get((g, name), 0) < self.settings.max_checks \
            and not self._own_fits.get((g, name), -math.inf) > PREFERENCE_BIC and (g, name) not in self._heating

    def for_filter(self, sample_times_s, readings: dict) -> dict:
        """The inputs the filters are driven with over the cycle about to be flown: ``readings``
        (input name → (n_gen, n) °C at ``sample_times_s``, s) with each unit's coolant-inlet reading
        held, sample by sample, as the plan holds it (:meth:`for_plan`) while it is under check:
        a sample farther than :attr:`InputWatchSettings.disagreement_K` from the other units'
        reading is replaced by the last agreeing reading; a warmer sample by the last agreeing
        reading plus whatever of the rise exceeds :attr:`held_K`, and by itself once the plan's
        hold has reached its time bound.

        Why the filter too: held from the plan only, a 3-K bias still drove the filter, whose
        disturbance heat flows cooled the unit to follow its sensors; the claim takes those back
        only approximately (the unit's own flows before the onset plus the other units' change
        since), and on seeds 1 and 2 of ``benchmarks/bench_inlet_confirmation.py`` that left 1-3
        re-plans and up to 5 load changes after the claim. Held, the filter never takes the bias and
        the claim has nothing to take back. A real rise, by contrast, now heats the unit beyond
        its filter's (held) prediction, which the fault statistic shows within a cycle: that is the
        physics confirming the reading (:meth:`_confirm_by_heating`). The heat flows the filter
        learnt meanwhile are left to decay once it is driven by the reading again: they add heat,
        the safe side, where taking them back would also take back a blockage's own heating.
        """
        used = {name: np.array(v, dtype=float, copy=True) for name, v in readings.items()}
        name = self.coolant_input
        if not self.settings.enabled or self.n_generators < 2 or name not in readings:
            return used
        times, values = np.asarray(sample_times_s, dtype=float), np.asarray(readings[name], dtype=float)
        for g in range(self.n_generators):
            others = [h for h in range(self.n_generators) if h != g and (h, name) not in self.claimed]
            if not others or not self._under_check(g, name):
                continue
            away = np.abs(values[g] - np.median(values[others], axis=0)) > self.settings.disagreement_K
            if not away.any():
                continue
            trusted = float(np.max(self._agreed[(g, name)]))
            row = used[name][g]
            warm, cold = away & (row > trusted), away & (row <= trusted)
            row[cold] = trusted
            if self.unconfirmed_inlet.expired(g):
                warm[:] = False
            row[warm] = np.maximum(trusted, row[warm] - self.held_K)
            self._filter_held_since.setdefault((g, name), float(times[np.flatnonzero(away)[0]]))
            if np.any(values[g][warm] - self.held_K > trusted) or \
                    np.any(away & ~(warm | cold)):
                self._filter_partial.add((g, name))
        return used

    def cycle(self, t_s: float, readings: dict, estimators, monitor) -> list:
        """Compare the units' input readings of the cycle just flown; check and claim.

        Parameters
        ----------
        t_s : float
            Time of the cycle's end, s.
        readings : dict
            Input name → (n_gen, n) readings of the cycle just flown as used (claimed sensors
            already substituted), °C.
        estimators : list of StateEstimator
            Just updated; a claimed unit's disturbance heat flows are taken back.
        monitor : FaultMonitor
            Its record is checked and corrected.

        Returns
        -------
        list of int
            Generators with a new claim this cycle.
        """
        self._now_s = float(t_s)
        for g, estimator in enumerate(estimators):
            self._flows[g].append((t_s, list(estimator.filter.state_names), np.array(estimator.z, dtype=float)))
        if not self.settings.enabled or self.n_generators < 2:
            return []
        new = []
        for name in self.input_names:
            if name not in readings:
                continue
            means = np.mean(readings[name], axis=1)
            disagree = []
            for g in range(self.n_generators):
                others = [h for h in range(self.n_generators) if h != g and (h, name) not in self.claimed]
                if (g, name) in self.claimed or not others:
                    continue
                if abs(means[g] - float(np.median(means[others]))) > self.settings.disagreement_K and \
                        self._checks.get((g, name), 0) < self.settings.max_checks:
                    disagree.append(g)
            if name == self.coolant_input:
                self._confirm_by_heating(t_s, name, means, monitor)
            found = {g: self._fit(g, name, t_s, monitor) for g in disagree}
            found = {g: h for g, h in found.items() if h is not None}
            if name == self.shared_air_input:
                # a step of one unit's reading of the one ambient: its sensor, unless its record
                # fits its own reading markedly better (the machine followed it)
                alone = {g: self._stepped_alone(g, name, monitor) for g in disagree}
                alone = {g: h for g, h in alone.items()
                         if h is not None and self._own_fits[(g, name)] <= PREFERENCE_BIC}
                if len(alone) == 1:
                    [(g, hypothesis)] = alone.items()
                    self._claim(g, name, hypothesis, t_s, estimators, monitor, "a step of the shared air's reading")
                    new.append(g)
                    continue
            if not found:
                continue

            best = min(found, key=lambda g: found[g].delta_bic)
            # the other disagreeing units must fit their own reading markedly better than this one's:
            # the model's own error favours the warmer reading (it runs cooler than the plant), and
            # with an input as weak as the ambient that alone picked the wrong unit
            if all(self._own_fits[(g, name)] > PREFERENCE_BIC for g in disagree if g != best):
                self._claim(best, name, found[best], t_s, estimators, monitor)
                new.append(best)
        return new

    def _confirm_by_heating(self, t_s: float, name: str, means, monitor) -> None:
        """Confirm the warmer inlet reading of every unit that heats: its fault test alarms this
        cycle (:attr:`SensorWatch.last_statistics <genthermal.schedule.monitoring.sensor_watch.SensorWatch>`,
        the unit's heat flows against the other units', added to the test's sums: the detector's
        own drift and threshold, set on 54 healthy flights). Its filter is driven by the held
        reading (:meth:`for_filter`), so a sensor reading high moves nothing in it, while air that
        really got warmer heats the unit beyond the filter's prediction; a blockage that
        recirculates its air also cuts the flow and heats the unit more. The bound is the alarm,
        not the healthy range: healthy Fig. 7.7 flights (seeds 0-5) reach statistics of 1.58 on the
        winding and 1.81 on the iron, and a real 3-16 K inlet step with 4 K of it held gave only
        1.2-1.6 (the record check confirms those, :meth:`_fit`); a 5-K rise with a 0.6 flow
        blockage gave 11.6 a cycle later. Holding the reading back would delay acting on a real
        fault."""
        statistics = np.asarray(getattr(self.watch, "last_statistics", ()), dtype=float)
        detector = monitor.detector
        if statistics.shape != np.shape(detector.sums):
            return
        alarming = np.isfinite(statistics) & (np.maximum(0.0, detector.sums + statistics - detector.drift)
                                              > detector.threshold)
        for g in range(self.n_generators):
            others = [h for h in range(self.n_generators) if h != g and (h, name) not in self.claimed]
            if not others or (g, name) in self._heating or \
                    not means[g] - float(np.median(means[others])) > self.settings.disagreement_K:
                continue
            if alarming[g].any():
                self._heating.add((g, name))
                self.unconfirmed_inlet.release(g, t_s, "confirmed: the unit heats, its fault test alarms (statistic "
                                               + ", ".join(f"{v:.2f}" for v in statistics[g]) + ")")

    def _fit(self, g: int, name: str, t_s: float, monitor):
        """Generator ``g``'s record checked for a fault of input ``name`` (module docstring,
        "Checking"): the hypothesis (onset since the mission start) or None."""
        from ...diagnose.calibrate import calibrate
        from ...diagnose.compare import measured_series
        from ...diagnose.sensor_faults import SensorHypothesis
        from ...simulate import simulate

        started = time.perf_counter()
        self._checks[(g, name)] = self._checks.get((g, name), 0) + 1
        dt_s = self.watch.settings.identify_dt_s
        model = monitor.flown_model(g)
        record = monitor.fit_record(g, dt_s)
        sources = [h for h in range(self.n_generators) if h != g and (h, name) not in self.claimed]
        shared = np.median([monitor.fit_record(h, dt_s)[name].to_numpy(float) for h in sources], axis=0)
        substituted = record.copy()
        substituted[name] = shared
        sensors, interface = model.output_names, model.spec.interface  # the record's grid needs no more
        own = measured_series(record, dt_s, sensors, interface)
        other = measured_series(substituted, dt_s, sensors, interface)
        elapsed = own.time_s - own.time_s[0]
        error = own.inputs[name].to_numpy(float) - other.inputs[name].to_numpy(float)
        since = np.flatnonzero(np.abs(error) > self.settings.disagreement_K)
        delta, fault = None, None
        if since.size:
            first = int(np.searchsorted(elapsed, max(elapsed[since[0]] - self.settings.lookback_s, 0.0)))
            fault = _input_error_shape(name, elapsed, error, first)
            window = elapsed >= fault.onset_s
            before = record[record["time_s"] < own.time_s[0] + fault.onset_s]
            span_s = before["time_s"].iloc[-1] - before["time_s"].iloc[0] if before["time_s"].size else 0.0
            if span_s >= self.watch.settings.min_calibration_s:  # the model's error is not the input's
                model = calibrate(model, before, [p for p in self.watch.settings.calibrate_parameters
                                                  if p in model.parameters], dt_s).model
            rss = []
            for series in (own, other):
                run = simulate(model, series.inputs)
                predicted = np.array([run[o].to_numpy(float) for o in model.output_names])
                residual = (series.outputs - predicted)[:, window]
                rss.append(float(np.nansum(residual ** 2)))
            n = int(np.count_nonzero(np.isfinite(own.outputs[:, window])))
            delta = n * math.log(max(rss[1], 1e-300) / max(rss[0], 1e-300))  # the substitute has no free parameter
            if not delta < -PREFERENCE_BIC:
                fault = None
        found = None
        if fault is not None:
            onset_index = int(np.searchsorted(elapsed, fault.onset_s))
            # the record's samples are stamped at the end of their step; an input reading is in force
            # from the start of it, which is when the fault begins on the mission clock
            start_s = float(own.time_s[0]) - monitor.dt_s
            found = SensorHypothesis(dataclasses.replace(fault, onset_s=start_s + fault.onset_s),
                                     onset_index, math.sqrt(rss[0] / n), math.sqrt(rss[1] / n), delta, "input",
                                     error, alternative=f"its own reading: RMSE {math.sqrt(rss[0] / n):.3f} K against "
                                     f"{math.sqrt(rss[1] / n):.3f} K with the other units' {name}", columns=(name,),
                                     output="")
        self._own_fits[(g, name)] = math.inf if delta is None else delta
        self.watch.checks.append({"time_s": t_s, "generator": g, "alarmed": [name], "claimed": found is not None,
                                  "refused": [], "best_machine_fault": None,
                                  "delta_ic_with_shared_input": delta, "solve_s": time.perf_counter() - started})
        return found

    def _stepped_alone(self, g: int, name: str, monitor):
        """Generator ``g``'s reading of the shared-air input ``name`` stepped by more than
        :attr:`InputWatchSettings.disagreement_K` in one sample within the look-back, while every
        other unit's reading moved less than :attr:`InputWatchSettings.shared_step_K` in that sample,
        and has disagreed with theirs since: the bias from that sample (onset since the mission
        start), or None. A real change of the ambient reaches every unit's sensor."""
        from ...diagnose.sensor_faults import SensorHypothesis

        sources = [h for h in range(self.n_generators) if h != g and (h, name) not in self.claimed]
        if not sources:
            return None
        record = monitor.frame(g)
        time_s, own = record["time_s"].to_numpy(float), record[name].to_numpy(float)
        others = np.array([monitor.frame(h)[name].to_numpy(float) for h in sources])
        if own.size < 2 or others.shape[1] != own.size:
            return None
        difference = own - np.median(others, axis=0)
        moved = np.abs(np.diff(others, axis=1)).max(axis=0)
        recent = time_s[1:] >= time_s[-1] - self.settings.lookback_s
        steps = np.flatnonzero(recent & (np.abs(np.diff(own)) > self.settings.disagreement_K)
                               & (moved < self.settings.shared_step_K)) + 1
        for k in steps[::-1]:
            if np.all(np.abs(difference[k:]) > self.settings.disagreement_K) and \
                    abs(difference[k - 1]) <= self.settings.disagreement_K:
                value = float(np.mean(difference[k:]) - difference[k - 1])
                fault = SensorFault(name, "bias", value, float(time_s[k] - monitor.dt_s))
                return SensorHypothesis(fault, int(k), float("nan"), float("nan"), self._own_fits[(g, name)], "input",
                                        difference, alternative=f"its {name} reading stepped by {value:+.2f} K in one "
                                        f"sample while the other units' moved {float(moved[k - 1]):.2f} K "
                                        f"(the units see one ambient); its record fits its own reading by "
                                        f"{self._own_fits[(g, name)]:+.1f} against the others'", columns=(name,),
                                        output="")
        return None

    def _claim(self, g: int, name: str, hypothesis, t_s: float, estimators, monitor,
               evidence: str = "input record check") -> None:
        """Claim generator ``g``'s sensor of input ``name``: substitute it, drop the effects
        identified since the onset and, unless its filter was held on its last agreeing reading
        since the onset (:meth:`for_filter`), take the unit's heat flows back to before the onset
        plus the common change since and restart its fault test (module docstring)."""
        fault = hypothesis.fault
        self.claimed[(g, name)] = fault
        monitor.replace_input(g, name, fault.onset_s, lambda times, values: self.replacement(g, name, times, values))
        held_since = self._filter_held_since.get((g, name), math.inf)
        # the filter held since the onset (to the record's sample) never took the fault: nothing to take back
        clean = (g, name) not in self._filter_partial and held_since - fault.onset_s <= self.watch.settings.identify_dt_s
        kept = [entry for entry in self._flows[g] if entry[0] < fault.onset_s]
        estimator = estimators[g]
        if not clean and kept and kept[-1][1] == list(estimator.filter.state_names):
            nodes = estimator.filter.model.n_states if isinstance(estimator.filter, ExtendedKalmanFilter) \
                else estimator.z.size
            t_kept, names, flows = kept[-1][0], kept[-1][1], kept[-1][2][nodes:]
            changes = []  # the common change since: what every unit's heat flows followed meanwhile
            for h in range(self.n_generators):
                then = [entry for entry in self._flows[h] if entry[0] == t_kept and entry[1] == names]
                if h != g and then and list(estimators[h].filter.state_names) == names:
                    changes.append(np.asarray(estimators[h].z)[nodes:] - then[0][2][nodes:])
            if changes:
                flows = flows + np.median(changes, axis=0)
            estimator.z = np.concatenate([estimator.z[:nodes], flows])
        if name == self.coolant_input:
            self.unconfirmed_inlet.release(g, t_s, "its sensor claimed: the other units' reading is planned")
        self.watch.undo_beliefs_since(g, fault.onset_s, monitor)
        if clean:
            self._record_claim(g, name, hypothesis, t_s, "the filter held its last agreeing reading since the onset",
                               evidence)
            return
        monitor.detector.restart(g)
        for h in range(self.n_generators):  # every unit was compared with heat flows that followed a wrong input
            # since the onset; a hold older than that is not the input's doing (releasing one that
            # began 50 min before a 3-K inlet bias let its unit's heat flows into the plan at the
            # claim: 3 re-plans and 7 load changes, seed 1 of benchmarks/bench_inlet_confirmation.py)
            if self.watch.unconfirmed.since.get(h, -math.inf) >= fault.onset_s:
                self.watch.unconfirmed.release(h, t_s, f"input sensor {name} of unit {g + 1} claimed")
        self._record_claim(g, name, hypothesis, t_s, "its heat flows taken back to before the onset", evidence)

    def _record_claim(self, g: int, name: str, hypothesis, t_s: float, filter_action: str, evidence: str) -> None:
        """Report the claim of generator ``g``'s sensor of input ``name`` with the watch's claims;
        ``filter_action`` says what was done to the unit's filter, ``evidence`` what showed the fault."""
        self.watch.claims.append({"generator": g, "claimed_at_s": t_s, "fault": hypothesis.fault,
                                  "delta_bic": hypothesis.delta_bic, "alternative": hypothesis.alternative,
                                  "evidence": evidence,
                                  "action": ("substituted by the other units' reading" if self.n_generators > 1
                                             else "corrected by the fitted error") + f"; {filter_action}"})


def _input_error_shape(name: str, elapsed_s, error, first: int) -> SensorFault:
    """The bias or drift (onset at a sample from ``first`` on) that best fits ``error`` (N,), K, the
    reading minus the shared one, by least squares; onset from the record start, s."""
    best = None
    for onset in range(first, elapsed_s.size - 1):
        after = np.arange(elapsed_s.size) >= onset
        for kind, shape in (("bias", after.astype(float)), ("drift", after * (elapsed_s - elapsed_s[onset]) / 3600.0)):
            norm = float(shape @ shape)
            if norm <= 0.0:
                continue
            value = float(shape @ error) / norm
            rss = float(np.sum((error - value * shape) ** 2))
            if best is None or rss < best[0]:
                best = (rss, SensorFault(name, kind, value, float(elapsed_s[onset])))
    return best[1]
