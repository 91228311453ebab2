"""Load management of several generators (thesis chapter 7).

* :mod:`.power_system` — N generators sharing a mission's load, faults with onsets, the design
  model as matrices (:class:`AffineGenerator`);
* :mod:`.plan` — segments, schedules (displaced current, rests), timelines, predictions;
* :mod:`.heuristic` — the thesis algorithm (eqs. 7.1-7.5, Fig. 7.2);
* :mod:`.optimal` — direct transcription in CasADi, IPOPT;
* :mod:`.milp` — discrete rests and load chunks as a MILP, HiGHS;
* :mod:`.closed_loop` — open-loop plans and the closed loop of thesis 7.2 (Kalman filter, re-plans);
* :mod:`.report` — summary keys, plots and the demo;
* :mod:`.flight` — ``Flight(plant, manager, mission).run()``, the flight as composed roles.
"""

from .closed_loop import fly
from .flight import Flight, Manager

from .manager_settings import SCHEDULERS, ManagerSettings

from .open_loop import plan_mission

from .replanning import plan_with
from .heuristic import HeuristicSettings, heuristic_plan
from .milp import MilpSettings, milp_plan
from .optimal import OptimalSettings, lowest_reachable_peak, optimal_plan
from .plan import PlanningProblem, PlanResult, Schedule, Segment, mission_segments, predict
from .power_system import AffineGenerator, Fault, PowerSystem

__all__ = ["SCHEDULERS", "AffineGenerator", "Fault", "Flight", "Manager", "HeuristicSettings", "ManagerSettings", "MilpSettings",
           "OptimalSettings", "PlanResult", "PlanningProblem", "PowerSystem", "Schedule", "Segment", "fly",
           "heuristic_plan", "lowest_reachable_peak", "milp_plan", "mission_segments", "optimal_plan",
           "plan_mission", "plan_with", "predict"]
