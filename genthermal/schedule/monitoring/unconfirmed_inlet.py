"""A warmer coolant-inlet reading the physics has not confirmed yet: the plan and the filter hold
most of the rise back until the unit's own temperatures follow it. Main object:
:class:`UnconfirmedInlet`. Method: docs/guide/flight-methods.md.
"""

from __future__ import annotations

import numpy as np


class UnconfirmedInlet:
    """Per unit, the warmer inlet reading under check and since when the plan has held it back.

    Parameters
    ----------
    held_K : float
        Most of the rise the plan holds back, K.
    max_hold_s : float
        Longest hold from the first held plan, s.
    n_generators : int

    Attributes
    ----------
    events : list of dict
        Every hold: ``generator``, ``since_s``, ``until_s``, ``rise_K`` (largest reading minus
        trusted seen) and why it ended (``ended``).
    """

    def __init__(self, held_K: float, max_hold_s: float, n_generators: int):
        self.held_K, self.max_hold_s, self.n_generators = float(held_K), float(max_hold_s), n_generators
        self.since: dict[int, float] = {}
        #: Units whose hold reached its time bound: not held again until their readings agree.
        self._expired: set = set()
        self.events: list[dict] = []

    def planned(self, g: int, t_s: float, reading, trusted):
        """The inlet unit ``g``'s plan takes at ``t_s`` (s) for its warmer ``reading`` (°C) while
        it is unconfirmed: ``trusted`` (its last agreeing reading, °C) plus the rise beyond
        :attr:`held_K`; the reading itself once the hold has lasted :attr:`max_hold_s`."""
        reading, trusted = np.asarray(reading, dtype=float), np.asarray(trusted, dtype=float)
        if g in self._expired or self.held_K <= 0.0:  # nothing held (a flight planned without margin)
            return reading
        if g not in self.since:
            self.since[g] = t_s
            self.events.append({"generator": g, "since_s": t_s, "until_s": None, "rise_K": 0.0, "ended": None})
        event = self._open(g)
        event["rise_K"] = max(event["rise_K"], float(np.max(reading - trusted)))
        if t_s - self.since[g] > self.max_hold_s:
            self.release(g, t_s, f"held {self.max_hold_s / 60:g} min without a decision: the reading is planned")
            self._expired.add(g)
            return reading
        return np.maximum(trusted, reading - self.held_K)

    def agrees(self, g: int, t_s: float) -> None:
        """Unit ``g``'s reading agrees with the other units' again: any hold ends."""
        self._expired.discard(g)
        self.release(g, t_s, "the readings agree again")

    def release(self, g: int, t_s: float, why: str) -> None:
        """End unit ``g``'s hold (if any) at ``t_s``, s, for the reason ``why``."""
        if self.since.pop(g, None) is None:
            return
        event = self._open(g)
        event["until_s"], event["ended"] = t_s, why

    def expired(self, g: int) -> bool:
        """True when unit ``g``'s hold reached its time bound (until its readings agree again)."""
        return g in self._expired

    def holds(self, g: int) -> bool:
        """True while unit ``g``'s warmer inlet reading is held back from its plan."""
        return g in self.since

    def _open(self, g: int) -> dict:
        return next(e for e in reversed(self.events) if e["generator"] == g and e["until_s"] is None)
