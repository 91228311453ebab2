r"""The load management system of thesis 7.2, open loop (``plan``) and closed loop (``fly``).

Closed loop, every ``cycle_s`` (thesis: 5 min):

1. **update** each generator's filter (default the extended Kalman filter on the flown nonlinear
   model, ``ManagerSettings.filter``) with the plant's noisy measurements of
   :math:`\theta_{winding}, \theta_{iron}` (noise variances of thesis eq. 6.10), predicting with the
   inlet and ambient temperatures as their sensors read them (a scenario's ``sensor_faults`` may
   make any of these sensors misread: :mod:`~genthermal.schedule.sensor_injection`; the sensor
   watches, :mod:`~genthermal.schedule.sensor_watch` and :mod:`~genthermal.schedule.input_watch`,
   claim and mask, correct or substitute them before the fault monitor sees the cycle); the planner gets
   its node temperatures (:func:`~genthermal.schedule.monitor.planner_state`) and the filter's
   disturbance heat flows (:func:`~genthermal.schedule.monitor.planning_generator`: offset-free
   predictions); the fault monitor
   (:mod:`genthermal.schedule.monitor`) tests the filters' disturbance heat flows and, on an
   alarm, identifies the fault from the in-flight record;
2. **predict** to the end of the mission under the current schedule, with the measured inlet
   temperature held (thesis 7.3.6) and the faults identified so far (with ``tell_fault``: the
   scenario's faults, each known at the first cycle after its onset): on the design model
   (``planner_model`` ``affine``), or on the filter's nonlinear model from its state with the
   disturbances held and a back-off of the filter's covariance propagated along the plan
   (``nonlinear``, :mod:`genthermal.schedule.flown`; the mission is then cut into control intervals
   of one cycle, each with its own displacement and rest);
3. **re-plan** (unless ``replan`` is off) if a temperature above the planning limit
   :math:`\theta_{max} - \text{margin}` is predicted, warm-started from the current plan;
4. **apply** the schedule to the true plant for one cycle.

The true plant is the nonlinear model with the faults from their onsets and parameters that differ
from the design model (``PowerSystem.plant_mismatch``). The back-off ``margin_K`` absorbs the
mismatch; its cost in mission time is measured by flying with and without it. The nonlinear planner
replaces it (and the rise back-off) by the back-off of the filter's uncertainty.

When no schedule keeps the prediction within the limit, the lowest reachable peak is found
(min-max), the scheduler plans within that peak (plus 0.1 K) instead and a warning names the peak,
the generator and the action. When that peak is above θmax itself, rest cannot help, and what the
manager does is ``when_infeasible`` (:data:`INFEASIBLE_RESPONSES`; the scenario's
``generators.when_infeasible`` or ``ManagerSettings.when_infeasible``):

* ``shed`` (default): the manager **sheds** load (:mod:`genthermal.schedule.shed`): each generator
  carries at most what keeps it within the planning limit, the others take what their limits
  allow, the rest is not served; a generator too hot even when carrying nothing is switched off
  for the rest of the mission;
* ``best_effort``: what the thesis heuristic does, which has no load shedding (thesis 7.2, Fig.
  7.2; its large blockage breaches 110.7 and 111 °C, 7.3.3): the scheduler's own plan is flown,
  all load served, knowing it breaches θmax by its predicted peak (the heuristic's, for a segment
  no rest makes feasible: the longest rest left and the largest displacement the receivers can
  take within θmax, so a healthy receiver is not planned past it; the optimal scheduler's: the
  heuristic's, :func:`~genthermal.schedule.optimal.optimal_plan`).

Either way the flight reports ``feasible: false`` (with ``shed``, also the load not served).

The total rest a flight adds is bounded by a **rest budget** (``ManagerSettings.rest_budget_s``,
default :data:`DEFAULT_REST_BUDGET_FRACTION` of the mission): every plan's rests are cut to what
is left of it, so a flight ends within its mission time plus the budget, after at most
``(mission + budget) / cycle_s + 1`` management cycles, whatever the plant does.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from ..errors import InputError
from ..estimation.ekf import ExtendedKalmanFilter
from ..simulate import simulate
from .flown import DEFAULT_CONFIDENCE_SIGMAS, FlownPlanning
from .engineer import EngineerSettings, engineer_plan
from .heuristic import HeuristicSettings, heuristic_plan
from .milp import MilpSettings, milp_plan
from .monitor import DetectionSettings, FaultMonitor, StateEstimator, believed_model, planning_generator
from .optimal import OptimalSettings, lowest_reachable_peak, optimal_plan
from .plan import (LIMIT_TOLERANCE_K, PlanningProblem, PlanResult, Schedule, build_timeline, evaluate,
                   generator_inputs, mission_segments, predict, remaining_after, split_segments)
from .power_system import PowerSystem
from .input_watch import InputWatch, InputWatchSettings
from .sensor_injection import SensorFaultInjector, parse_sensor_faults
from .sensor_watch import SensorWatch, SensorWatchSettings
from .optimal_nlp import flown_optimal_plan
from .shed import INFEASIBLE_RESPONSES, NOT_SERVED_TOLERANCE_A, shed_plan, unexplained_rise

SCHEDULERS = ("heuristic", "engineer", "optimal", "milp")
#: Models the schedulers may plan on (``ManagerSettings.planner_model``): ``affine``, the design
#: model with the margin and the rise back-off; ``nonlinear``, the flown model the filter runs
#: on, with the back-off of its covariance (:mod:`genthermal.schedule.flown`), the mission cut
#: into control intervals of one cycle.
PLANNER_MODELS = ("affine", "nonlinear")
#: Default back-off margin below θmax, K.
DEFAULT_MARGIN_K = 2.5
#: Default rise back-off: plans tolerate a design model that underestimates a temperature rise
#: within one cycle by this fraction (the thesis generator's copper loss at rated current and its winding limit is ~20 % above the
#: linear design model's).
DEFAULT_RISE_BACKOFF = 0.3
#: Default rest budget of a flight, as a fraction of the nominal mission duration. Choice of this
#: project, not a thesis value: the thesis's longest managed rest is 20 min (rig, large blockage,
#: 7.3.3) on a 4-h mission (8 %); a quarter of the mission (60 min on 4 h, the longest rest the
#: schedulers take before one action) leaves room for that three times over and bounds a flight at
#: 1.25 times its nominal duration.
DEFAULT_REST_BUDGET_FRACTION = 0.25


@dataclasses.dataclass(frozen=True)
class ManagerSettings:
    """Settings of the load management system.

    Attributes
    ----------
    cycle_s : float
        Management cycle, s (thesis 7.2: 5 min).
    dt_s : float
        Plant and design-model step, s.
    margin_K : float
        Back-off margin: the schedulers plan to :math:`\\theta_{max}` − margin, K. A scenario that
        gives ``generators.margin_K`` (``PowerSystem.margin_K``) flies with that instead
        (:func:`planning_margin_K`).
    rise_backoff : float
        :math:`\\kappa` of the robust constraint on temperature rises within one cycle (see
        :class:`~genthermal.schedule.plan.PlanningProblem`).
    max_rest_s : float
        Longest rest before one segment, s.
    rest_budget_s : float or None
        Most rest a whole flight may add, s; None (default): :data:`DEFAULT_REST_BUDGET_FRACTION`
        of the mission's nominal duration (:meth:`rest_budget_for`). When it is spent, a plan that
        needs more rest is flown without it, or the generator is shed.
    replan_tolerance_K : float
        A prediction above the planning limit by more than this triggers a re-plan, K.
    seed : int
        Seed of the measurement noise.
    tell_fault : bool
        Hand the manager every fault's effect and parameters from the first cycle after its onset
        (the comparison case); default False: the manager detects and identifies faults itself
        (:mod:`genthermal.schedule.monitor`).
    replan : bool
        Re-plan when the prediction crosses the planning limit (default); False flies the nominal
        schedule whatever is predicted, which isolates the filter and the fault detector from the
        scheduler (detection benchmarks).
    filter : str
        Filter in the loop, a key of :data:`genthermal.schedule.monitor.FLIGHT_FILTERS`: ``"ekf"``
        (default, the extended Kalman filter on the flown nonlinear model) or ``"kf"`` (the
        thesis linear filter on the design model).
    detection : DetectionSettings
        Fault detection and identification in flight.
    sensor_watch : SensorWatchSettings
        Sensor-fault detection and masking in flight (:mod:`genthermal.schedule.sensor_watch`).
    input_watch : InputWatchSettings
        Inlet and ambient sensor faults in flight (:mod:`genthermal.schedule.input_watch`).
    planner_model : str
        One of :data:`PLANNER_MODELS`: ``affine`` (default) plans on the design model within θmax −
        ``margin_K`` with the rise back-off; ``nonlinear`` plans on the flown model (the filter's,
        ``filter`` must be ``ekf``) within θmax with the back-off of the filter's covariance
        (``confidence_sigmas`` standard deviations; ``margin_K`` and ``rise_backoff`` unused), and
        displacement and rest free per management cycle.
    confidence_sigmas : float
        Standard deviations of the predicted temperature kept below θmax by the nonlinear planner.
    heuristic, engineer, optimal, milp
        Settings of each scheduler.
    cpu_limit_s : float or None
        Processor time a flight may take, s (of this process: other load on the machine does not
        count against it); checked at every management cycle, a flight past it raises
        :class:`FlightTimeout` (a robustness sweep records it as such instead of waiting on it).
        None (default): no limit.
    when_infeasible : str
        One of :data:`INFEASIBLE_RESPONSES`: what the manager does when even the lowest reachable
        peak is above θmax; ``shed`` (default) sheds load, ``best_effort`` flies the scheduler's
        own plan with all load served, breaching θmax as predicted (the thesis heuristic). A
        scenario that gives ``generators.when_infeasible`` flies with that instead
        (:func:`infeasible_response`).
    """

    cycle_s: float = 300.0
    dt_s: float = 10.0
    margin_K: float = DEFAULT_MARGIN_K
    rise_backoff: float = DEFAULT_RISE_BACKOFF
    max_rest_s: float = 3600.0
    rest_budget_s: float | None = None
    replan_tolerance_K: float = 0.05
    seed: int = 0
    tell_fault: bool = False
    replan: bool = True
    filter: str = "ekf"
    planner_model: str = "affine"
    confidence_sigmas: float = DEFAULT_CONFIDENCE_SIGMAS
    detection: DetectionSettings = DetectionSettings()
    sensor_watch: SensorWatchSettings = SensorWatchSettings()
    input_watch: InputWatchSettings = InputWatchSettings()
    heuristic: HeuristicSettings = HeuristicSettings()
    engineer: EngineerSettings = EngineerSettings()
    optimal: OptimalSettings = OptimalSettings()
    milp: MilpSettings = MilpSettings()
    cpu_limit_s: float | None = None
    when_infeasible: str = "shed"

    def __post_init__(self):
        if self.when_infeasible not in INFEASIBLE_RESPONSES:
            raise InputError("when_infeasible", self.when_infeasible,
                             f"must be one of {', '.join(INFEASIBLE_RESPONSES)}")
        if self.rest_budget_s is not None and not (np.isfinite(self.rest_budget_s) and self.rest_budget_s >= 0):
            raise ValueError(f"rest_budget_s = {self.rest_budget_s!r}: must be a number of seconds >= 0 or None")
        if self.cpu_limit_s is not None and not (np.isfinite(self.cpu_limit_s) and self.cpu_limit_s > 0):
            raise ValueError(f"cpu_limit_s = {self.cpu_limit_s!r}: must be a number of seconds > 0 or None")
        if self.planner_model not in PLANNER_MODELS:
            raise InputError("planner_model", self.planner_model, f"must be one of {', '.join(PLANNER_MODELS)}")
        if self.planner_model == "nonlinear" and self.filter != "ekf":
            raise InputError("filter", self.filter, "the nonlinear planner plans on the extended Kalman filter's "
                             "model and covariance: use the filter ekf")
        if not (np.isfinite(self.confidence_sigmas) and self.confidence_sigmas >= 0):
            raise InputError("confidence_sigmas", self.confidence_sigmas,
                             "must be a number of standard deviations >= 0")

    @property
    def nonlinear(self) -> bool:
        """True when planning on the flown (nonlinear) model."""
        return self.planner_model == "nonlinear"

    def rest_budget_for(self, mission_duration_s: float) -> float:
        """The flight's rest budget, s, for a mission of ``mission_duration_s`` (s)."""
        if self.rest_budget_s is not None:
            return float(self.rest_budget_s)
        return DEFAULT_REST_BUDGET_FRACTION * float(mission_duration_s)


class FlightTimeout(RuntimeError):
    """A closed-loop flight took more than ``ManagerSettings.cpu_limit_s`` of processor time.

    Attributes
    ----------
    mission_time_s : float
        Mission time flown when it was stopped, s.
    cycles : int
        Management cycles flown.
    cpu_s : float
        Processor time spent, s.
    """

    def __init__(self, mission_time_s: float, cycles: int, cpu_s: float, limit_s: float):
        self.mission_time_s, self.cycles, self.cpu_s = float(mission_time_s), int(cycles), float(cpu_s)
        super().__init__(f"flight stopped after {cpu_s:.0f} s of processor time (limit {limit_s:g} s), "
                         f"{cycles} management cycles, at mission time {mission_time_s:.0f} s")


@dataclasses.dataclass
class FlightResult:
    """What was flown: per step (``dt_s``) the applied currents and the temperatures.

    Attributes
    ----------
    system : PowerSystem
    scheduler : str
    closed_loop : bool
        True: true plant under the closed loop; False: design-model run of an open-loop plan.
    time_s : numpy.ndarray
        (n + 1,) s.
    temperatures_C : numpy.ndarray
        (n_generators, 2, n + 1) winding and iron, °C.
    currents_A : numpy.ndarray
        (n_generators, n) applied phase currents, A RMS.
    nominal_A : numpy.ndarray
        (n,) nominal current of the action flown (rest mode current during rests), A.
    resting : numpy.ndarray
        (n,) True during rests.
    action_index : numpy.ndarray
        (n,) index of the mission action being flown or rested before.
    plans : list of dict
        One record per (re-)plan: ``time_s``, ``method``, ``solve_s``, ``feasible``, ``peak_C``,
        ``believed`` (the effects the plan was made with, per generator).
    warnings : list of str
    schedule_table : pandas.DataFrame or None
        The open-loop plan per action.
    monitor : FaultMonitor or None
        Alarms, identifications and recalibrations of the flight (closed loop).
    settings : ManagerSettings or None
    cycles : int
        Management cycles flown (closed loop; 0 for a plan).
    rest_budget_s : float
        The flight's rest budget, s.
    shed_events : list of dict
        One when the manager starts shedding load and one per generator switched off: ``time_s``,
        ``shedding`` (names), ``switched_off`` (names switched off then),
        ``lowest_reachable_peak_C``, ``lowest_peak_action``, ``response``.
    sensor_watch : SensorWatch or None
        Sensor faults injected, claimed and masked (closed loop).
    """

    system: PowerSystem
    scheduler: str
    closed_loop: bool
    time_s: np.ndarray
    temperatures_C: np.ndarray
    currents_A: np.ndarray
    nominal_A: np.ndarray
    resting: np.ndarray
    action_index: np.ndarray
    plans: list
    warnings: list
    schedule_table: object = None
    monitor: object = None
    settings: object = None
    cycles: int = 0
    rest_budget_s: float = np.inf
    shed_events: list = dataclasses.field(default_factory=list)
    sensor_watch: object = None


def flight_filter(system: PowerSystem, settings: ManagerSettings) -> str:
    """The filter a flight runs: the scenario's (``generators.filter``, e.g. the thesis's linear
    filter in the thesis-reproduction scenarios) when it names one, else ``settings.filter``."""
    return settings.filter if system.filter is None else system.filter


def planning_margin_K(system: PowerSystem, settings: ManagerSettings) -> float:
    """The back-off margin a flight plans with, K: the scenario's (``generators.margin_K``, e.g. 0 in
    the thesis-reproduction scenarios, whose heuristic checks θmax itself) when it gives one, else
    ``settings.margin_K``."""
    return settings.margin_K if system.margin_K is None else float(system.margin_K)


def infeasible_response(system: PowerSystem, settings: ManagerSettings) -> str:
    """What a flight does when even the lowest reachable peak is above θmax, one of
    :data:`INFEASIBLE_RESPONSES`: the scenario's (``generators.when_infeasible``, e.g.
    ``best_effort`` in the thesis-reproduction scenarios, whose heuristic has no load shedding)
    when it gives one, else ``settings.when_infeasible``."""
    return settings.when_infeasible if system.when_infeasible is None else system.when_infeasible


def plan_with(scheduler: str, problem: PlanningProblem, settings: ManagerSettings, names, limit_C: float,
              previous=None, switched_off=None, when_infeasible: str | None = None,
              shedding: bool = False) -> PlanResult:
    """Run ``scheduler`` on ``problem``; when infeasible, plan within the lowest reachable peak or shed.

    Parameters
    ----------
    scheduler : {"heuristic", "engineer", "optimal", "milp"}
    problem : PlanningProblem
        Its ``limit_C`` is the planning limit (θmax minus the margin); its ``rest_budget_s`` bounds
        the total rest of the plan (rests beyond it are cut, earliest kept).
    settings : ManagerSettings
    names : sequence of str
        Generator names, for the messages.
    limit_C : float
        θmax, °C.
    previous : Schedule, optional
        Warm start of the optimal scheduler.
    switched_off : array-like of bool, optional
        (n_generators,) generators already switched off: the plan is :func:`~.shed.shed_plan`.
    when_infeasible : str, optional
        One of :data:`INFEASIBLE_RESPONSES`, what to do when the lowest reachable peak is above
        θmax; None (default): ``settings.when_infeasible``.
    shedding : bool
        The manager sheds load now (its last plan did). It goes back to plans without shedding
        only once one keeps the planning limit: while the lowest reachable peak is above it, it
        keeps shedding rather than fly a schedule that uses up the margin (hysteresis). Measured
        on the robustness grid's case 15 (a k_flow 0.23 blockage on gen2 of 3): the lowest-peak
        schedules flown after the shedding, 0.2-0.6 K into the margin, moved gen2's landing load onto
        the healthy generators, which the plant's 25 % weaker cooling took to 110.5 °C (20 s
        above θmax).

    Returns
    -------
    PlanResult
        ``feasible`` is True only when the plan's own prediction, with its back-off (the margin and
        the rise back-off), stays within the planning limit. Otherwise ``details`` hold the lowest
        reachable peak (``lowest_peak_C``, its generator and action), the peak of the plan flown
        (``planned_peak_C``) and what the manager does about it (``response``); when that peak is
        above θmax and ``when_infeasible`` is ``shed``, the plan sheds load (``method`` ``shed``;
        ``shedding``: the generators whose load is shed, ``switched_off``: the generators off); with
        ``best_effort`` it is the scheduler's own plan, all load served (``best_effort`` True in
        ``details``).
    """
    response_mode = settings.when_infeasible if when_infeasible is None else when_infeasible
    if response_mode not in INFEASIBLE_RESPONSES:
        raise InputError("when_infeasible", response_mode, f"must be one of {', '.join(INFEASIBLE_RESPONSES)}")
    if switched_off is not None and np.any(switched_off):
        off = np.array(switched_off, dtype=bool)
        return _shed(problem, off, off, names, limit_C, "", settings.margin_K)

    def run(p, initial=previous):
        if scheduler == "heuristic":
            return heuristic_plan(p, settings.heuristic)
        if scheduler == "engineer":
            return engineer_plan(p, settings.engineer)
        if scheduler == "optimal":
            return optimal_plan(p, settings.optimal, initial)
        return milp_plan(p, settings.milp)
    result = _within_budget(problem, run(problem))
    if result.feasible:
        return result
    lowest = _within_budget(problem, lowest_reachable_peak(problem, settings.optimal))
    segment = problem.segments[lowest.peak_segment]
    where = (f"the lowest reachable peak is {lowest.peak_C:.1f} °C, on {names[lowest.peak_generator]} during "
             f"action {segment.action_index + 1} ({segment.label})")
    found = dict(lowest_peak_C=lowest.peak_C, lowest_peak_generator=names[lowest.peak_generator],
                 lowest_peak_action=segment.action_index + 1)
    keep_shedding = shedding and lowest.peak_C > problem.limit_C + LIMIT_TOLERANCE_K
    if (lowest.peak_C > limit_C or keep_shedding) and response_mode == "shed":
        nobody = np.zeros(problem.n_generators, dtype=bool)
        if lowest.peak_C <= limit_C:
            where += (f", within θmax {limit_C:g} °C: the manager, shedding, keeps shedding until a plan keeps "
                      "the margin")
        if problem.flown is not None:  # shed as little load as keeps θmax on the flown model
            shed = _flown_shed(problem, settings, previous, names, limit_C, where)
            if shed is not None:
                shed.solve_s += result.solve_s + lowest.solve_s
                shed.details.update(found)
                return shed
        shed = _shed(problem, nobody, nobody, names, limit_C, where, settings.margin_K,
                     within_margin=lowest.peak_C <= limit_C)
        shed.solve_s += result.solve_s + lowest.solve_s
        shed.details.update(found)
        return shed
    if lowest.peak_C > limit_C:  # best effort: the scheduler's own plan, all load served
        best = _best_effort(problem, result, names, limit_C, where, found)
        best.solve_s += lowest.solve_s
        return best
    within_lowest = dataclasses.replace(problem, limit_C=max(lowest.peak_C, problem.limit_C) + 0.1)
    relaxed = _within_budget(problem, run(within_lowest, lowest.schedule))  # the min-max schedule is feasible there
    if relaxed.peak_C > lowest.peak_C + 0.1:  # the scheduler does worse than the min-max schedule: fly that
        relaxed = dataclasses.replace(lowest, method=f"{result.method} (lowest peak)", warnings=list(relaxed.warnings))
    response = (f"flying the lowest-peak schedule: rest {relaxed.schedule.added_rest_s / 60:.1f} min, move "
                f"{relaxed.schedule.displaced_Ah(problem.segments):.2f} A·h to the other generators")
    if relaxed.peak_C > limit_C:
        message = f"infeasible: no schedule keeps θ ≤ {limit_C:g} °C; {where}; {response}"
    else:
        message = (f"margin not kept: no schedule stays within the planning limit {problem.limit_C:.1f} °C; "
                   f"{where}, within θmax {limit_C:g} °C; {response}")
    relaxed.feasible = False
    relaxed.solve_s += result.solve_s + lowest.solve_s
    relaxed.warnings.append(message)
    relaxed.details.update(found, planned_peak_C=relaxed.peak_C, response=response)
    return relaxed


def _best_effort(problem: PlanningProblem, result: PlanResult, names, limit_C: float, where: str,
                 found: dict) -> PlanResult:
    """The scheduler's own plan ``result`` flown although it breaches θmax (``when_infeasible``
    ``best_effort``): every load served, the breach predicted and reported; ``details`` carry
    ``best_effort`` True and the plan's predicted peak."""
    rested = result.schedule.added_rest_s / 60.0
    moved_Ah = result.schedule.displaced_Ah(problem.segments)
    response = (f"best effort, no load shed: rest {rested:.1f} min, move {moved_Ah:.2f} "
                f"A·h to the other generators; predicted peak {result.peak_C:.1f} °C on {names[result.peak_generator]}, "
                f"{result.peak_C - limit_C:.1f} K above θmax {limit_C:g} °C")
    result.feasible = False
    result.warnings.append(f"infeasible: no schedule keeps θ ≤ {limit_C:g} °C; {where}; {response}")
    result.details.update(found, planned_peak_C=result.peak_C, response=response, best_effort=True)
    return result


def _flown_shed(problem: PlanningProblem, settings: ManagerSettings, previous, names, limit_C: float,
                where: str) -> PlanResult | None:
    """The optimal scheduler on the flown model with load allowed to go unserved
    (:func:`~genthermal.schedule.optimal_nlp.flown_optimal_plan`, ``shed``); None when even that
    does not keep its prediction within θmax (the caller switches generators off)."""
    result = flown_optimal_plan(problem, settings.optimal.nonlinear, previous, shed=True)
    if not result.feasible:  # its own prediction, with its back-off, above θmax
        return None
    result = _within_budget(problem, result)
    not_served = result.schedule.displaced_A.sum(axis=0)
    short = not_served > NOT_SERVED_TOLERANCE_A
    shedding = [names[g] for g in range(problem.n_generators)
                if np.any((result.schedule.displaced_A[g] > NOT_SERVED_TOLERANCE_A) & short)]
    durations = np.array([s.duration_s for s in problem.segments])
    not_served_Ah = float(np.sum(np.clip(not_served, 0.0, None) * durations) / 3600.0)
    response = (f"shed load of {', '.join(shedding) or 'nobody'}: {not_served_Ah:.2f} A·h not served, the least "
                f"that keeps every generator within θmax {limit_C:g} °C on the flown model with its back-off, after rest "
                f"{result.schedule.added_rest_s / 60:.1f} min and displacement")
    result.method, result.feasible = "shed", False
    result.warnings.append(f"infeasible: no schedule keeps θ ≤ {limit_C:g} °C; {where}; {response}")
    result.details.update(response=response, planned_peak_C=result.peak_C, shedding=shedding, switched_off=[])
    return result


def _within_budget(problem: PlanningProblem, result: PlanResult) -> PlanResult:
    """``result`` with its rests cut to ``problem.rest_budget_s`` and the rest before the first
    segment to ``max_rest_s`` minus the rest already taken before it; re-evaluated when cut."""
    schedule = result.schedule.within_rest_budget(problem.rest_budget_s, _first_rest_max_s(problem))
    if np.allclose(schedule.rest_before_s, result.schedule.rest_before_s, rtol=0.0, atol=1e-6):
        return result
    cut = evaluate(problem, schedule, result.method, result.solve_s, result.warnings)
    cut.feasible = cut.feasible and result.feasible
    cut.details = dict(result.details, rest_cut_to_budget_s=problem.rest_budget_s)
    cut.warnings.append(f"rests cut to the {problem.rest_budget_s / 60:.1f} min left of the flight's rest budget "
                        f"and {problem.max_rest_s / 60:g} min before one action")
    return cut


def _first_rest_max_s(problem: PlanningProblem) -> float:
    """Rest still allowed before the first segment, s."""
    return max(problem.max_rest_s - problem.rest_taken_s, 0.0)


def _shed(problem: PlanningProblem, already: np.ndarray, off: np.ndarray, names, limit_C: float,
          where: str, receiver_margin_K: float, within_margin: bool = False) -> PlanResult:
    """Shed load with ``off`` switched off (``already`` were off before) and, while the plan still
    breaches θmax on a generator still on, switch that one off too; the
    :func:`~.shed.shed_plan` result (receivers within ``receiver_margin_K`` more), never
    ``feasible``. ``within_margin``: θmax can be kept but the planning limit cannot (the messages
    say so)."""
    off = off.copy()
    result = shed_plan(problem, off, receiver_margin_K)
    # a receiver filled to the planning limit sits on it to rounding: with no margin that limit is
    # θmax, and a strict comparison switched the healthy receiver off for a 3e-14 K excess
    while result.peak_C > limit_C + LIMIT_TOLERANCE_K and not off[result.peak_generator]:
        off[result.peak_generator] = True
        result = shed_plan(problem, off, receiver_margin_K)
    newly = [names[g] for g in np.flatnonzero(off & ~already)]
    shedding = [names[g] for g in result.details["shedding"]]
    if where:
        bound = f"the planning limit {problem.limit_C:.1f} °C" if within_margin else f"θmax {limit_C:g} °C"
        response = (f"shed load of {', '.join(shedding) or 'nobody'}: no rest within the rest budget and no "
                    f"displacement keeps it within {bound}; each generator carries at most what keeps "
                    "it within the planning limit, the others take what their limits allow, the rest is not served"
                    + (f"; switch off {', '.join(newly)} (too hot even carrying nothing)" if newly else ""))
        headline = (f"margin not kept: no schedule stays within the planning limit {problem.limit_C:.1f} °C"
                    if within_margin else f"infeasible: no schedule keeps θ ≤ {limit_C:g} °C")
        result.warnings.append(f"{headline}; {where}; {response}")
        result.details.update(response=response)
    elif newly:
        response = f"switch off {', '.join(newly)} (too hot even carrying nothing)"
        result.warnings.append(f"shed: {response}")
        result.details.update(response=response)
    result.feasible = False
    result.details.update(planned_peak_C=result.peak_C, shedding=shedding,
                          switched_off=[names[g] for g in np.flatnonzero(off)])
    return result


def _problem(system: PowerSystem, settings: ManagerSettings, segments, x0, t_s: float, generators,
             rest_budget_s: float, rest_taken_s: float = 0.0, flown: FlownPlanning | None = None,
             inputs_C: dict | None = None, unexplained_rise_K=None) -> PlanningProblem:
    """The planning problem at ``t_s`` with ``rest_budget_s`` (s) of rest left to the flight and
    ``rest_taken_s`` (s) of rest already flown right before the first segment; with ``flown`` (the
    nonlinear planner) the limit is θmax itself and the back-off that of the filters' covariance.
    ``inputs_C`` (input name → (n_gen, 1) readings at ``t_s``, °C): the measured inlet of each
    generator and the median measured ambient, held over the plan (default the mission's);
    ``unexplained_rise_K`` (n_generators, n_outputs), K: the last cycle's rise the filters did not
    explain (``PlanningProblem.unexplained_rise_K``)."""
    generator = system.planning_model.spec.interface.generator
    inputs_C = inputs_C or {}
    inlet = np.array([float(inputs_C[generator.coolant_input][g, 0]) if generator.coolant_input in inputs_C
                      else float(system.inlet_C(g, t_s)) for g in range(system.n_generators)])
    ambient = float(np.median(inputs_C[generator.ambient_input][:, 0])) if generator.ambient_input in inputs_C \
        else system.mission.T_ambient_C
    budget = max(float(rest_budget_s), 0.0)
    limit, rise_backoff = (system.limit_C, 0.0) if flown is not None else \
        (system.limit_C - planning_margin_K(system, settings), settings.rise_backoff)
    return PlanningProblem(tuple(segments), generators, np.asarray(x0, dtype=float), inlet,
                           ambient, system.rest_current_A, system.current_limit_A,
                           limit, min(settings.max_rest_s, budget), settings.dt_s,
                           rise_backoff, settings.cycle_s, budget, float(rest_taken_s), flown,
                           None if unexplained_rise_K is None else np.asarray(unexplained_rise_K, dtype=float))


def _segments(system: PowerSystem, settings: ManagerSettings) -> tuple:
    """The mission's segments; for the nonlinear planner cut into control intervals of one cycle."""
    segments = mission_segments(system.mission)
    return split_segments(segments, settings.cycle_s) if settings.nonlinear else segments


class TrustedHeatFlows:
    """The disturbance heat flows each generator's plan may carry (offset-free planning).

    While the sensor watch trusts a generator's heat flows (:meth:`SensorWatch.trusts_heat_flows
    <genthermal.schedule.sensor_watch.SensorWatch.trusts_heat_flows>`), the plan takes the
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


class _Recorder:
    """Collects the steps flown, from a cold machine (every node at the ambient temperature)."""

    def __init__(self, system: PowerSystem):
        self.system, self.time = system, [0.0]
        self.temperatures = [np.full((system.n_generators, 2), system.mission.T_ambient_C)]
        self.currents, self.nominal, self.resting, self.action = [], [], [], []
        self.plans, self.warnings, self.shed_events = [], [], []
        self.switched_off = np.zeros(system.n_generators, dtype=bool)

    def plan(self, t_s: float, result: PlanResult, believed=None) -> None:
        """Record a (re-)plan made at ``t_s`` with the ``believed`` effects per generator."""
        record = {"time_s": t_s, "method": result.method, "solve_s": result.solve_s,
                  "feasible": result.feasible, "peak_C": result.peak_C, **result.details}
        if believed is not None:
            record["believed"] = {name: [{"effect": e, "parameters": dict(v)} for e, v in effects]
                                  for name, effects in zip(self.system.generator_names, believed)}
        self.plans.append(record)
        self.warnings += result.warnings
        newly = result.schedule.switched_off & ~self.switched_off
        starts = result.method == "shed" and (not self.plans[:-1] or self.plans[-2]["method"] != "shed")
        if starts or newly.any():
            self.shed_events.append({"time_s": float(t_s), "shedding": list(result.details.get("shedding", [])),
                                     "switched_off": [self.system.generator_names[g] for g in np.flatnonzero(newly)],
                                     "lowest_reachable_peak_C": result.details.get("lowest_peak_C"),
                                     "lowest_peak_action": result.details.get("lowest_peak_action"),
                                     "response": result.details.get("response", "")})
        self.switched_off |= result.schedule.switched_off

    def add(self, segments, timeline, n: int, outputs, t0: float) -> None:
        """Record ``n`` steps of ``timeline`` and the ``outputs`` (n_gen, 2, n) after each."""
        dt = timeline.dt_s
        self.time += list(t0 + dt * np.arange(1, n + 1))
        self.temperatures += list(np.moveaxis(outputs, 2, 0))
        self.currents.append(timeline.currents_A[:, :n])
        self.resting.append(timeline.resting[:n])
        self.action.append(np.array([segments[k].action_index for k in timeline.segment[:n]]))
        nominal = [self.system.rest_current_A if timeline.resting[i] else
                   float(segments[timeline.segment[i]].current_at(timeline.offset_s[i])) for i in range(n)]
        self.nominal.append(np.array(nominal))

    def result(self, scheduler, closed_loop, table=None, monitor=None, settings=None, cycles=0,
               rest_budget_s=np.inf) -> FlightResult:
        """The :class:`FlightResult`."""
        return FlightResult(self.system, scheduler, closed_loop, np.array(self.time),
                            np.moveaxis(np.array(self.temperatures), 0, 2), np.hstack(self.currents),
                            np.concatenate(self.nominal), np.concatenate(self.resting),
                            np.concatenate(self.action), self.plans, self.warnings, table,
                            monitor, settings, cycles, rest_budget_s, self.shed_events)


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
            u = generator.input(timeline.currents_A[g, i], float(system.inlet_C(g, t)), system.mission.T_ambient_C)
            states[g] = E @ states[g] + G @ generator.forcing(u)
            outputs[g, :, i] = generator.outputs(states[g], u)
    return outputs, states


class _FlownOpenLoop:
    """The open-loop plan's run on the flown model (nonlinear planner): per generator, the extended
    Kalman filter on the planning model with the faults known at a time, stepped with the
    disturbances at zero (no measurements: the filter's initial covariance is the uncertainty)."""

    def __init__(self, system: PowerSystem, dt_s: float):
        self.system, self.dt_s, self._filters = system, dt_s, {}

    def filter(self, g: int, t_s: float) -> ExtendedKalmanFilter:
        """Generator ``g``'s filter on the model with the faults started by ``t_s``."""
        beliefs = _told_beliefs(self.system, t_s)[g]
        if beliefs not in self._filters:
            model = believed_model(self.system.planning_model, beliefs)
            self._filters[beliefs] = ExtendedKalmanFilter(model, self.dt_s)
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
                u = system.design_generator(g).input(timeline.currents_A[g, i], float(system.inlet_C(g, t)),
                                                     system.mission.T_ambient_C)
                states[g] = np.asarray(ekf.state_step(states[g], u)).ravel()
                outputs[g, :, i] = ekf.H @ states[g] + ekf.e
        return outputs, states


def plan_mission(system: PowerSystem, scheduler: str, settings: ManagerSettings = ManagerSettings()) -> FlightResult:
    """Open-loop plan on the design model (or, with ``settings.planner_model`` ``nonlinear``, on
    the flown model, :class:`_FlownOpenLoop`).

    The mission is flown as planned up to the first management cycle at or after the earliest
    fault onset; there every fault of the scenario is taken as known (conservative for later
    onsets) and one plan is made for the rest of the mission, which the same model then flies.
    """
    dt = settings.dt_s
    segments = _segments(system, settings)
    schedule = Schedule.nominal(system.n_generators, len(segments))
    x = np.full((system.n_generators, system.nominal_model.n_states), system.mission.T_ambient_C)
    flown_run = _FlownOpenLoop(system, dt) if settings.nonlinear else None
    if flown_run is not None:
        x = np.hstack([x, np.zeros((system.n_generators, len(flown_run.filter(0, 0.0).disturbance_names)))])
    budget = settings.rest_budget_for(system.mission.duration_s)
    onset = min((f.onset_s for f in system.faults), default=0.0)
    t_plan = float(np.ceil(onset / settings.cycle_s - 1e-9) * settings.cycle_s)
    timeline = build_timeline(segments, schedule, system.rest_current_A, dt)
    n_before = min(int(round(t_plan / dt)), timeline.n_steps)
    recorder = _Recorder(system)

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
        problem = _problem(system, settings, segments, nodes, t_plan, generators, np.floor(budget / dt + 1e-9) * dt,
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


def _plant_steps(system: PowerSystem, g: int, x0, timeline, t0: float):
    """Run generator ``g``'s true plant over ``timeline`` from ``t0`` (faults switch in at their
    onsets). Returns (outputs (2, n) after each step, state at the end)."""
    n = timeline.n_steps
    model = system.plant_model(g, system.faults_known_at(t0))
    _, switches = system.plant_switches(g)
    later = [(onset, m) for onset, m in switches if t0 < onset < t0 + n * timeline.dt_s]
    frame = generator_inputs(timeline, g, t0, lambda t: system.inlet_C(g, t), system.mission.T_ambient_C,
                             system.mission.power_factor, system.rated_current_A,
                             model.spec.interface.generator)
    run = simulate(model, frame, x0=x0, switches=later)
    states = run[[f"T_{name}" for name in model.state_names]].to_numpy()
    return run[list(model.output_names)].to_numpy()[1:].T, states[-1]


def true_inputs(system: PowerSystem, input_names, times) -> dict:
    """The true values of the measured inputs ``input_names`` (coolant inlet, ambient) of every
    generator at ``times`` (s): input name → (n_gen, n) °C."""
    generator = system.planning_model.spec.interface.generator
    times = np.asarray(times, dtype=float)
    values = {generator.coolant_input: np.array([system.inlet_C(g, times) for g in range(system.n_generators)]),
              generator.ambient_input: np.full((system.n_generators, times.size), system.mission.T_ambient_C)}
    return {name: values[name] for name in input_names if name in values}


def _filter_inputs(system: PowerSystem, inputs_C: dict, times) -> tuple:
    """Per generator, the inlet (n,) and ambient (n,) temperatures its filter is driven with, °C: the
    readings in ``inputs_C`` (:func:`true_inputs` keys), the true values for an input not read."""
    generator = system.planning_model.spec.interface.generator
    true = true_inputs(system, (generator.coolant_input, generator.ambient_input), times)
    inlet = inputs_C.get(generator.coolant_input, true[generator.coolant_input])
    ambient = inputs_C.get(generator.ambient_input, true[generator.ambient_input])
    return inlet, ambient


def _told_beliefs(system: PowerSystem, t_s: float) -> list:
    """Per generator, the effects of the faults started by ``t_s`` (``--tell-fault``)."""
    known = system.faults_known_at(t_s)
    return [tuple((system.faults[i].effect, tuple(system.faults[i].values.items())) for i in known
                  if system.faults[i].generator == g and system.faults[i].effect) for g in range(system.n_generators)]


def fly(system: PowerSystem, scheduler: str, settings: ManagerSettings = ManagerSettings()) -> FlightResult:
    """Fly the mission in closed loop on the true plant (module docstring).

    Parameters
    ----------
    system : PowerSystem
    scheduler : {"heuristic", "engineer", "optimal", "milp"}
    settings : ManagerSettings

    Returns
    -------
    FlightResult
        True-plant temperatures, applied currents, one record per re-plan and the alarms with
        what was identified.

    Raises
    ------
    FlightTimeout
        When ``settings.cpu_limit_s`` is set and a management cycle starts past it.
    """
    started = time.process_time()
    dt = settings.dt_s
    cycle_steps = max(int(round(settings.cycle_s / dt)), 1)
    rng = np.random.default_rng(settings.seed)
    noise_sd = np.sqrt(np.asarray(system.planning_model.spec.interface.noise_variances_K2))
    segments = _segments(system, settings)
    schedule = Schedule.nominal(system.n_generators, len(segments))
    x_true = np.full((system.n_generators, system.nominal_model.n_states), system.mission.T_ambient_C)
    filter_cache: dict = {}
    if settings.nonlinear and flight_filter(system, settings) != "ekf":
        raise InputError("generators.filter", system.filter, "the nonlinear planner plans on the extended Kalman "
                         "filter's model and covariance: fly this scenario with --filter ekf")
    estimators = [StateEstimator(system.design_generator_for(()), lambda: system.planning_model, x_true[g], dt,
                                 filter_cache, flight_filter(system, settings)) for g in range(system.n_generators)]
    # the fault detector reads an extended Kalman filter's disturbance states: with the linear
    # filter in the loop it gets parallel extended Kalman filters of its own
    detector_cache: dict = {}
    detectors = estimators if flight_filter(system, settings) == "ekf" or settings.tell_fault else [
        StateEstimator(system.design_generator_for(()), lambda: system.planning_model, x_true[g], dt,
                       detector_cache, "ekf") for g in range(system.n_generators)]
    monitor = FaultMonitor(system, settings.detection, dt)
    from ..diagnose.input_sensors import input_sensors

    input_names = input_sensors(system.planning_model.spec.interface)
    sensor_faults = parse_sensor_faults(system.mission.extras.get("sensor_faults"), system.generator_names,
                                        system.planning_model.output_names, input_names)
    injector = SensorFaultInjector(sensor_faults, noise_sd, settings.seed)
    watch = SensorWatch(system, settings.sensor_watch, settings.detection, sensor_faults)
    inputs_watch = InputWatch(watch, settings.input_watch, input_names, system.n_generators)

    def read_inputs(times):
        """The inputs as the manager reads them at ``times`` (s): injected faults, claimed ones substituted."""
        return inputs_watch.substitute(times, injector.apply_inputs(times, true_inputs(system, input_names, times)))
    trusted = TrustedHeatFlows(system.n_generators)
    recorder = _Recorder(system)
    budget = settings.rest_budget_for(system.mission.duration_s)
    measured, inputs_read, t, rested_s, resting_s, cycles = None, None, 0.0, 0.0, 0.0, 0
    while segments:
        if settings.cpu_limit_s is not None and time.process_time() - started > settings.cpu_limit_s:
            raise FlightTimeout(t, cycles, time.process_time() - started, settings.cpu_limit_s)
        cycles += 1
        if measured is not None:
            before = [(e.z.copy(), None if e.P is None else e.P.copy()) for e in estimators]
            for g, estimator in enumerate(estimators):
                estimator.update(measured[g])
                if detectors is not estimators:
                    detectors[g].update(measured[g])
            if not settings.tell_fault:
                # sensor faults first: never seen as heat
                watch.cycle(t, estimators, measured, before, monitor, detectors)
                inputs_watch.cycle(t, inputs_read, estimators, monitor)
                believed, model = list(monitor.beliefs), monitor.model
                monitor.cycle(t, estimators, detectors)
                watch.review(t, believed, estimators, monitor, model)  # a new belief may be a sensor's doing
        beliefs = _told_beliefs(system, t) if settings.tell_fault else monitor.beliefs
        for g, estimator in enumerate(estimators):
            if settings.tell_fault:
                estimator.use(system.design_generator_for(beliefs[g]),
                              lambda g=g: believed_model(system.planning_model, beliefs[g]))
            else:
                estimator.use(monitor.design_generator(g), lambda g=g: monitor.flown_model(g))
                if detectors is not estimators:
                    detectors[g].use(monitor.design_generator(g), lambda g=g: monitor.flown_model(g))
        flown = FlownPlanning([e.filter for e in estimators], [e.z for e in estimators],
                              [e.P for e in estimators], settings.confidence_sigmas) if settings.nonlinear else None
        trusts = [watch.trusts_heat_flows(g, t) for g in range(system.n_generators)]
        # a sensor the watch does not trust may be what the innovation shows: no rise from it
        rise = np.array([unexplained_rise(e.innovation, e.innovation_std) if trusts[g] else np.zeros(2)
                         for g, e in enumerate(estimators)])
        problem = _problem(system, settings, segments, [e.x for e in estimators], t,
                           [trusted.planning_generator(g, e, trusts[g]) for g, e in enumerate(estimators)],
                           np.floor((budget - rested_s) / dt + 1e-9) * dt, resting_s, flown,
                           inputs_watch.for_plan(read_inputs(np.array([t]))), rise)
        shedding = bool(recorder.plans) and recorder.plans[-1]["method"] == "shed"  # re-planned every cycle
        if settings.replan and (shedding or predict(problem, schedule).peak()[0]
                                > problem.limit_C + settings.replan_tolerance_K):
            result = plan_with(scheduler, problem, settings, system.generator_names, system.limit_C,
                               previous=schedule, switched_off=schedule.switched_off,
                               when_infeasible=infeasible_response(system, settings), shedding=shedding)
            schedule = result.schedule.rounded(dt).within_rest_budget(problem.rest_budget_s,
                                                                      _first_rest_max_s(problem))
            recorder.plan(t, result, beliefs)
        timeline = build_timeline(segments, schedule, system.rest_current_A, dt)
        n = min(cycle_steps, timeline.n_steps)
        applied = timeline.head(n)
        outputs = np.empty((system.n_generators, 2, n))
        step_times = t + dt * np.arange(n)
        inputs_read = read_inputs(step_times)
        inlets, ambients = _filter_inputs(system, inputs_read, step_times)
        for g, estimator in enumerate(estimators):
            outputs[g], x_true[g] = _plant_steps(system, g, x_true[g], applied, t)
            estimator.predict(applied.currents_A[g], inlets[g], ambients[g])
            if detectors is not estimators:
                detectors[g].predict(applied.currents_A[g], inlets[g], ambients[g])
        sensed = outputs + noise_sd[None, :, None] * rng.standard_normal(outputs.shape)
        sample_times = t + dt * np.arange(1, n + 1)
        read = injector.apply(sample_times, sensed)
        monitor.record(t, applied.currents_A, watch.correct(sample_times, read), inputs_read)
        measured = watch.correct(sample_times, read, for_filter=True)[:, :, -1]
        recorder.add(segments, timeline, n, outputs, t)
        rested_s += float(np.count_nonzero(applied.resting)) * dt
        running = np.flatnonzero(~applied.resting)
        resting_s = resting_s + n * dt if running.size == 0 else float(n - 1 - running[-1]) * dt
        segments, schedule = remaining_after(segments, schedule, timeline, n)
        t += n * dt
    result = recorder.result(scheduler, True, monitor=monitor, settings=settings, cycles=cycles,
                             rest_budget_s=budget)
    result.sensor_watch = watch
    return result
