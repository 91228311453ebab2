r"""A warmer coolant-inlet reading the physics has not confirmed yet: what the plan and filter hold.

A unit's inlet PT100 drives its filter and its plan. When it suddenly reads warmer than the other
units' two things can have happened, and they look alike at the inlet reading alone:

* the air really got warmer at that unit (a blockage recirculates hot air): the winding and the
  iron follow, along the model's response to the inlet step (on the thesis generator 0.31 K per K
  after 5 min, 0.48 after 10 min, 0.59 after 15 min for the winding; the iron about half that),
  and the outlet-air reading, where the machine's sensor schema has one, follows within a minute;
* the sensor reads high (a bias, a drift): only the reading moves.

**Shared air.** The units of a power system take their cooling air from one source: the mission
has one inlet temperature, and a unit's inlet differs from it only by the rise of a fault of that
unit (:meth:`PowerSystem.inlet_C <genthermal.schedule.power_system.PowerSystem.inlet_C>`, a
recirculating blockage). The other units' median reading is therefore the reference, as in
:mod:`~genthermal.schedule.monitoring.input_watch`; with one unit there is no reference, and nothing is held.

**Deciding.** Two tests, each cycle while the readings disagree: the input watch's record check
(:math:`\Delta`, the record's misfit with the unit's own reading against the other units', no
parameter fitted) claims the sensor at :math:`\Delta < -10` and confirms the rise at
:math:`\Delta > +10` (on the Fig. 7.7 flight a 3-K bias gave -7.6 one cycle after its onset and
-36 two cycles after; real 2-16 K steps were confirmed one cycle after); and the unit's fault test
(:meth:`~genthermal.schedule.monitoring.input_watch.InputWatch._confirm_by_heating`) confirms the rise when
it alarms on the unit, which a high-reading sensor cannot make it do (the model driven by a warmer
reading runs hot, the filter cools the unit) and a blockage that cuts the flow as it heats the
air does within a cycle or two, when the record check is still undecided (its misfit mixes the
flow's heating into both fits).

**The hold.** While the warmer reading is undecided, the plan *and the unit's filters* take the
unit's last agreeing (trusted) reading plus whatever of the rise exceeds
:attr:`~genthermal.schedule.monitoring.input_watch.InputWatchSettings.unconfirmed_rise_K`, for at most
:attr:`~genthermal.schedule.monitoring.input_watch.InputWatchSettings.max_unconfirmed_s` from the first held
plan. Planning the warmer reading at once (the rule before) moved the plan for a sensor fault: a +3
K inlet bias on a flight planned 0.1-0.2 K below its limit re-planned at its onset and changed three
cycles' loads before its claim; holding it from the plan only still let the filter learn heat flows
from it, which the claim takes back only approximately (1-3 re-plans, up to 7 load changes on other
noise seeds, ``benchmarks/bench_inlet_confirmation.py``). The bounds make a real rise safe: over
the hold and the cycle the last held plan is flown, a real rise of the held size heats the winding
by at most the response to a step of that size over that time (0.59 K per K after 15 min: 4 K
held for 10 min plus one 5-min cycle is 2.4 K), within the plan's margin (2.5 K,
``ManagerSettings.margin_K``). A rise larger than the held part is planned at once for the excess
(a 31-K blockage inlet is planned 27 K warmer from its first cycle). The hold ends when the readings
agree again, when a test confirms the rise (the reading is then planned and filtered), when the
check claims the sensor (the other units' reading is then used, as for any claimed input sensor),
when the checks run out, or at the time bound (the reading is then used).

A colder reading under check is held at the last agreeing one by the input watch without a bound
(:meth:`~genthermal.schedule.monitoring.input_watch.InputWatch.for_plan`): that is the safe side.
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
