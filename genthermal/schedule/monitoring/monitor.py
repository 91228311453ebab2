"""Fault detection in flight: the tests on each generator's filter, the common model-error test
and recalibration, and the hand-over to identification on an alarm. Main objects:
:class:`FaultMonitor`, :class:`DetectionSettings`, :class:`Cusum`. Method: docs/guide/flight-methods.md.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd

from ...errors import InputError
from ...measurements import required_columns
from .detector import DetectorSettings, DisturbanceDetector, extra_heat_flow
from ...diagnose.error_model import MIN_BASELINE_S
from .fault_identification import FAULT_EFFECTS, confirms, identify_fault
from .flight_error import flight_error_model
from .innovation_detector import InnovationCusum, InnovationCusumSettings
from .record_grid import check_fit_step, on_fit_grid
from ..state_estimator import believed_model


@dataclasses.dataclass(frozen=True)
class DetectionSettings:
    """Fault detection and identification in flight (module docstring).

    Attributes
    ----------
    detector : DetectorSettings
        Drifts and thresholds of the disturbance test (:mod:`genthermal.schedule.monitoring.detector`).
    innovation : InnovationCusumSettings or None
        Drift and threshold of the innovation test
        (:mod:`genthermal.schedule.monitoring.innovation_detector`); None: the disturbance test alone.
        In flight whitened by what it learns in its first 8 tested updates (``learn_updates``).
    model_drift, model_threshold : float
        :math:`\nu_m, h_m` of the common (model error) CUSUM.
    calibrate_parameters : tuple of str
        Parameters recalibrated on the healthy generators' record before an identification and
        on a model-error alarm (those the model lacks are skipped). Default: the five the
        robustness grid varies; with ``R0`` and ``h_end_air`` alone, a plant whose ``P_iron`` is
        off was "identified" as an excitation iron loss from the mission start instead of its
        shorted turn (``benchmarks/bench_detection.py``, cases 5 and 9).
    recalibrate_every_s : float
        Shortest time between recalibrations, s.
    min_record_s : float
        A model-error alarm recalibrates only on a record at least this long, s (shorter records
        do not separate the parameters).
    max_recalibrations : int
        Recalibrations per flight on model-error alarms (a fault alarm always recalibrates).
    fault_effects : tuple of str
        Candidate effects of the identification.
    identify_dt_s : float
        Sample period of the records handed to calibration and identification, s: a whole
        multiple of the flight's step (:meth:`FaultMonitor.fit_record`).
    max_identifications : int
        Identifications (whatever their outcome) per generator and flight; later alarms are
        recorded only. 8: with the innovation test alarming from 9 min after blockage_large's
        onset (heuristic), the first four identifications (75-105 min) named a stray loss, a
        shorted turn and a k_flow 0.86 blockage before the record told the blockage's size; with
        4 the flight kept the last.
    identify_spacing_s : float
        Shortest time between two identifications of one generator, s (alarms in between are
        recorded only).
    max_onset_lead_s : float
        An identified effect must start at most this long before the alarm, s: the detector
        compares the generators from the first cycles on, so a fault present much earlier would
        have alarmed earlier; an effect fitted from the mission start is the model error, not
        the fault.
    late_onset_s : float
        ... unless it starts at least this long after the mission start, s: a manager that moves
        load off a generator it sees hot (the disturbance heat flows in the plan) can delay the
        alarm by more than ``max_onset_lead_s``. On blockage_large with the optimal scheduler the
        first alarm on the blocked generator came at 145 min, 79 min after the onset, and the
        blockage fitted with onset 69 min (ΔBIC -712) was refused at four alarms in a row. The
        model's own error shows from the first minutes (fits with onsets of 8-15 min on the same
        flight), well before 60 min.
    confirm_tolerance : float
        A new identification of the believed effect whose parameters each differ from the
        believed ones by at most this fraction of the larger of the believed value and the
        parameter's typical value (:class:`~genthermal.effects.EffectParameter`; a convection
        exponent near 0 does not count as changed by 0.01) confirms the belief, which is kept: the filters and plan
        do not restart for a refinement, and the sensor watch does not re-check the record (on
        the robustness grid's case 0 a k_flow 0.197 → 0.174 refinement had the watch claim the
        blocked unit's winding sensor as stuck and mask it).
    equivalent_delta_bic : float
        Effects within this ΔBIC of the identified one are reported as equivalent explanations
        (Kass & Raftery 1995: a BIC difference below 2 is not worth more than a bare mention);
        a shorted turn and an end-winding stray loss, both a loss ∝ I² in the winding, are
        typically within it.
    error_model : bool
        Score the identification's hypotheses on the AR(1) error of the recalibrated model on the
        healthy generator's record it was recalibrated on
        (:mod:`~genthermal.schedule.monitoring.flight_error`), re-estimated at each recalibration
        on a record long enough for it (1 h and 5 correlation times); until then, and with
        False, as if the model's error were white sensor noise.
    interval_level : float
        Coverage of the identified parameters' intervals; the manager believes the end of each
        that is the most severe fault (:mod:`genthermal.schedule.monitoring.fault_identification`,
        "Uncertainty"). 0.95: the usual two-sided 95 %.
    """

    detector: DetectorSettings = DetectorSettings()
    innovation: InnovationCusumSettings | None = InnovationCusumSettings(inlet_tolerance_K=1.0, learn_updates=8)
    model_drift: float = 2.5
    model_threshold: float = 5.0
    calibrate_parameters: tuple = ("R0", "h_end_air", "h_top_air", "P_iron", "m_dot_fan")
    recalibrate_every_s: float = 1800.0
    min_record_s: float = 3600.0
    max_recalibrations: int = 3
    fault_effects: tuple = FAULT_EFFECTS
    identify_dt_s: float = 60.0
    max_identifications: int = 8
    identify_spacing_s: float = 600.0
    max_onset_lead_s: float = 3600.0
    late_onset_s: float = 3600.0
    confirm_tolerance: float = 0.25
    equivalent_delta_bic: float = 2.0
    error_model: bool = True
    interval_level: float = 0.95

    def __post_init__(self):
        if not 0.0 < self.interval_level < 1.0:
            raise InputError("detection.interval_level", self.interval_level,
                             "the coverage of the identified parameters' intervals must lie strictly between 0 and 1")


class Cusum:
    """CUSUM with drift :math:`\nu` and threshold :math:`h`; one- or two-sided."""

    def __init__(self, drift: float, threshold: float, two_sided: bool = False):
        self.drift, self.threshold, self.two_sided = drift, threshold, two_sided
        self.high = self.low = 0.0

    def update(self, z: float) -> bool:
        """Add one cycle; True when a statistic crosses the threshold (both then restart)."""
        if not np.isfinite(z):
            return False
        self.high = max(0.0, self.high + z - self.drift)
        self.low = max(0.0, self.low - z - self.drift) if self.two_sided else 0.0
        if max(self.high, self.low) > self.threshold:
            self.high = self.low = 0.0
            return True
        return False


def record_frame(interface, time_s, currents_A, excitation_A, inlet_C, ambient_C,
                 measured_C) -> pd.DataFrame:
    """A generator's in-flight record in the measurement CSV schema (balanced phases).

    Parameters
    ----------
    interface : MachineInterface
        The generator's (``model.spec.interface``, with the generator role): the column names.
    time_s : array_like
        (n,) s.
    currents_A, excitation_A, inlet_C : array_like
        (n,) phase current, field current (A) and inlet temperature (°C) in force at each sample.
    ambient_C : float or array_like
        Ambient temperature, °C (one, or (n,) per sample).
    measured_C : array_like
        (n_sensors, n) measured sensor temperatures in the interface's output order, °C.
    """
    generator = interface.generator
    frame = {"time_s": np.asarray(time_s, dtype=float)}
    for name in generator.phase_inputs:
        frame[name] = currents_A
    frame[generator.excitation_input] = excitation_A
    frame[generator.coolant_input] = inlet_C
    frame[generator.ambient_input] = np.broadcast_to(np.asarray(ambient_C, dtype=float), frame["time_s"].shape).copy()
    for sensor, measured in zip(interface.sensors, measured_C):
        for column in sensor.columns:
            frame[column] = measured
    return pd.DataFrame(frame)[list(required_columns(interface))]


class FaultMonitor:
    """Detection, recalibration and identification for every generator of one flight.

    Parameters
    ----------
    system_frame : SystemFrame
        The power system's generators, currents, inputs and the mission's inlet
        (:meth:`PowerSystem.frame <genthermal.schedule.power_system.PowerSystem.frame>`).
    planning_model : ThermalModel
        The model the manager plans on: the belief of a healthy unit and the start of every
        recalibration.
    design_generator_for : callable
        ``design_generator_for(effects, base=None)``: the design model of a belief
        (:meth:`PowerSystem.design_generator_for
        <genthermal.schedule.power_system.PowerSystem.design_generator_for>`, which caches them).
    settings : DetectionSettings
    dt_s : float
        Step of the record, s.

    Attributes
    ----------
    model : ThermalModel
        The planning model, recalibrated in flight.
    beliefs : list of tuple
        Per generator, the identified effects (``(name, ((parameter, value), ...))``).
    alarms : list of dict
        ``time_s``, ``generator``, ``node`` (``winding`` or ``iron``), ``test`` (``innovation`` or
        ``disturbance``) and ``statistic`` (the innovation test's CUSUM sum in K, or the
        disturbance test's :math:`r`) of every fault alarm.
    identifications : list of Identification
    calibrations : list of dict
        ``time_s``, ``generator`` (whose record), ``parameters``, the model and ``error_model``
        (the :class:`~genthermal.diagnose.error_model.ErrorModel` estimated on that record, None
        when it was too short or ``DetectionSettings.error_model`` is off).
    error_model : ErrorModel or None
        The latest of those the identification scores with (None: white noise).
    """

    def __init__(self, system_frame, planning_model, design_generator_for, settings: DetectionSettings,
                 dt_s: float):
        check_fit_step("detection.identify_dt_s", settings.identify_dt_s, dt_s)
        self.system_frame, self.settings, self.dt_s = system_frame, settings, dt_s
        self.planning_model, self._design_generator_for = planning_model, design_generator_for
        n = system_frame.n_generators
        self.node_roles = detector_node_roles(planning_model)
        self.detector = DisturbanceDetector(n, settings.detector, self.node_roles)
        self.model_test = Cusum(settings.model_drift, settings.model_threshold, two_sided=True)
        self.model, self.beliefs = planning_model, [()] * n
        self.alarms, self.identifications, self.calibrations = [], [], []
        self.error_model = None
        #: ``(generator, node index)`` out of the fault test after a sensor of the generator was
        #: masked by the sensor watch (:meth:`mask`, :meth:`DisturbanceDetector.statistics`).
        self.masked: set = set()
        self.innovation_test = None if settings.innovation is None or n < 2 else InnovationCusum(
            n, dt_s, system_frame.T_ambient_C, design_generator_for(()), settings.innovation)
        self._time, self._currents, self._measured, self._inputs = [], [], [], []
        #: Beliefs the innovation test's filters last ran on (a change relearns its level).
        self._tested_beliefs = list(self.beliefs)

    def record(self, t0: float, currents_A, measured_C, inputs_C=None) -> None:
        """Add the steps flown from ``t0``: currents (n_gen, n) and sensors (n_gen, 2, n) at the end
        of each step; ``inputs_C`` maps the measured inputs (coolant inlet, ambient) to their
        readings (n_gen, n) °C in force during each step (default: the mission's true values)."""
        self._time.append(t0 + self.dt_s * np.arange(currents_A.shape[1]))
        self._currents.append(currents_A)
        self._measured.append(measured_C)
        self._inputs.append({name: np.array(v, dtype=float, copy=True) for name, v in (inputs_C or {}).items()})
        if self.innovation_test is not None:
            coolant = self.system_frame.role.coolant_input
            for g in range(self.system_frame.n_generators):
                inlet = (self._inputs[-1][coolant][g] if coolant in self._inputs[-1]
                         else self.system_frame.inlet_C(g, self._time[-1], currents_A))
                self.innovation_test.predict(g, currents_A[g], inlet)

    def replace_input(self, g: int, name: str, from_s: float, replacement) -> None:
        """Rewrite generator ``g``'s recorded reading of input ``name`` from ``from_s`` (s since the
        mission start) on with ``replacement(times, readings (n_gen, n)) -> (n,)`` of each recorded
        cycle (a claimed input sensor, :mod:`~genthermal.schedule.monitoring.input_watch`)."""
        for times, inputs in zip(self._time, self._inputs):
            if name in inputs and np.any(times >= from_s):
                inputs[name][g] = replacement(times, inputs[name])

    def mask(self, g: int, row: int, from_s: float) -> None:
        """Take generator ``g`` out of the fault test and its sensor ``row`` out of its record from
        ``from_s`` (s since the mission start) on: a sensor fault was claimed, and neither the
        identification nor a recalibration may read the faulty samples as heat. The whole
        generator leaves the test: with one sensor the filter cannot tell the heat flows of the
        two nodes apart (on the Fig. 7.7 flight with the iron sensor of one unit masked, its
        winding statistic alarmed three times, recalibrated the model and moved the plan)."""
        self.masked.update((g, j) for j in range(self.detector.sums.shape[1]))
        for times, measured in zip(self._time, self._measured):
            measured[g, row, times + self.dt_s >= from_s] = np.nan

    def frame(self, g: int) -> pd.DataFrame:
        """Generator ``g``'s record so far in the measurement schema."""
        time_s = np.concatenate(self._time) + self.dt_s
        currents = np.concatenate(self._currents, axis=1)
        current = currents[g]
        measured = np.concatenate(self._measured, axis=2)[g]
        interface, system = self.planning_model.spec.interface, self.system_frame
        excitation = interface.generator.exciter_law(current, system.power_factor, system.rated_current_A)
        generator = interface.generator
        inlet = self._recorded_input(g, generator.coolant_input, system.inlet_C(g, time_s - self.dt_s, currents))
        ambient = self._recorded_input(g, generator.ambient_input, np.full(time_s.shape, system.T_ambient_C))
        return record_frame(interface, time_s, current, excitation, inlet, ambient, measured)

    def fit_record(self, g: int, dt_s: float | None = None) -> pd.DataFrame:
        """Generator ``g``'s record so far on the grid of ``dt_s`` (default ``identify_dt_s``; a
        whole multiple of the record's step), each row's inputs averaged over the steps it is held
        for (currents as root mean square): what recalibration, identification and the sensor
        watch's record checks fit (:func:`~genthermal.schedule.monitoring.record_grid.on_fit_grid`, module
        docstring)."""
        interface = self.planning_model.spec.interface
        generator = interface.generator
        return on_fit_grid(self.frame(g), self.settings.identify_dt_s if dt_s is None else dt_s,
                           [*generator.phase_inputs, generator.excitation_input],
                           [column for sensor in interface.sensors for column in sensor.columns])

    def _recorded_input(self, g: int, name: str, true_values) -> np.ndarray:
        """Generator ``g``'s recorded reading of input ``name`` over the record, ``true_values``
        where none was recorded."""
        if not all(name in inputs for inputs in self._inputs):
            return np.asarray(true_values, dtype=float)
        return np.concatenate([inputs[name][g] for inputs in self._inputs])

    def design_generator(self, g: int):
        """Design model of generator ``g`` as the manager believes it."""
        return self._design_generator_for(self.beliefs[g], base=self.model)

    def flown_model(self, g: int):
        """Nonlinear model of generator ``g`` as the manager believes it (what
        :meth:`design_generator` linearises)."""
        return believed_model(self.model, self.beliefs[g])

    def cycle(self, t_s: float, estimators, detection_estimators=None) -> None:
        """Run both tests on the cycle just flown (every estimator just updated).

        Parameters
        ----------
        t_s : float
            Time of the cycle's end, s.
        estimators : sequence of StateEstimator
            The planner's filters (their innovations feed the model-error test).
        detection_estimators : sequence of StateEstimator, optional
            Extended Kalman filters whose disturbance states feed the fault test; default
            ``estimators`` (which must then be extended Kalman filters).
        """
        innovation_alarms = self._innovation_cycle()
        if len(self._time) < 2:
            return
        detection_estimators = estimators if detection_estimators is None else detection_estimators
        z = np.array([e.innovation[0] / e.innovation_std[0] for e in estimators])
        healthy = [g for g in range(len(z)) if not self.beliefs[g]]
        r = self.statistics(detection_estimators)
        alarms = [(g, node, "disturbance", float(r[g, node])) for g, node in self.detector.update(t_s, r)]
        alarms += [(g, self.node_roles.index("winding"), "innovation", sum_K) for g, sum_K in innovation_alarms]
        for g, node, test, statistic in alarms:  # one alarm per generator and cycle: the disturbance test's first
            if not any(a["time_s"] == t_s and a["generator"] == g for a in self.alarms):
                self._fault_alarm(g, t_s, z, node, statistic, test)
        last = max((c["time_s"] for c in self.calibrations), default=-np.inf)
        if healthy and self.model_test.update(float(np.mean(z[healthy]))) and t_s >= self.settings.min_record_s and \
                t_s - last >= self.settings.recalibrate_every_s and \
                len(self.calibrations) < self.settings.max_recalibrations:
            self._recalibrate(t_s, healthy, z)

    def _innovation_cycle(self) -> list:
        """Measurement update and test of the innovation test with the readings recorded last
        (masked sensors NaN), each filter first moved to the design model as now believed; its
        alarms ``(generator, CUSUM sum K)``. A generator with a masked sensor is neither tested
        nor a reference."""
        test = self.innovation_test
        if test is None or not self._measured:
            return []
        n = self.system_frame.n_generators
        for g in range(n):
            test.use(g, self.design_generator(g), relearn=self.beliefs[g] != self._tested_beliefs[g])
        self._tested_beliefs = list(self.beliefs)
        measured = self._measured[-1][:, :, -1]
        left_out = {g for g, _ in self.masked}
        references = [[h for h in range(n) if h != g and not self.beliefs[h] and h not in left_out] for g in range(n)]
        for g in left_out:
            references[g] = []
        return test.update(measured, np.mean(self._currents[-1], axis=1), references)

    def statistics(self, detection_estimators) -> np.ndarray:
        """The fault test's :math:`r_{gj}` (n_generators, n_nodes) of the cycle just recorded, from
        the extended Kalman filters ``detection_estimators`` (just updated); the test's sums are
        not touched (NaN before two cycles are recorded)."""
        if len(self._time) < 2:
            return np.full(self.detector.sums.shape, np.nan)
        load_factors = np.mean(self._currents[-1] ** 2, axis=1) / self.system_frame.rated_current_A ** 2

        def extra(g, load_factor):
            e = detection_estimators[g]
            return extra_heat_flow(e.filter, e.z, e.P, load_factor)
        return self.detector.statistics(extra, load_factors, [not b for b in self.beliefs], self.masked)

    def readings(self, g: int) -> tuple:
        """Generator ``g``'s sensor readings so far: (time_s (N,), readings (n_sensors, N) °C) as
        recorded (masked sensors NaN)."""
        return (np.concatenate(self._time) + self.dt_s, np.concatenate(self._measured, axis=2)[g])

    def _recalibrate(self, t_s: float, candidates, z) -> None:
        from ...diagnose import calibrate

        candidates = [h for h in candidates if (h, 0) not in self.masked]  # a masked sensor: not a reference
        if not candidates:
            return
        g = min(candidates, key=lambda h: z[h])
        names = [n for n in self.settings.calibrate_parameters if n in self.planning_model.parameters]
        record = self.fit_record(g)
        result = calibrate(self.planning_model, record, names, self.settings.identify_dt_s)
        self.model = result.model
        error_model = None
        if self.settings.error_model and record["time_s"].iloc[-1] - record["time_s"].iloc[0] >= MIN_BASELINE_S:
            try:
                error_model = flight_error_model(result.model, record, self.settings.identify_dt_s)
            except InputError as short:  # its residual stays correlated for more than a fifth of the record
                if short.field != "baseline":
                    raise
        self.error_model = error_model or self.error_model
        self.calibrations.append({"time_s": t_s, "generator": g, "model": result.model,
                                  "parameters": dict(zip(result.names, result.values)), "error_model": error_model})

    def _fault_alarm(self, g: int, t_s: float, z, node: int, statistic: float, test: str) -> None:
        self.alarms.append({"time_s": t_s, "generator": g, "node": self.node_roles[node], "test": test,
                            "statistic": statistic})
        if test == "innovation":  # detection only: identification waits for the disturbance test
            return
        earlier = [i for i in self.identifications if i.generator == g]
        if len(earlier) >= self.settings.max_identifications or \
                (earlier and t_s - earlier[-1].detected_at_s < self.settings.identify_spacing_s):
            return
        others = [h for h in range(len(z)) if h != g and not self.beliefs[h]]
        if others:
            self._recalibrate(t_s, others, z)
        found = identify_fault(self.model, self.fit_record(g), g, t_s, self.settings, self.error_model)
        self.identifications.append(found)
        if found.effect and not confirms(found.effects, self.beliefs[g], self.settings.confirm_tolerance):
            self.beliefs[g] = found.effects
            self.detector.restart(g)
            if self.innovation_test is not None:
                self.innovation_test.restart(g)


def detector_node_roles(model) -> list:
    """Per sensor node of ``model`` (the extended Kalman filter's disturbance nodes), ``"winding"``
    when it is the machine's slot-winding node and ``"iron"`` when it is one of its iron nodes
    (:class:`~genthermal.machines.Role`); InputError for any other sensor node."""
    from ...machines import Role

    interface = model.spec.interface
    winding = interface.role(Role.SLOT_WINDING, "the fault detector")
    iron = tuple(interface.role(Role.IRON, "the fault detector"))
    roles = []
    for output, node in model.spec.sensors.items():
        if node != winding and node not in iron:
            raise InputError("model.sensors", output, f"senses node {node}, neither the slot winding ({winding}) "
                             f"nor the iron ({', '.join(iron)}): the fault detector has no drift for it")
        roles.append("winding" if node == winding else "iron")
    return roles
