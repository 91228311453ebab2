"""Load management of several generators (thesis chapter 7), as composed roles.

* :mod:`.power_system` — the generators sharing a mission's load, their faults, the design model;
* :mod:`.state_estimator` — each generator's filter in flight (the estimator role);
* :mod:`.planning` — schedules and the planners (thesis heuristic, engineer, optimal, MILP, shedding);
* :mod:`.monitoring` — fault detection and identification, the sensor watches (the monitor role);
* :mod:`.flight` — the closed loop of thesis 7.2, ``Flight(plant, manager, mission).run()``;
* :mod:`.sweeps` — the robustness grid in worker processes;
* :mod:`.report` — summary keys, plots and the demo.
"""

from .flight.closed_loop import fly
from .flight.flight import Flight, Manager
from .flight.manager_settings import SCHEDULERS, ManagerSettings
from .flight.open_loop import plan_mission
from .flight.replanning import plan_with
from .planning.heuristic import HeuristicSettings, heuristic_plan
from .planning.milp import MilpSettings, milp_plan
from .planning.optimal import OptimalSettings, lowest_reachable_peak, optimal_plan
from .planning.plan import PlanningProblem, PlanResult, Schedule, Segment, mission_segments, predict
from .power_system import AffineGenerator, Fault, PowerSystem

__all__ = ["SCHEDULERS", "AffineGenerator", "Fault", "Flight", "Manager", "HeuristicSettings", "ManagerSettings", "MilpSettings",
           "OptimalSettings", "PlanResult", "PlanningProblem", "PowerSystem", "Schedule", "Segment", "fly",
           "heuristic_plan", "lowest_reachable_peak", "milp_plan", "mission_segments", "optimal_plan",
           "plan_mission", "plan_with", "predict"]
