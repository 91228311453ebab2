"""The closed loop of thesis 7.2 (``fly``): every cycle update the filters, watch the sensors, test
for faults, predict to the end of the mission and re-plan when a breach is predicted.

Main objects: :func:`fly`, :class:`TrustedHeatFlows`, :func:`replay_score`. Method:
docs/guide/flight-methods.md; the plant protocol: :mod:`genthermal.plants`.
"""

from __future__ import annotations

import time

import numpy as np

from ...errors import InputError
from ...estimation.ekf import ExtendedKalmanFilter
from ...plants.model_plant import ModelPlant
from ...plants.protocol import PlantFault, PlantSetup, check_sensors, checked_readings
from .flight_result import FlightRecorder, FlightResult, FlightTimeout
from ..planning.flown import FlownPlanning
from ..monitoring.input_watch import InputWatch
from .manager_settings import ManagerSettings
from ..monitoring.monitor import FaultMonitor
from ..state_estimator import StateEstimator, believed_model, planning_generator
from .open_loop import told_beliefs
from .preflight import preflight_check
from ..planning.plan import Schedule, build_timeline, generator_inputs, predict, remaining_after
from ..power_system import PowerSystem
from ..system_frame import SystemFrame
from ..monitoring.record_grid import check_fit_step
from .replanning import first_rest_max_s, flight_segments, plan_with, planning_problem
from .sensor_injection import SensorFaultInjector, parse_sensor_faults
from ..monitoring.sensor_watch import SensorWatch
from ..planning.shed import unexplained_rise


class TrustedHeatFlows:
    """The disturbance heat flows each generator's plan may carry (offset-free planning).

    While the sensor watch trusts a generator's heat flows (:meth:`SensorWatch.trusts_heat_flows
    <genthermal.schedule.monitoring.sensor_watch.SensorWatch.trusts_heat_flows>`), the plan takes the
    filter's current ones and they are kept. While it does not (a sensor claimed faulty, or the
    sensor pattern under check), the plan holds the last trusted ones with the filter's current node
    temperatures: dropping them altogether made the stuck-sensor flight of
    ``tests/test_sensor_watch.py`` re-plan at every cycle after the claim, and taking the current
    ones re-planned on heat flows learnt from the faulty readings. A filter whose state
    changed since (a new model) plans without them until they are trusted again.
    """

    def __init__(self, n_generators: int):
        self._kept: list = [None] * n_generators

    def planning_generator(self, g: int, estimator, trusts: bool):
        """Generator ``g``'s design generator for the plan (see the class docstring)."""
        if trusts:
            self._kept[g] = (list(estimator.filter.state_names), np.array(estimator.z, dtype=float))
            return estimator.planning_generator
        kept = self._kept[g]
        if kept is None or kept[0] != list(estimator.filter.state_names):
            return estimator.generator
        state = np.array(estimator.z, dtype=float)
        nodes = estimator.filter.model.n_states if isinstance(estimator.filter, ExtendedKalmanFilter) else state.size
        state[nodes:] = kept[1][nodes:]
        return planning_generator(estimator.generator, estimator.filter, state)


def plant_inputs(frame: SystemFrame, timeline, t0: float) -> dict:
    """The machine's inputs over ``timeline`` from ``t0`` (s), as a plant is given them: input name →
    (n_gen, n) (phase currents A RMS, the exciter current following the load, the coolant inlet with
    the faults' rises and the ambient, °C); ``frame``: :meth:`PowerSystem.frame`."""
    # the currents a load-following inlet rise reads, the final one repeated for the frame's last row
    currents = np.hstack([timeline.currents_A, timeline.currents_A[:, -1:]])
    frames = [generator_inputs(timeline, g, t0, lambda t, g=g: frame.inlet_C(g, t, currents),
                               frame.T_ambient_C, frame.power_factor, frame.rated_current_A, frame.role)
              for g in range(frame.n_generators)]
    return {name: np.array([inputs[name].to_numpy()[:-1] for inputs in frames]) for name in frame.input_names}


def plant_setup(system: PowerSystem, dt_s: float) -> PlantSetup:
    """What a plant is told at take-off (:class:`~genthermal.plants.protocol.PlantSetup`)."""
    faults = tuple({"generator": f.generator, "onset_s": f.onset_s, "kind": f.kind, "effect": f.effect,
                    "values": dict(f.values), "inlet_rise_C": f.inlet_rise_C} for f in system.faults)
    return PlantSetup(tuple(system.generator_names), tuple(system.planning_model.input_names),
                      tuple(system.planning_model.output_names), dt_s, system.mission.T_ambient_C, faults)


def true_inputs(frame: SystemFrame, input_names, times, currents_A=None) -> dict:
    """The true values of the measured inputs ``input_names`` (coolant inlet, ambient) of every
    generator at ``times`` (s): input name → (n_gen, n) °C. ``frame``: :meth:`PowerSystem.frame`;
    ``currents_A`` (n_gen, n): the phase currents flown at ``times``, A, which an inlet rise that
    follows the load reads (:meth:`PowerSystem.inlet_C`; None: the undisplaced load)."""
    generator = frame.role
    times = np.asarray(times, dtype=float)
    values = {generator.coolant_input: np.array([frame.inlet_C(g, times, currents_A)
                                                 for g in range(frame.n_generators)]),
              generator.ambient_input: np.full((frame.n_generators, times.size), frame.T_ambient_C)}
    return {name: values[name] for name in input_names if name in values}


def _filter_inputs(frame: SystemFrame, inputs_C: dict, times, currents_A=None) -> tuple:
    """Per generator, the inlet (n,) and ambient (n,) temperatures its filter is driven with, °C: the
    readings in ``inputs_C`` (:func:`true_inputs` keys), the true values for an input not read
    (with the phase currents ``currents_A`` flown at ``times``)."""
    generator = frame.role
    true = true_inputs(frame, (generator.coolant_input, generator.ambient_input), times, currents_A)
    inlet = inputs_C.get(generator.coolant_input, true[generator.coolant_input])
    ambient = inputs_C.get(generator.ambient_input, true[generator.ambient_input])
    return inlet, ambient


def fly(system: PowerSystem, scheduler: str, settings: ManagerSettings = ManagerSettings(), plant=None,
        preflight: dict | bool | None = None) -> FlightResult:
    """Fly the mission in closed loop on the true plant (module docstring).

    Parameters
    ----------
    system : PowerSystem
        The generators, the mission, its faults and the true plants (:meth:`PowerSystem.from_mission`).
    scheduler : str
        Who re-plans when a breach is predicted: heuristic, engineer, optimal, milp or a planner
        registered by name (:func:`~genthermal.schedule.planning.registry.register_planner`).
    settings : ManagerSettings
        Management cycle, margin, filter, rest budget, noise seed and each scheduler's settings.
    plant : Plant, optional
        What is flown (:mod:`genthermal.plants`); default the model plant of ``system``
        (:class:`~genthermal.plants.model_plant.ModelPlant`). When it fails in flight (raises, or
        reads other sensors, other timestamps or a non-finite value), the flight stops there: the
        result holds what was flown and the fault (``plant_fault``), the manager holding the
        minimum power mode.
    preflight : dict or False, optional
        The verdict before take-off (:func:`~genthermal.schedule.flight.preflight.preflight_check`,
        which a caller that prints it first passes here); None (default): the flight makes it;
        False: none (a robustness sweep, whose flights are judged by what they fly).

    Returns
    -------
    FlightResult
        True-plant temperatures, applied currents, one record per re-plan, the alarms with
        what was identified and ``preflight``.

    Raises
    ------
    FlightTimeout
        When ``settings.cpu_limit_s`` is set and a management cycle starts past it.
    InputError
        When the plant's sensors are not the machine's, or it raises at its reset.
    """
    started = time.process_time()
    roles = settings.roles(scheduler, system.mission.duration_s, system.manager_say)
    loop, planner, filter_name = roles.loop, roles.planner, roles.estimator.filter
    settings = settings.for_flight(scheduler, filter_name)  # planner_model "auto" resolved, as in roles
    if preflight is None:
        preflight = preflight_check(system, scheduler, settings)
    frame = system.frame()
    n_gen, dt = frame.n_generators, loop.dt_s
    cycle_steps = max(int(round(loop.cycle_s / dt)), 1)
    rng = np.random.default_rng(loop.seed)
    noise_sd = np.sqrt(np.asarray(system.planning_model.spec.interface.noise_variances_K2))
    segments = flight_segments(system.mission, planner, scheduler)
    schedule = Schedule.nominal(n_gen, len(segments))
    cold = np.full((n_gen, system.nominal_model.n_states), frame.T_ambient_C)
    filter_cache: dict = {}
    estimators = [StateEstimator(system.design_generator_for(()), lambda: system.planning_model, cold[g], dt,
                                 filter_cache, filter_name) for g in range(n_gen)]
    # the fault detector reads an extended Kalman filter's disturbance states: with the linear
    # filter in the loop it gets parallel extended Kalman filters of its own
    detector_cache: dict = {}
    detectors = estimators if filter_name == "ekf" or loop.tell_fault else [
        StateEstimator(system.design_generator_for(()), lambda: system.planning_model, cold[g], dt,
                       detector_cache, "ekf") for g in range(n_gen)]
    monitor = FaultMonitor(frame, system.planning_model, system.design_generator_for, roles.monitor.detection, dt)
    from ...diagnose.input_sensors import input_sensors

    input_names = input_sensors(system.planning_model.spec.interface)
    sensor_faults = parse_sensor_faults(system.mission.extras.get("sensor_faults"), frame.generator_names,
                                        frame.output_names, input_names)
    injector = SensorFaultInjector(sensor_faults, noise_sd, loop.seed)
    check_fit_step("sensor_watch.identify_dt_s", roles.monitor.sensor_watch.identify_dt_s, dt)
    watch = SensorWatch(frame, monitor.node_roles, roles.monitor.sensor_watch, roles.monitor.detection,
                        sensor_faults)
    inputs_watch = InputWatch(watch, roles.monitor.input_watch, input_names, n_gen, roles.monitor.margin_K)

    def read_inputs(times, currents_A):
        """The inputs as the manager reads them at ``times`` (s), the generators carrying ``currents_A``
        (n_gen, n) A: injected faults, claimed ones substituted."""
        return inputs_watch.substitute(times, injector.apply_inputs(times, true_inputs(frame, input_names, times,
                                                                                       currents_A)))
    trusted = TrustedHeatFlows(n_gen)
    recorder = FlightRecorder(frame)
    budget = loop.rest_budget_s
    plant = ModelPlant(system.true_plants()) if plant is None else plant
    sensors = frame.output_names
    check_sensors(plant, "--plant", type(plant).__name__, sensors)
    try:
        plant.reset(plant_setup(system, dt))
    except InputError:
        raise
    except Exception as error:  # noqa: BLE001 - any failure of a user's plant is named, never a traceback
        raise InputError("--plant", type(plant).__name__, f"the plant raised at its reset: "
                         f"{type(error).__name__}: {error}") from None
    plant_fault = None
    measured, inputs_read, t, rested_s, resting_s, cycles = None, None, 0.0, 0.0, 0.0, 0
    carried_A = None  # (n_gen, 1) the currents of the last step flown: the inlet read when planning
    while segments:
        if loop.cpu_limit_s is not None and time.process_time() - started > loop.cpu_limit_s:
            raise FlightTimeout(t, cycles, time.process_time() - started, loop.cpu_limit_s)
        cycles += 1
        if measured is not None:
            before = [(e.z.copy(), None if e.P is None else e.P.copy()) for e in estimators]
            for g, estimator in enumerate(estimators):
                estimator.update(measured[g])
                if detectors is not estimators:
                    detectors[g].update(measured[g])
            if not loop.tell_fault:
                # sensor faults first: never seen as heat
                watch.cycle(t, estimators, measured, before, monitor, detectors)
                inputs_watch.cycle(t, inputs_read, estimators, monitor)
                believed, model = list(monitor.beliefs), monitor.model
                monitor.cycle(t, estimators, detectors)
                watch.review(t, believed, estimators, monitor, model)  # a new belief may be a sensor's doing
        beliefs = told_beliefs(system, t) if loop.tell_fault else monitor.beliefs
        for g, estimator in enumerate(estimators):
            if loop.tell_fault:
                estimator.use(system.design_generator_for(beliefs[g]),
                              lambda g=g: believed_model(system.planning_model, beliefs[g]))
            else:
                estimator.use(monitor.design_generator(g), lambda g=g: monitor.flown_model(g))
                if detectors is not estimators:
                    detectors[g].use(monitor.design_generator(g), lambda g=g: monitor.flown_model(g))
        flown = FlownPlanning([e.filter for e in estimators], [e.z for e in estimators], [e.P for e in estimators],
                              planner.confidence_sigmas) if planner.nonlinear or planner.own_shed else None
        trusts = [watch.trusts_heat_flows(g, t) for g in range(n_gen)]
        # a sensor the watch does not trust may be what the innovation shows: no rise from it
        rise = np.array([unexplained_rise(e.innovation, e.innovation_std) if trusts[g] else np.zeros(len(sensors))
                         for g, e in enumerate(estimators)])
        problem = planning_problem(frame, planner, segments, [e.x for e in estimators], t,
                                   [trusted.planning_generator(g, e, trusts[g]) for g, e in enumerate(estimators)],
                                   np.floor((budget - rested_s) / dt + 1e-9) * dt, resting_s,
                                   flown if planner.nonlinear else None,
                                   inputs_watch.for_plan(read_inputs(np.array([t]), carried_A)), rise)
        shedding = bool(recorder.plans) and recorder.plans[-1]["method"] == "shed"  # re-planned every cycle
        if loop.replan and (shedding or predict(problem, schedule).peak()[0]
                            > problem.limit_C + loop.replan_tolerance_K):
            planning_started = time.process_time()
            result = plan_with(scheduler, problem, planner, frame.generator_names, frame.limit_C,
                               previous=schedule, switched_off=schedule.switched_off, shedding=shedding,
                               flown_shed=flown if planner.own_shed else None)
            result.details["solve_cpu_s"] = time.process_time() - planning_started  # wall time is the machine's
            schedule = result.schedule.rounded(dt).within_rest_budget(problem.rest_budget_s,
                                                                      first_rest_max_s(problem))
            recorder.plan(t, result, beliefs)
        timeline = build_timeline(segments, schedule, frame.rest_current_A, dt)
        n = min(cycle_steps, timeline.n_steps, replay_steps_left(plant, t, dt))
        if n <= 0:  # a replayed log ends the flight at its last row
            break
        applied = timeline.head(n)
        step_times = t + dt * np.arange(n)
        sample_times = t + dt * np.arange(1, n + 1)
        try:
            try:
                readings = plant.step(t, dt, plant_inputs(frame, applied, t))
            except PlantFault:
                raise
            except Exception as error:  # noqa: BLE001 - a plant's failure is recorded, the flight so far kept
                raise PlantFault("raised", f"the plant raised: {type(error).__name__}: {error}") from None
            outputs = checked_readings(readings, sensors, n_gen, sample_times)
            flown_A = checked_currents(readings, applied.currents_A)
        except PlantFault as fault:
            plant_fault = {"time_s": float(t), "cycle": cycles, "kind": fault.kind, "message": str(fault),
                           "plant": type(plant).__name__, "held": "minimum power mode",
                           "rest_current_A": float(frame.rest_current_A)}
            recorder.warnings.append(f"plant fault at {t:g} s: {fault}; the flight stops there, the manager "
                                     f"holding the minimum power mode ({frame.rest_current_A:.2f} A)")
            break
        inputs_read = read_inputs(step_times, flown_A)
        inlets, ambients = _filter_inputs(frame, inputs_watch.for_filter(step_times, inputs_read), step_times,
                                          flown_A)
        for g, estimator in enumerate(estimators):
            estimator.predict(flown_A[g], inlets[g], ambients[g])
            if detectors is not estimators:
                detectors[g].predict(flown_A[g], inlets[g], ambients[g])
        sensed = outputs + noise_sd[None, :, None] * rng.standard_normal(outputs.shape)
        read = injector.apply(sample_times, sensed)
        monitor.record(t, flown_A, watch.correct(sample_times, read), inputs_read)
        measured = watch.correct(sample_times, read, for_filter=True)[:, :, -1]
        recorder.add(segments, timeline, n, outputs, t, flown_A)
        carried_A = flown_A[:, -1:]
        rested_s += float(np.count_nonzero(applied.resting)) * dt
        running = np.flatnonzero(~applied.resting)
        resting_s = resting_s + n * dt if running.size == 0 else float(n - 1 - running[-1]) * dt
        segments, schedule = remaining_after(segments, schedule, timeline, n)
        t += n * dt
    result = FlightResult(system, scheduler, True, **recorder.record(), monitor=monitor, settings=settings,
                          cycles=cycles, rest_budget_s=budget)
    result.sensor_watch = watch
    result.plant_fault = plant_fault
    result.preflight = preflight or None
    if preflight and not preflight["feasible"]:
        result.warnings.insert(0, preflight["message"])
    if getattr(plant, "replays_log", False):
        result.replay = replay_score(result, recorder, plant)
    return result


def replay_steps_left(plant, t_s: float, dt_s: float) -> int:
    """Steps of ``dt_s`` a replayed log has left after ``t_s`` (s); unbounded for any other plant."""
    end_s = getattr(plant, "end_s", None) if getattr(plant, "replays_log", False) else None
    return np.iinfo(np.int64).max if end_s is None else int(np.floor((end_s - t_s) / dt_s + 1e-9))


def checked_currents(readings, commanded_A: np.ndarray) -> np.ndarray:
    """The phase currents the plant carried, A RMS (n_gen, n): its ``applied_A`` (a replayed log's)
    or the commanded ones; a :class:`PlantFault` when they are of another shape or not finite."""
    applied = getattr(readings, "applied_A", None)
    if applied is None:
        return commanded_A
    applied = np.asarray(applied, dtype=float)
    if applied.shape != commanded_A.shape:
        raise PlantFault("shape", f"the plant's applied currents have the shape {list(applied.shape)}, not "
                         f"{list(commanded_A.shape)}")
    if not np.all(np.isfinite(applied)):
        g, i = (int(v[0]) for v in np.nonzero(~np.isfinite(applied)))
        raise PlantFault("not_finite", f"the plant carried {applied[g, i]} A on generator {g + 1} in step {i + 1}")
    return applied


def replay_score(result: FlightResult, recorder: FlightRecorder, plant) -> dict:
    """What the manager decided along a replayed log, scored (its decisions were not applied).

    Returns
    -------
    dict
        ``log``, ``decisions_applied`` (False), ``log_end_s``; ``first_replan_s`` (the manager's first
        re-plan, s, None if none), ``log_first_breach_s`` (first logged winding or iron above θmax, s),
        ``lead_s`` (breach less re-plan, s: how early the manager acted); ``commanded_rest_s`` (the rests
        it decided, s) and ``commanded_minus_logged_Ah`` per generator (the charge it would have moved).
    """
    system = result.system
    commanded = np.hstack(recorder.commanded) if recorder.commanded else np.zeros((system.n_generators, 0))
    dt = result.settings.dt_s
    over = np.flatnonzero(np.any(result.temperatures_C > system.limit_C, axis=(0, 1)))
    breach = float(result.time_s[over[0]]) if over.size else None
    replan = float(result.plans[0]["time_s"]) if result.plans else None
    return {"log": str(plant.path), "decisions_applied": False, "log_end_s": plant.end_s,
            "note": "the temperatures and currents are the log's; plans, rests and alarms are the manager's "
                    "decisions, recorded and not applied",
            "first_replan_s": replan, "log_first_breach_s": breach,
            "lead_s": None if breach is None or replan is None else breach - replan,
            "commanded_rest_s": float(np.count_nonzero(result.resting) * dt),
            "commanded_minus_logged_Ah": {name: float(np.sum(commanded[g] - result.currents_A[g]) * dt / 3600.0)
                                          for g, name in enumerate(system.generator_names)}}
