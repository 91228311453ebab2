"""A flight as composed roles: ``Flight(plant, manager, mission).run()`` returns a
:class:`~genthermal.schedule.flight.flight_result.FlightResult`; :class:`Manager` is the scheduler
and its settings. The flight itself is :func:`~genthermal.schedule.flight.closed_loop.fly`.
"""

from __future__ import annotations

import dataclasses
import os

from .flight_result import FlightResult
from ..planning.registry import planner
from .manager_settings import ManagerSettings
from ..power_system import PowerSystem


@dataclasses.dataclass(frozen=True)
class Manager:
    """The load manager: ``scheduler`` (a registered planner: a built-in one or one of yours,
    :func:`~genthermal.schedule.planning.registry.register_planner`) with its ``settings``."""

    scheduler: str = "optimal"
    settings: ManagerSettings = dataclasses.field(default_factory=ManagerSettings)

    def __post_init__(self):
        planner(self.scheduler)  # an InputError naming the registered planners
        self.settings.check_scheduler(self.scheduler)


@dataclasses.dataclass
class Flight:
    """A mission flown by a manager against a plant (module docstring).

    Examples
    --------
    >>> from genthermal.schedule.flight.flight import Flight, Manager
    >>> result = Flight(None, Manager("engineer"), "thesis_fig_7_7").run()  # doctest: +SKIP
    >>> result.to_pandas().head()  # doctest: +SKIP
    """

    plant: object
    manager: Manager
    mission: str | os.PathLike | PowerSystem

    def power_system(self) -> PowerSystem:
        """The mission as a power system (a scenario is loaded by name or path)."""
        if isinstance(self.mission, PowerSystem):
            return self.mission
        from ...mission import load_mission

        return PowerSystem.from_mission(load_mission(self.mission))

    def run(self) -> FlightResult:
        """Fly the mission; the result holds a plant's failure in ``plant_fault`` (the flight so far)."""
        from .closed_loop import fly

        return fly(self.power_system(), self.manager.scheduler, self.manager.settings, self.plant)
