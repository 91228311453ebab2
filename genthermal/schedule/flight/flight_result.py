"""What a flight or an open-loop plan flew: :class:`FlightResult`, collected by :class:`FlightRecorder`."""

from __future__ import annotations

import dataclasses

import numpy as np

from ..planning.plan import PlanResult
from ..power_system import PowerSystem
from ..system_frame import SystemFrame


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
    plant_fault : dict or None
        The plant's failure that stopped the flight (closed loop): ``time_s``, ``cycle``, ``kind``,
        ``message``, ``plant``, ``held``, ``rest_current_A``; None when the plant answered throughout.
    replay : dict or None
        Flown along a replayed log (:class:`~genthermal.plants.log_plant.LogPlant`): the manager's
        decisions scored, not applied (:func:`~genthermal.schedule.flight.closed_loop.replay_score`).
    preflight : dict or None
        The verdict before take-off (closed loop,
        :func:`~genthermal.schedule.flight.preflight.preflight_check`): whether a plan holds θmax.
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
    plant_fault: dict | None = None
    replay: dict | None = None
    preflight: dict | None = None

    def to_pandas(self):
        """The flight as a table, one row per sample.

        Returns
        -------
        pandas.DataFrame
            ``time_s`` (s); per generator its winding and iron temperatures (°C, ``gen1_T_winding``)
            and the phase current applied over the step that starts there (A RMS,
            ``gen1_current_A``); the nominal current, ``resting`` and the mission ``action``
            (1-based). The step columns are empty on the last sample.
        """
        import pandas as pd

        n = self.currents_A.shape[1]
        columns = {"time_s": self.time_s}
        sensors = list(self.system.planning_model.output_names)
        for g, name in enumerate(self.system.generator_names):
            for k, sensor in enumerate(sensors):
                columns[f"{name}_{sensor}"] = self.temperatures_C[g, k]
        pad = np.full(self.time_s.size - n, np.nan)
        for g, name in enumerate(self.system.generator_names):
            columns[f"{name}_current_A"] = np.concatenate([self.currents_A[g], pad])
        columns["nominal_A"] = np.concatenate([self.nominal_A, pad])
        frame = pd.DataFrame(columns)
        frame["resting"] = pd.array(list(self.resting) + [pd.NA] * pad.size, dtype="boolean")
        frame["action"] = pd.array([int(a) + 1 for a in self.action_index] + [pd.NA] * pad.size, dtype="Int64")
        return frame

    def summary(self) -> dict:
        """The summary keys of ``genthermal plan`` / ``fly`` (:func:`~genthermal.schedule.report.flight_summary`)."""
        from ..report import flight_summary

        return flight_summary(self)

    def plot(self, path=None, title: str = ""):
        """Currents (rests shaded) and winding and iron temperatures of every generator.

        Parameters
        ----------
        path : path-like, optional
            PNG file to write the figure to.
        title : str
            Figure title.

        Returns
        -------
        matplotlib.figure.Figure
        """
        from ..report import plot_flight

        return plot_flight(self, title=title, path=path)


class FlightRecorder:
    """Collects the steps flown, from a cold machine (every node at the ambient temperature).

    Parameters
    ----------
    frame : SystemFrame
        The power system's names, rest current and ambient (:meth:`PowerSystem.frame`).
    """

    def __init__(self, frame: SystemFrame):
        self.frame, self.time = frame, [0.0]
        self.temperatures = [np.full((frame.n_generators, len(frame.output_names)), frame.T_ambient_C)]
        self.currents, self.nominal, self.resting, self.action, self.commanded = [], [], [], [], []
        self.plans, self.warnings, self.shed_events = [], [], []
        self.switched_off = np.zeros(frame.n_generators, dtype=bool)

    def plan(self, t_s: float, result: PlanResult, believed=None) -> None:
        """Record a (re-)plan made at ``t_s`` with the ``believed`` effects per generator."""
        record = {"time_s": t_s, "method": result.method, "solve_s": result.solve_s,
                  "feasible": result.feasible, "peak_C": result.peak_C, **result.details}
        if believed is not None:
            record["believed"] = {name: [{"effect": e, "parameters": dict(v)} for e, v in effects]
                                  for name, effects in zip(self.frame.generator_names, believed)}
        self.plans.append(record)
        self.warnings += result.warnings
        newly = result.schedule.switched_off & ~self.switched_off
        starts = result.method == "shed" and (not self.plans[:-1] or self.plans[-2]["method"] != "shed")
        if starts or newly.any():
            self.shed_events.append({"time_s": float(t_s), "shedding": list(result.details.get("shedding", [])),
                                     "switched_off": [self.frame.generator_names[g] for g in np.flatnonzero(newly)],
                                     "lowest_reachable_peak_C": result.details.get("lowest_peak_C"),
                                     "lowest_peak_action": result.details.get("lowest_peak_action"),
                                     "response": result.details.get("response", "")})
        self.switched_off |= result.schedule.switched_off

    def add(self, segments, timeline, n: int, outputs, t0: float, carried_A=None) -> None:
        """Record ``n`` steps of ``timeline`` and the ``outputs`` (n_gen, n_sensors, n) after each;
        ``carried_A`` (n_gen, n): the currents the plant carried when not the commanded ones, A."""
        dt = timeline.dt_s
        self.time += list(t0 + dt * np.arange(1, n + 1))
        self.temperatures += list(np.moveaxis(outputs, 2, 0))
        self.commanded.append(timeline.currents_A[:, :n])
        self.currents.append(timeline.currents_A[:, :n] if carried_A is None else np.asarray(carried_A))
        self.resting.append(timeline.resting[:n])
        self.action.append(np.array([segments[k].action_index for k in timeline.segment[:n]]))
        nominal = [self.frame.rest_current_A if timeline.resting[i] else
                   float(segments[timeline.segment[i]].current_at(timeline.offset_s[i])) for i in range(n)]
        self.nominal.append(np.array(nominal))

    def record(self) -> dict:
        """What was flown, as the :class:`FlightResult` fields of the same names: ``time_s``,
        ``temperatures_C``, ``currents_A``, ``nominal_A``, ``resting``, ``action_index``, ``plans``,
        ``warnings``, ``shed_events`` (the caller adds the system, the scheduler and the settings)."""
        nothing = not self.currents  # a plant that failed in the first cycle
        return dict(time_s=np.array(self.time), temperatures_C=np.moveaxis(np.array(self.temperatures), 0, 2),
                    currents_A=np.zeros((self.frame.n_generators, 0)) if nothing else np.hstack(self.currents),
                    nominal_A=np.zeros(0) if nothing else np.concatenate(self.nominal),
                    resting=np.zeros(0, dtype=bool) if nothing else np.concatenate(self.resting),
                    action_index=np.zeros(0, dtype=int) if nothing else np.concatenate(self.action),
                    plans=self.plans, warnings=self.warnings, shed_events=self.shed_events)

