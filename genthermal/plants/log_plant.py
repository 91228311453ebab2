"""A recorded flight replayed as the plant (``fly --plant log.csv``): the manager flies along a log.

The log is a CSV with ``time_s`` (s, every step of the flight from 0) and one column per generator
and sensor, ``gen1_T_winding`` (°C), as ``fly --record`` writes it
(:meth:`~genthermal.schedule.flight.flight_result.FlightResult.to_pandas`). Its ``gen1_current_A``
columns, when present, are the currents the logged flight carried: the filter is driven with them.
The manager's decisions are recorded and scored, never applied (the log does not change).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import InputError
from .protocol import TIMESTAMP_TOLERANCE_S, PlantFault, PlantSetup, Readings

#: Columns of a flight record that are neither a sensor nor a current (``fly --record``).
RECORD_COLUMNS = ("time_s", "nominal_A", "resting", "action")
#: Largest log read, bytes.
MAX_LOG_BYTES = 200_000_000


class LogPlant:
    """:class:`~genthermal.plants.protocol.Plant` that replays the readings of a recorded flight.

    Parameters
    ----------
    path : path-like
        The CSV log (module docstring).
    sensor_names : sequence of str
        The machine's sensors (``T_winding``, ``T_iron``): each generator's must all be in the log.
    option : str
        The option named in errors.

    Attributes
    ----------
    end_s : float
        The log's last time, s: the flight ends there.
    replays_log : bool
        True: the flight's decisions are not applied (the summary says so).
    """

    replays_log = True

    def __init__(self, path, sensor_names, option: str = "--plant"):
        self.path, self.option = Path(path), option
        if not self.path.is_file():
            raise InputError(option, str(path), "no such log file")
        if self.path.stat().st_size > MAX_LOG_BYTES:
            raise InputError(option, str(path), f"the log is larger than {MAX_LOG_BYTES // 1_000_000} MB")
        try:
            self.frame = pd.read_csv(self.path)
        except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as error:
            raise InputError(option, str(path), f"not a readable CSV log: {error}") from None
        if "time_s" not in self.frame.columns:
            raise InputError(f"{option} column", "time_s", f"the log {self.path.name} has no time_s column "
                             f"(its columns: {list(self.frame.columns)[:8]})")
        self.time_s = pd.to_numeric(self.frame["time_s"], errors="coerce").to_numpy(dtype=float)
        if self.time_s.size < 2 or not np.all(np.isfinite(self.time_s)) or np.any(np.diff(self.time_s) <= 0.0):
            raise InputError(f"{option} column", "time_s", "must hold at least two finite, increasing times, s")
        self.sensor_names = tuple(sensor_names)
        self.end_s = float(self.time_s[-1])
        self._columns = None

    def reset(self, setup: PlantSetup) -> None:
        """Check the log holds every generator's sensors at the flight's step (InputError naming the
        missing or extra column) and start at its first row."""
        wanted = [f"{name}_{sensor}" for name in setup.generator_names for sensor in self.sensor_names]
        missing = [c for c in wanted if c not in self.frame.columns]
        currents = [f"{name}_current_A" for name in setup.generator_names]
        known = set(wanted) | set(currents) | set(RECORD_COLUMNS)
        extra = [c for c in self.frame.columns if c not in known]
        if missing or extra:
            column = (missing or extra)[0]
            raise InputError(f"{self.option} column", column,
                             f"the log {self.path.name} does not match the machine's sensors "
                             f"{list(self.sensor_names)} of {list(setup.generator_names)}"
                             + (f": missing {missing}" if missing else "") + (f"; extra {extra}" if extra else ""))
        step = float(np.median(np.diff(self.time_s)))
        if abs(self.time_s[0]) > TIMESTAMP_TOLERANCE_S or abs(step - setup.dt_s) > TIMESTAMP_TOLERANCE_S:
            raise InputError(f"{self.option} column", "time_s", f"the log starts at {self.time_s[0]:g} s with a "
                             f"step of {step:g} s; the flight starts at 0 with a step of {setup.dt_s:g} s")
        self._columns = [[f"{name}_{sensor}" for sensor in self.sensor_names] for name in setup.generator_names]
        self._currents = currents if all(c in self.frame.columns for c in currents) else None

    def step(self, t_s: float, dt_s: float, inputs: dict) -> Readings:
        """The logged readings at ``t_s + dt_s * (1..n)`` (``inputs``, the manager's commands, are
        not applied); ``applied_A``: the logged currents over those steps, when the log has them."""
        n = next(iter(inputs.values())).shape[1]
        times = t_s + dt_s * np.arange(1, n + 1)
        rows = np.searchsorted(self.time_s, times - TIMESTAMP_TOLERANCE_S)
        if rows[-1] >= self.time_s.size or not np.allclose(self.time_s[rows], times, atol=TIMESTAMP_TOLERANCE_S):
            raise PlantFault("timestamps", f"the log {self.path.name} has no row at {times[-1]:g} s "
                             f"(it ends at {self.end_s:g} s)")
        # only the rows read now are converted: a bad value stops the flight when it is reached
        values = np.array([self.frame[columns].iloc[rows].to_numpy(dtype=float).T for columns in self._columns])
        applied = None
        if self._currents is not None:  # the current over a step is on the row that starts it
            applied = self.frame[self._currents].iloc[rows - 1].to_numpy(dtype=float).T
        return Readings(times, values, self.sensor_names, applied)
