"""Settings of the load management system (thesis 7.2), the scenario's say over them and their split
into the settings of each role (:mod:`~genthermal.schedule.flight.role_settings`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

from ...errors import InputError
from ..planning.engineer import EngineerSettings
from ..planning.flown import DEFAULT_CONFIDENCE_SIGMAS
from ..planning.heuristic import HeuristicSettings
from ..monitoring.input_watch import InputWatchSettings
from ..planning.milp import MilpSettings
from ..monitoring.monitor import DetectionSettings
from ..planning.optimal import OptimalSettings
from ..planning.plan import DEFAULT_MARGIN_K
from ..planning.registry import BUILT_IN_PLANNERS, model_for, planner
from ..monitoring.sensor_watch import SensorWatchSettings
from ..planning.shed import INFEASIBLE_RESPONSES
from .role_settings import EstimatorSettings, LoopSettings, ManagerRoles, MonitorSettings, PlannerSettings

#: The schedulers genthermal ships (others may be registered: :mod:`genthermal.schedule.planning.registry`).
SCHEDULERS = BUILT_IN_PLANNERS
#: Models the schedulers may plan on (``ManagerSettings.planner_model``): ``auto``, each planner's
#: own default when the filter allows (:func:`~genthermal.schedule.planning.registry.model_for`);
#: ``affine``, the design model with the margin and the rise back-off; ``nonlinear``, the flown
#: model the filter runs on, with the back-off of its covariance (:mod:`genthermal.schedule.planning.flown`),
#: the mission cut into control intervals of one cycle (the thesis heuristic keeps its K-conditions).
PLANNER_MODELS = ("auto", "affine", "nonlinear")
#: Schedulers that plan on the flown model when ``planner_model`` is ``nonlinear``; the engineer's
#: heuristic and the MILP are defined on the design model.
FLOWN_SCHEDULERS = tuple(name for name in BUILT_IN_PLANNERS if planner(name).on_flown_model)
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
        (:meth:`with_scenario`).
    rise_backoff : float
        :math:`\\kappa` of the robust constraint on temperature rises within one cycle (see
        :class:`~genthermal.schedule.planning.plan.PlanningProblem`).
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
        (:mod:`genthermal.schedule.monitoring.monitor`).
    replan : bool
        Re-plan when the prediction crosses the planning limit (default); False flies the nominal
        schedule whatever is predicted, which isolates the filter and the fault detector from the
        scheduler (detection benchmarks).
    filter : str
        Filter in the loop, a key of :data:`genthermal.schedule.state_estimator.FLIGHT_FILTERS`: ``"ekf"``
        (default, the extended Kalman filter on the flown nonlinear model) or ``"kf"`` (the
        thesis linear filter on the design model).
    detection : DetectionSettings
        Fault detection and identification in flight.
    sensor_watch : SensorWatchSettings
        Sensor-fault detection and masking in flight (:mod:`genthermal.schedule.monitoring.sensor_watch`).
    input_watch : InputWatchSettings
        Inlet and ambient sensor faults in flight (:mod:`genthermal.schedule.monitoring.input_watch`).
    planner_model : str
        One of :data:`PLANNER_MODELS`: ``auto`` (default) is resolved per flight by
        :meth:`for_flight` (the optimal scheduler on the flown model when the flight's filter is
        ``ekf``, every other planner and the ``kf`` filter on the design model); ``affine`` plans on the design model within θmax −
        ``margin_K`` with the rise back-off; ``nonlinear`` plans on the flown model (the filter's,
        ``filter`` must be ``ekf``) within θmax with the back-off of the filter's covariance
        (``confidence_sigmas`` standard deviations; ``margin_K`` and ``rise_backoff`` unused), and
        displacement and rest free per management cycle (the thesis heuristic: per K-condition;
        only the schedulers of :data:`FLOWN_SCHEDULERS` plan on it).
    confidence_sigmas : float
        Standard deviations of the predicted temperature kept below θmax by the nonlinear planner.
    own_shed : bool
        The optimal scheduler planning on the design model (``planner_model`` ``affine``) with the
        extended Kalman filter: when it must shed load, it also plans rest, displacement and load
        not served together on the flown model and flies that plan whenever it keeps θmax on its
        forecast, else the shared shed plan (:mod:`~genthermal.schedule.planning.optimal_shed`; default True).
        False: it flies the shared shed plan, as the baselines do. With ``filter`` ``kf`` there is
        no flown model and the shared plan is flown.
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
        (:meth:`with_scenario`).
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
    planner_model: str = "auto"
    confidence_sigmas: float = DEFAULT_CONFIDENCE_SIGMAS
    own_shed: bool = True
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
        if not isinstance(self.own_shed, bool):
            raise InputError("own_shed", self.own_shed, "must be True or False")

    def check_scheduler(self, scheduler: str) -> None:
        """InputError naming ``planner_model`` when ``scheduler`` cannot plan on the model it names
        (on the flown model only those of :data:`FLOWN_SCHEDULERS` plan; the others are defined on
        the design model, and their plans would be judged on the flown one)."""
        if self.nonlinear and not planner(scheduler).on_flown_model:
            raise InputError("planner_model", self.planner_model, f"the {scheduler} scheduler plans on the design "
                             f"model; on the flown model plan with one of {', '.join(FLOWN_SCHEDULERS)}")

    def for_flight(self, scheduler: str, filter_flown: str) -> "ManagerSettings":
        """These settings with ``planner_model`` resolved for ``scheduler`` flown with the filter
        ``filter_flown`` (the scenario's ``generators.filter`` when it names one, else ``filter``):
        :func:`~genthermal.schedule.planning.registry.model_for`."""
        return dataclasses.replace(self, planner_model=model_for(scheduler, self.planner_model, filter_flown))

    @property
    def nonlinear(self) -> bool:
        """True when planning on the flown (nonlinear) model."""
        return self.planner_model == "nonlinear"

    def sheds_on_flown_model(self, scheduler: str, filter_flown: str) -> bool:
        """True when ``scheduler`` plans its own shed plan on the flown model (``own_shed``): the
        optimal scheduler on the design model with the extended Kalman filter. ``filter_flown`` is the
        filter the flight runs (:meth:`with_scenario`: a scenario's ``generators.filter`` overrides
        ``filter``; with the thesis's linear filter there is no flown model to plan on)."""
        return self.own_shed and scheduler == "optimal" and not self.nonlinear and filter_flown == "ekf"

    def rest_budget_for(self, mission_duration_s: float) -> float:
        """The flight's rest budget, s, for a mission of ``mission_duration_s`` (s)."""
        if self.rest_budget_s is not None:
            return float(self.rest_budget_s)
        return DEFAULT_REST_BUDGET_FRACTION * float(mission_duration_s)

    def with_scenario(self, say: Mapping) -> "ManagerSettings":
        """These settings with the scenario's say over them (``say``: a scenario's ``generators:``
        key → value, :attr:`PowerSystem.manager_say <genthermal.schedule.power_system.PowerSystem.manager_say>`):
        the scenario's ``margin_K``, ``filter`` and ``when_infeasible`` replace the manager's own.

        Raises
        ------
        InputError
            Naming ``generators.<key>`` for a key that is not a field of these settings, and
            ``generators.filter`` when the nonlinear planner would fly the thesis's linear filter.
        """
        fields = {field.name for field in dataclasses.fields(self)}
        for key, value in say.items():
            if key not in fields:
                raise InputError(f"generators.{key}", value, f"is not a setting of the manager: one of "
                                 f"{', '.join(sorted(fields))}")
        if self.nonlinear and say.get("filter", self.filter) != "ekf":
            raise InputError("generators.filter", say["filter"], "the nonlinear planner plans on the extended Kalman "
                             "filter's model and covariance: fly this scenario with --filter ekf")
        return dataclasses.replace(self, **say) if say else self

    def roles(self, scheduler: str, mission_duration_s: float, say: Mapping | None = None) -> ManagerRoles:
        """The settings of each role of a flight of ``scheduler`` over a mission of
        ``mission_duration_s`` (s), with the scenario's ``say`` (:meth:`with_scenario`).

        Raises
        ------
        InputError
            As :meth:`check_scheduler` and :meth:`with_scenario`.
        """
        self.check_scheduler(scheduler)
        own = self.with_scenario(say or {})
        own = own.for_flight(scheduler, own.filter)  # planner_model "auto" resolved to what the planner can
        return ManagerRoles(
            LoopSettings(own.cycle_s, own.dt_s, own.seed, own.rest_budget_for(mission_duration_s), own.cpu_limit_s,
                         own.replan, own.replan_tolerance_K, own.tell_fault),
            EstimatorSettings(own.filter),
            MonitorSettings(own.detection, own.sensor_watch, own.input_watch, own.margin_K),
            PlannerSettings(own.cycle_s, own.dt_s, own.margin_K, own.rise_backoff, own.max_rest_s, own.planner_model,
                            own.confidence_sigmas, own.sheds_on_flown_model(scheduler, own.filter),
                            own.when_infeasible, own.heuristic, own.engineer, own.optimal, own.milp))
