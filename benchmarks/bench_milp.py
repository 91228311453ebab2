"""MILP scheduler (HiGHS) on long missions: does it finish, and how far did it get when it did not?

Missions of 2, 4, 8 and 16 h are built from the thesis Fig. 7.7 flight (``blockage_large``: the
coolant blockage of gen1 at 66 min, flow factor 0.2, inlet +31 K): 2 h shortens its cruise, 8 and
16 h repeat 60 min of cruise before landing. Each is planned open loop (design model,
:func:`genthermal.schedule.flight.open_loop.plan_mission`) with 2, 3 and 4 generators by the MILP and,
for the ratio of added rest, by the optimal (NLP) scheduler.

Usage::

    python benchmarks/bench_milp.py [--hours 2 4 8 16] [--generators 2 3 4] [--time-limit 30] [--no-nlp]
                                    [--blocked 1]

With ``--blocked 2`` gen1 and gen2 are both blocked (cases with fewer than 3 generators skipped):
with one blockage, 3 and 4 generators have room enough that no rest is needed.

Prints one JSON line per case: hours, generators, MILP status, ``certified``, ``mip_gap``,
``incumbent_objective_min``, ``bound_min``, method, added rest, solve seconds, and the optimal
scheduler's added rest with the ratio MILP / NLP.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time

from genthermal.mission import Mission
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.flight.open_loop import plan_mission
from genthermal.schedule.planning.milp import MilpSettings
from genthermal.schedule.power_system import PowerSystem

#: Thesis Fig. 7.7 flight up to the fault (66 min): (condition number, minutes).
BEFORE_FAULT = [(1, 15), (2, 15), (3, 15), (4, 21)]
#: Its cruise, combat and cruise after the fault (4 h mission), and the landing.
FIG_7_7_CRUISE = [(5, 54), (6, 60), (5, 40)]
LANDING = (7, 20)
#: The blockage of ``scenarios/blockage_large.yaml`` (thesis 7.3.3).
BLOCKAGE = {"generator": 1, "kind": "coolant_blockage", "onset_min": 66, "k_flow": 0.2, "n_flow": 0.0,
            "inlet_rise_C": 31}


def mission_actions(hours: float) -> list[tuple[int, float]]:
    """Actions of a ``hours`` long mission: the Fig. 7.7 flight, its cruise shortened (2 h) or
    followed by 60 min cruise repeats (longer than 4 h)."""
    total_min = 60.0 * hours
    fixed = sum(m for _, m in BEFORE_FAULT) + LANDING[1]
    if total_min <= fixed + sum(m for _, m in FIG_7_7_CRUISE):
        middle = [(5, total_min - fixed)]
        if middle[0][1] <= 0:
            raise ValueError(f"hours={hours}: a mission must be longer than {fixed / 60:g} h")
    else:
        extra = total_min - fixed - sum(m for _, m in FIG_7_7_CRUISE)
        repeats = int(extra // 60)
        middle = FIG_7_7_CRUISE + [(5, 60.0)] * repeats + ([(5, extra - 60 * repeats)] if extra % 60 else [])
    return BEFORE_FAULT + middle + [LANDING]


def build_system(hours: float, n_generators: int, n_blocked: int = 1) -> PowerSystem:
    """The ``hours`` mission flown by ``n_generators`` generators, the first ``n_blocked`` of them
    blocked at 66 min."""
    if not 1 <= n_blocked < n_generators:
        raise ValueError(f"n_blocked={n_blocked}: must be 1..{n_generators - 1} (one generator stays healthy)")
    mission = Mission.from_dict({
        "name": f"blockage_{hours:g}h_{n_generators}gen_{n_blocked}blocked", "rated_current_A": 7.0, "T_inlet_C": 20.0,
        "T_ambient_C": 20.0,
        "generators": {"count": n_generators, "rest_percent": 27.3, "limit_C": 110.0,
                       "current_limit_percent": 100},
        "faults": [{**BLOCKAGE, "generator": g + 1} for g in range(n_blocked)],
        "actions": [{"condition": c, "duration_min": m} for c, m in mission_actions(hours)]})
    return PowerSystem.from_mission(mission)


def run_case(hours: float, n_generators: int, time_limit_s: float, with_nlp: bool, n_blocked: int = 1) -> dict:
    """Plan one case with the MILP (and the optimal scheduler) and report what each did."""
    system = build_system(hours, n_generators, n_blocked)
    settings = dataclasses.replace(ManagerSettings(), milp=MilpSettings(time_limit_s=time_limit_s))
    started = time.perf_counter()
    milp = plan_mission(system, "milp", settings)
    wall = time.perf_counter() - started
    record = {"hours": hours, "generators": n_generators, "blocked": n_blocked, "wall_s": round(wall, 2)}
    if not milp.plans:
        record["milp"] = "no plan needed"
        return record
    plan = milp.plans[0]
    keys = ("method", "plan_used", "status", "certified", "mip_gap", "incumbent_objective_min", "bound_min", "feasible",
            "solve_s", "peak_C", "n_rows", "n_columns", "n_integers")
    record.update({k: plan.get(k) for k in keys})
    record["milp_added_rest_s"] = milp.time_s[-1] - system.mission.duration_s
    record["targets"] = {"certified": bool(plan.get("certified"))}
    if with_nlp:
        optimal = plan_mission(system, "optimal", settings)
        rest = optimal.time_s[-1] - system.mission.duration_s
        record["nlp_added_rest_s"] = rest
        record["nlp_method"] = optimal.plans[0]["method"] if optimal.plans else None
        record["rest_ratio_milp_over_nlp"] = record["milp_added_rest_s"] / rest if rest > 0 else None
    return record


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--hours", type=float, nargs="+", default=[2, 4, 8, 16])
    parser.add_argument("--generators", type=int, nargs="+", default=[2, 3, 4])
    parser.add_argument("--time-limit", type=float, default=MilpSettings.time_limit_s, help="HiGHS time limit, s")
    parser.add_argument("--no-nlp", action="store_true", help="skip the optimal (NLP) scheduler")
    parser.add_argument("--blocked", type=int, default=1, help="generators blocked (default 1: gen1)")
    args = parser.parse_args(argv)
    for hours in args.hours:
        for n in args.generators:
            if args.blocked < n:
                print(json.dumps(run_case(hours, n, args.time_limit, not args.no_nlp, args.blocked), default=float),
                      flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
