"""Two in-flight signatures of a sensor fault that no heat flow has: a frozen reading
(:func:`frozen_since`) and two nodes of one unit moving in opposite directions
(:func:`opposite_flows`, :class:`UnconfirmedExcess`). Method: docs/guide/flight-methods.md.
"""

from __future__ import annotations

import numpy as np


def frozen_since(time_s, values, min_samples: int) -> float | None:
    """Start of a run of identical readings at the end of a record, if the sensor was noisy before.

    Parameters
    ----------
    time_s : array_like
        (N,) sample times, s.
    values : array_like
        (N,) readings, °C (NaN: masked or missing; a NaN ends the record looked at).
    min_samples : int
        Shortest run taken for a frozen reading, samples.

    Returns
    -------
    float or None
        Time of the first sample of the run, s; None when the last ``min_samples`` readings are not
        all equal, or when the readings before the run are not noisy (fewer than two distinct values
        among the ``min_samples`` before it).
    """
    time_s, values = np.asarray(time_s, dtype=float), np.asarray(values, dtype=float)
    finite = np.flatnonzero(np.isfinite(values))
    if finite.size < 2 * min_samples or finite[-1] != values.size - 1:
        return None
    tail = values[finite]
    if np.any(tail[-min_samples:] != tail[-1]):
        return None
    changed = np.flatnonzero(tail != tail[-1])
    if changed.size == 0:
        return None
    start = int(changed[-1]) + 1
    before = tail[max(0, start - min_samples):start]
    if before.size < min_samples or np.unique(before).size < 2:
        return None
    return float(time_s[finite[start]])


def opposite_flows(statistics) -> np.ndarray:
    """:math:`m_g` of the module docstring from the fault test's :math:`r` (n_generators, 2); 0 where
    either statistic is NaN (a generator not tested this cycle)."""
    r = np.asarray(statistics, dtype=float)
    if r.ndim != 2 or r.shape[1] != 2:
        return np.zeros(r.shape[0] if r.ndim else 0)
    mixed = np.isfinite(r).all(axis=1) & (r[:, 0] * r[:, 1] < 0)
    return np.where(mixed, np.min(np.abs(np.nan_to_num(r)), axis=1), 0.0)


class UnconfirmedExcess:
    r"""Units whose extra heat flow the fault test has seen but not yet confirmed.

    Offset-free planning hands the plan each unit's disturbance heat flows. A sensor fault is
    absorbed by those heat flows before any test can tell it from heat: a 1.5 K/h winding-sensor
    drift is 0.4 K after 15 min, indistinguishable from a slowly growing winding heat source (both
    sensors have not had time to disagree), yet it moved a plan flown at 0.1-0.2 K from its limit
    (``benchmarks/bench_sensor_flights.py``: re-plans at 75 and 100 min, claimed at 120 min).

    A unit believed healthy whose fault statistic :math:`r_{gj}`
    (:mod:`genthermal.schedule.monitoring.detector`) rises above the largest value healthy flights reach
    (:attr:`bounds`) is *unconfirmed* from that cycle: the plan holds its last confirmed heat flows
    until the fault test alarms on it (the alarm's identification, reviewed by the sensor watch,
    then decides what the plan carries: a belief, a held belief, or a masked sensor) or for at most
    ``max_hold_s``. A fault strong enough to matter alarms within one or two cycles of crossing
    the bound (the detector's threshold), so the plan waits at most that for it; a statistic
    between the healthy maximum and the detector's drift never alarms and is taken after
    ``max_hold_s``.

    Parameters
    ----------
    bounds : array_like
        Per disturbance node, the statistic above which the unit's excess is unconfirmed.
    max_hold_s : float
        Longest hold, s.
    n_generators : int
    """

    def __init__(self, bounds, max_hold_s: float, n_generators: int):
        self.bounds, self.max_hold_s = np.asarray(bounds, dtype=float), float(max_hold_s)
        self.since: dict[int, float] = {}
        self.n_generators = n_generators
        #: Every hold: ``generator``, ``since_s``, ``until_s``, ``statistic`` and why it ended.
        self.events: list[dict] = []

    def update(self, t_s: float, statistics, believed_healthy, masked_units) -> None:
        """Start a hold for every unit believed healthy, not masked, whose statistic (n_gen, n_nodes)
        exceeds a bound this cycle; end holds older than ``max_hold_s``."""
        r = np.asarray(statistics, dtype=float)
        for g in range(self.n_generators):
            if g in self.since:
                if t_s - self.since[g] >= self.max_hold_s:
                    self.release(g, t_s, f"held {self.max_hold_s / 60:g} min without an alarm")
                continue
            if not believed_healthy[g] or g in masked_units or r.ndim != 2:
                continue
            above = np.isfinite(r[g]) & (r[g] > self.bounds)
            if above.any():
                self.since[g] = t_s
                self.events.append({"generator": g, "since_s": t_s, "until_s": None,
                                    "statistic": [float(v) for v in r[g]], "ended": None})

    def release(self, g: int, t_s: float, why: str) -> None:
        """End generator ``g``'s hold (if any) at ``t_s``, s, for the reason ``why``."""
        if self.since.pop(g, None) is None:
            return
        for event in reversed(self.events):
            if event["generator"] == g and event["until_s"] is None:
                event["until_s"], event["ended"] = t_s, why
                break

    def holds(self, g: int) -> bool:
        """True while generator ``g``'s excess is unconfirmed."""
        return g in self.since
