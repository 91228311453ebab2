"""The open-loop plan of a mission (``genthermal plan``): planned once on the design model (or the
flown model), then flown by the same model."""

from __future__ import annotations

import numpy as np

from ..estimation.ekf import ExtendedKalmanFilter
from .flight_result import FlightRecorder, FlightResult
from .flown import FlownPlanning
from .manager_settings import ManagerSettings, infeasible_response
from .state_estimator import believed_model
from .plan import Schedule, build_timeline, predict, remaining_after
from .power_system import PowerSystem
from .replanning import flight_segments, plan_with, planning_problem


def told_beliefs(system: PowerSystem, t_s: float) -> list:
    """Per generator, the effects of the faults started by ``t_s`` (``--tell-fault``)."""
    known = system.faults_known_at(t_s)
    return [tuple((system.faults[i].effect, tuple(system.faults[i].values.items())) for i in known
                  if system.faults[i].generator == g and system.faults[i].effect) for g in range(system.n_generators)]


def _design_steps(system: PowerSystem, x0, timeline, t0: float, n: int, faults_at):
    """Run the design models for ``n`` steps of ``timeline`` from ``t0``; ``faults_at(t)`` gives the
    faults in force. Returns (outputs (n_gen, 2, n), states after (n_gen, nx))."""
    outputs = np.empty((system.n_generators, 2, n))
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
        (outputs (n_gen, 2, n), states after (n_gen, n_z))."""
        system = self.system
        outputs, states = np.empty((system.n_generators, 2, n)), np.array(z0, dtype=float)
        for i in range(n):
            t = t0 + i * timeline.dt_s
            for g in range(system.n_generators):
                ekf = self.filter(g, t)
                u = system.design_generator(g).input(timeline.currents_A[g, i], float(system.inlet_C(g, t, timeline.currents_A[:, i])),
                                                     system.mission.T_ambient_C)
                states[g] = np.asarray(ekf.state_step(states[g], u)).ravel()
                outputs[g, :, i] = ekf.H @ states[g] + ekf.e
        return outputs, states


def plan_mission(system: PowerSystem, scheduler: str, settings: ManagerSettings = ManagerSettings()) -> FlightResult:
    """Open-loop plan on the design model (or, with ``settings.planner_model`` ``nonlinear``, on
    the flown model, :class:`FlownOpenLoop`).

    The mission is flown as planned up to the first management cycle at or after the earliest
    fault onset; there every fault of the scenario is taken as known (conservative for later
    onsets) and one plan is made for the rest of the mission, which the same model then flies.

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
    settings.check_scheduler(scheduler)
    dt = settings.dt_s
    segments = flight_segments(system, settings, scheduler)
    schedule = Schedule.nominal(system.n_generators, len(segments))
    x = np.full((system.n_generators, system.nominal_model.n_states), system.mission.T_ambient_C)
    flown_run = FlownOpenLoop(system, dt) if settings.nonlinear else None
    if flown_run is not None:
        x = np.hstack([x, np.zeros((system.n_generators, len(flown_run.filter(0, 0.0).disturbance_names)))])
    budget = settings.rest_budget_for(system.mission.duration_s)
    onset = min((f.onset_s for f in system.faults), default=0.0)
    t_plan = float(np.ceil(onset / settings.cycle_s - 1e-9) * settings.cycle_s)
    timeline = build_timeline(segments, schedule, system.rest_current_A, dt)
    n_before = min(int(round(t_plan / dt)), timeline.n_steps)
    recorder = FlightRecorder(system)

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
            flown = FlownPlanning(filters, x, [f.P0 for f in filters], settings.confidence_sigmas)
        nodes = x[:, :system.nominal_model.n_states]
        problem = planning_problem(system, settings, segments, nodes, t_plan, generators, np.floor(budget / dt + 1e-9) * dt,
                           flown=flown)
        if predict(problem, schedule).peak()[0] > problem.limit_C + settings.replan_tolerance_K:
            result = plan_with(scheduler, problem, settings, system.generator_names, system.limit_C,
                               when_infeasible=infeasible_response(system, settings))
            schedule = result.schedule.rounded(dt).within_rest_budget(problem.rest_budget_s)
            recorder.plan(t_plan, result)
        table = schedule.table(segments, system.generator_names)
        timeline = build_timeline(segments, schedule, system.rest_current_A, dt)
        outputs, x = run(x, timeline, t_plan, timeline.n_steps, system.faults_known_at)
        recorder.add(segments, timeline, timeline.n_steps, outputs, t_plan)
    return recorder.result(scheduler, False, table, rest_budget_s=budget)

