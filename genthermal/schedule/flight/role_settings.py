"""The settings each role of the flight receives: the loop, the estimator, the monitor, the planner.

:meth:`~genthermal.schedule.flight.manager_settings.ManagerSettings.roles` splits the manager's
settings (the keys of the command line and of a scenario) into these, with the scenario's say
resolved; each role is handed its own object only.
"""

from __future__ import annotations

import dataclasses

from ..monitoring.input_watch import InputWatchSettings
from ..monitoring.monitor import DetectionSettings
from ..monitoring.sensor_watch import SensorWatchSettings
from ..planning.engineer import EngineerSettings
from ..planning.heuristic import HeuristicSettings
from ..planning.milp import MilpSettings
from ..planning.optimal import OptimalSettings


@dataclasses.dataclass(frozen=True)
class LoopSettings:
    """The closed loop's clock and limits.

    Attributes
    ----------
    cycle_s, dt_s : float
        Management cycle and plant step, s.
    seed : int
        Seed of the measurement noise.
    rest_budget_s : float
        Most rest the flight may add, s (resolved for the mission).
    cpu_limit_s : float or None
        Processor time the flight may take, s; None: no limit.
    replan : bool
        Re-plan when the prediction crosses the planning limit.
    replan_tolerance_K : float
        A prediction above the planning limit by more than this triggers a re-plan, K.
    tell_fault : bool
        Hand the manager every fault from the first cycle after its onset (no detection).
    """

    cycle_s: float
    dt_s: float
    seed: int
    rest_budget_s: float
    cpu_limit_s: float | None
    replan: bool
    replan_tolerance_K: float
    tell_fault: bool


@dataclasses.dataclass(frozen=True)
class EstimatorSettings:
    """The filter in the loop: ``filter``, ``ekf`` or ``kf`` (the scenario's when it names one); it
    steps with the loop's ``dt_s``."""

    filter: str


@dataclasses.dataclass(frozen=True)
class MonitorSettings:
    """Fault detection and identification (``detection``), the sensor watch (``sensor_watch``) and
    the inlet and ambient watch (``input_watch``, which holds substitutes within ``margin_K``, K)."""

    detection: DetectionSettings
    sensor_watch: SensorWatchSettings
    input_watch: InputWatchSettings
    margin_K: float


@dataclasses.dataclass(frozen=True)
class PlannerSettings:
    """What the re-planning uses (:mod:`~genthermal.schedule.flight.replanning`); the fields are
    :class:`~genthermal.schedule.flight.manager_settings.ManagerSettings`'s of the same names, with
    the scenario's ``margin_K`` and ``when_infeasible`` resolved.

    Attributes
    ----------
    cycle_s, dt_s : float
        Management cycle and plan step, s.
    margin_K : float
        Back-off margin below θmax, K.
    rise_backoff : float
        κ of the robust constraint on rises within one cycle.
    max_rest_s : float
        Longest rest before one segment, s.
    planner_model : str
        ``affine`` or ``nonlinear``.
    confidence_sigmas : float
        Standard deviations kept below θmax by the nonlinear planner.
    own_shed : bool
        This flight's optimal scheduler plans its own shed plan on the flown model (resolved:
        :meth:`ManagerSettings.sheds_on_flown_model`).
    when_infeasible : str
        ``shed`` or ``best_effort``.
    heuristic, engineer, optimal, milp
        Settings of each scheduler.
    """

    cycle_s: float
    dt_s: float
    margin_K: float
    rise_backoff: float
    max_rest_s: float
    planner_model: str
    confidence_sigmas: float
    own_shed: bool
    when_infeasible: str
    heuristic: HeuristicSettings
    engineer: EngineerSettings
    optimal: OptimalSettings
    milp: MilpSettings

    @property
    def nonlinear(self) -> bool:
        """True when planning on the flown (nonlinear) model."""
        return self.planner_model == "nonlinear"


@dataclasses.dataclass(frozen=True)
class ManagerRoles:
    """The four role settings of one flight (:meth:`ManagerSettings.roles`)."""

    loop: LoopSettings
    estimator: EstimatorSettings
    monitor: MonitorSettings
    planner: PlannerSettings
