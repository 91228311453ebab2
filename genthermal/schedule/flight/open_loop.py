"""The open-loop plan of a mission (``genthermal plan``): planned once on the design model (or the
flown model), then flown by the same model, whose run is the plan's forecast and is judged by the
same test as every plan (:func:`~genthermal.schedule.planning.plan.within_limit`)."""

from __future__ import annotations

import numpy as np

from ...estimation.ekf import ExtendedKalmanFilter
from .flight_result import FlightRecorder, FlightResult
from ..planning.flown import FlownPlanning
from .manager_settings import ManagerSettings
from ..state_estimator import believed_model
from ..planning.optimal import lowest_reachable_peak
from ..planning.plan import Schedule, build_timeline, predict, remaining_after, within_limit
from ..power_system import PowerSystem
from .replanning import flight_segments, plan_with, planning_problem
from .role_settings import PlannerSettings


#: Plans made again with the held inlet raised to what the forecast read, when a load-following inlet
#: rise on a generator taking load made the forecast breach (:func:`plan_mission`).
MAX_INLET_REPLANS = 2


def told_beliefs(system: PowerSystem, t_s: float) -> list:
    """Per generator, the effects of the faults started by ``t_s`` (``--tell-fault``)."""
    known = system.faults_known_at(t_s)
    return [tuple((system.faults[i].effect, tuple(system.faults[i].values.items())) for i in known
                  if system.faults[i].generator == g and system.faults[i].effect) for g in range(system.n_generators)]


def _design_steps(system: PowerSystem, x0, timeline, t0: float, n: int, faults_at):
    """Run the design models for ``n`` steps of ``timeline`` from ``t0``; ``faults_at(t)`` gives the
    faults in force. Returns (outputs (n_gen, n_outputs, n), states after (n_gen, nx))."""
    outputs = np.empty((system.n_generators, len(system.planning_model.output_names), n))
    states = np.array(x0, dtype=float)
    for i in range(n):
        t = t0 + i * timeline.dt_s
        for g in range(system.n_generators):
            generator = system.design_generator(g, faults_at(t))
            E, G = generator.step(timeline.dt_s)
            u = generator.input(timeline.currents_A[g, i], float(system.inlet_C(g, t, timeline.currents_A[:, i])), system.mission.T_ambient_C)
            states[g] = E @ states[g] + G @ generator.forcing(u)
            outputs[g, :, i] = generator.outputs(states[g], u)
    return outputs, states


class FlownOpenLoop:
    """The open-loop plan's run on the flown model (nonlinear planner): per generator, the extended
    Kalman filter on the planning model with the faults known at a time, stepped with the
    disturbances at zero (no measurements: the filter's initial covariance is the uncertainty)."""

    def __init__(self, system: PowerSystem, dt_s: float):
        self.system, self.dt_s, self._filters = system, dt_s, {}

    def filter(self, g: int, t_s: float) -> ExtendedKalmanFilter:
        """Generator ``g``'s filter on the model with the faults started by ``t_s``."""
        beliefs = told_beliefs(self.system, t_s)[g]
        if beliefs not in self._filters:
            model = believed_model(self.system.planning_model, beliefs)
            # zero disturbances and the default covariance, even on a model that carries a
            # calibration's disturbance prior: this run has no measurements to start it from
            self._filters[beliefs] = ExtendedKalmanFilter(model, self.dt_s, disturbance_prior=None)
        return self._filters[beliefs]

    def steps(self, z0, timeline, t0: float, n: int):
        """Run ``n`` steps of ``timeline`` from filter states ``z0`` (n_gen, n_z). Returns
        (outputs (n_gen, n_outputs, n), states after (n_gen, n_z))."""
        system = self.system
        n_outputs = len(system.planning_model.output_names)
        outputs, states = np.empty((system.n_generators, n_outputs, n)), np.array(z0, dtype=float)
        for i in range(n):
            t = t0 + i * timeline.dt_s
            for g in range(system.n_generators):
                ekf = self.filter(g, t)
                u = system.design_generator(g).input(timeline.currents_A[g, i], float(system.inlet_C(g, t, timeline.currents_A[:, i])),
                                                     system.mission.T_ambient_C)
                states[g] = np.asarray(ekf.state_step(states[g], u)).ravel()
                outputs[g, :, i] = ekf.H @ states[g] + ekf.e
        return outputs, states


def highest_inlet_C(system: PowerSystem, t0_s: float, end_s: float, dt_s: float) -> np.ndarray:
    """Per generator, the highest coolant inlet temperature its faults reach from ``t0_s`` to
    ``end_s`` (s) on a grid of ``dt_s``, °C (n_generators,): the inlet the open-loop plan holds,
    every fault taken as known from the plan time whatever its onset (its effect is)."""
    times = np.arange(t0_s, max(end_s, t0_s) + dt_s, dt_s)
    return np.array([float(np.max(system.inlet_C(g, times))) for g in range(system.n_generators)])


def forecast_inlet_C(system: PowerSystem, timeline, t0_s: float) -> np.ndarray:
    """Per generator, the highest inlet temperature the forecast of ``timeline`` from ``t0_s`` reads
    (the currents flown, which a load-following rise follows), °C (n_generators,)."""
    times = t0_s + timeline.dt_s * np.arange(timeline.n_steps)
    return np.array([float(np.max(system.inlet_C(g, times, timeline.currents_A), initial=-np.inf))
                     for g in range(system.n_generators)])


def judge_forecast(recorder: FlightRecorder, t_plan: float, problem, forecast_C: np.ndarray,
                   settings: PlannerSettings, names) -> None:
    """The verdict on the plan's own forecast ``forecast_C`` (n_gen, 2, n) from ``t_plan`` (every fault at
    its onset): above the planning limit by more than the tolerance every plan is judged with, the plan is
    recorded infeasible (a record added when the nominal schedule was kept) with the lowest reachable peak
    of ``problem`` (at least the forecast's peak: that plan was reachable) and a warning naming the peak."""
    if forecast_C.size == 0:
        return
    peak = float(forecast_C.max())
    if within_limit(peak, problem.limit_C):
        return
    g, _, i = np.unravel_index(np.argmax(forecast_C), forecast_C.shape)
    at_s = t_plan + (i + 1) * settings.dt_s
    message = (f"infeasible: the plan's own forecast, every fault at its onset, reaches {peak:.1f} °C on {names[g]} at "
               f"{at_s / 60:.0f} min, above the planning limit {problem.limit_C:.1f} °C")
    if not recorder.plans or recorder.plans[-1]["time_s"] != t_plan:
        lowest = lowest_reachable_peak(problem, settings.optimal)
        recorder.plans.append({"time_s": t_plan, "method": "nominal", "solve_s": lowest.solve_s, "feasible": False,
                               "peak_C": peak, "lowest_peak_C": min(lowest.peak_C, peak),
                               "lowest_peak_generator": names[lowest.peak_generator]})
    record = recorder.plans[-1]
    if "lowest_peak_C" not in record:
        lowest = lowest_reachable_peak(problem, settings.optimal)
        record.update(lowest_peak_C=min(lowest.peak_C, peak), lowest_peak_generator=names[lowest.peak_generator])
        record["solve_s"] += lowest.solve_s
    record.update(feasible=False, forecast_peak_C=peak)
    recorder.warnings.append(message + f"; the lowest reachable peak is {record['lowest_peak_C']:.1f} °C")


def plan_mission(system: PowerSystem, scheduler: str, settings: ManagerSettings = ManagerSettings()) -> FlightResult:
    """Open-loop plan on the design model (or, with ``settings.planner_model`` ``nonlinear``, on
    the flown model, :class:`FlownOpenLoop`).

    The mission is flown as planned up to the first management cycle at or after the earliest
    fault onset; there every fault of the scenario is taken as known (conservative for later
    onsets: its effect, and the highest inlet temperature its rise reaches, :func:`highest_inlet_C`)
    and one plan is made for the rest of the mission, which the same model then flies with every
    fault at its onset. That run is the plan's forecast: when it breaches the planning limit the
    plan is infeasible (:func:`judge_forecast`), whatever the planner's own prediction said.

    Parameters
    ----------
    system : PowerSystem
        The generators, the mission and its faults (:meth:`PowerSystem.from_mission`).
    scheduler : {"heuristic", "engineer", "optimal", "milp"}
        Who plans: the thesis heuristic (Fig 7.2), the engineer's rule, the optimal scheduler
        (IPOPT) or the MILP (HiGHS).
    settings : ManagerSettings
        Management cycle, margin, rest budget, planner model and each scheduler's settings.

    Returns
    -------
    FlightResult
        The design-model (or flown-model) temperatures and currents of the plan, with its
        ``schedule_table``.
    """
    # no filter flies the open-loop plan: the scenario's filter is not its say
    say = {key: value for key, value in system.manager_say.items() if key != "filter"}
    roles = settings.roles(scheduler, system.mission.duration_s, say)
    loop, planner, frame = roles.loop, roles.planner, system.frame()
    settings = settings.for_flight(scheduler, settings.filter)  # planner_model "auto" resolved, as in roles
    dt = loop.dt_s
    segments = flight_segments(system.mission, planner, scheduler)
    schedule = Schedule.nominal(system.n_generators, len(segments))
    x = np.full((system.n_generators, system.nominal_model.n_states), system.mission.T_ambient_C)
    flown_run = FlownOpenLoop(system, dt) if planner.nonlinear else None
    if flown_run is not None:
        x = np.hstack([x, np.zeros((system.n_generators, len(flown_run.filter(0, 0.0).disturbance_names)))])
    budget = loop.rest_budget_s
    onset = min((f.onset_s for f in system.faults), default=0.0)
    t_plan = float(np.ceil(onset / loop.cycle_s - 1e-9) * loop.cycle_s)
    timeline = build_timeline(segments, schedule, system.rest_current_A, dt)
    n_before = min(int(round(t_plan / dt)), timeline.n_steps)
    recorder = FlightRecorder(frame)

    def run(x, timeline, t0, n, faults_at):
        if flown_run is None:
            return _design_steps(system, x, timeline, t0, n, faults_at)
        return flown_run.steps(x, timeline, t0, n)
    outputs, x = run(x, timeline, 0.0, n_before, system.faults_known_at)
    recorder.add(segments, timeline, n_before, outputs, 0.0)
    segments, schedule = remaining_after(segments, schedule, timeline, n_before)
    table = None
    if segments:
        all_faults = tuple(range(len(system.faults)))
        generators = [system.design_generator(g, all_faults) for g in range(system.n_generators)]
        flown = None
        if flown_run is not None:
            end = system.mission.duration_s
            filters = [flown_run.filter(g, end) for g in range(system.n_generators)]
            flown = FlownPlanning(filters, x, [f.P0 for f in filters], planner.confidence_sigmas)
        nodes = x[:, :system.nominal_model.n_states]
        coolant = system.planning_model.spec.interface.generator.coolant_input
        inlet = highest_inlet_C(system, t_plan, system.mission.duration_s + budget, dt)
        nominal, planned = schedule, None
        for _ in range(MAX_INLET_REPLANS + 1):
            problem = planning_problem(frame, planner, segments, nodes, t_plan, generators,
                                       np.floor(budget / dt + 1e-9) * dt, flown=flown, inputs_C={coolant: inlet[:, None]})
            schedule, planned = nominal, None
            if predict(problem, schedule).peak()[0] > problem.limit_C + loop.replan_tolerance_K:
                planned = plan_with(scheduler, problem, planner, system.generator_names, system.limit_C)
                schedule = planned.schedule.rounded(dt).within_rest_budget(problem.rest_budget_s)
            timeline = build_timeline(segments, schedule, system.rest_current_A, dt)
            outputs, x_end = run(x, timeline, t_plan, timeline.n_steps, system.faults_known_at)
            flown_inlet = forecast_inlet_C(system, timeline, t_plan)
            if within_limit(float(outputs.max(initial=-np.inf)), problem.limit_C) or np.all(flown_inlet <= inlet + 0.05):
                break
            inlet = np.maximum(inlet, flown_inlet)  # a load-following rise on a generator taking load: plan with it
        if planned is not None:
            recorder.plan(t_plan, planned)
        table = schedule.table(segments, system.generator_names)
        recorder.add(segments, timeline, timeline.n_steps, outputs, t_plan)
        judge_forecast(recorder, t_plan, problem, outputs, planner, system.generator_names)
    return FlightResult(system, scheduler, False, **recorder.record(), schedule_table=table, settings=settings,
                        rest_budget_s=budget)

