"""Re-plan time of the optimal scheduler in the closed loop: flown (nonlinear) model versus design model.

Flies ``blockage_large`` (thesis 7.3.3: 4 h, 2 generators, the coolant blockage of gen1 at 66 min)
in closed loop with the optimal scheduler twice in one process, once per planner model
(``--planner-model affine`` and ``nonlinear``), and times every re-plan the manager makes (the
``solve_s`` of each plan record: the scheduler, and the lowest-peak search when a plan is
infeasible). The first plan of the nonlinear planner includes building its solver (CasADi expands
the NLP and its exact Hessian once per set of filters); so does the first plan after an
identification changes a filter's model. Both are counted in the median and the maximum, and
reported separately.

Usage::

    python benchmarks/bench_replan.py [--scenario blockage_large] [--tell-fault]

Prints one JSON object: per planner model the re-plan count, median and maximum re-plan time (s,
wall-clock as recorded in the plans and CPU time of this process, which a shared machine does not
inflate), IPOPT's iterations, the flight's mission time, added rest, peaks and breach; the ratios
of the medians (nonlinear / affine) and the machine's load average.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

from genthermal.mission import load_mission
from genthermal.schedule.flight import closed_loop
from genthermal.schedule.flight.closed_loop import fly
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.power_system import PowerSystem
from genthermal.schedule.report import flight_summary


def replan_times(scenario: str, planner_model: str, tell_fault: bool) -> dict:
    """Fly ``scenario`` with the optimal scheduler planning on ``planner_model``; the re-plan times
    and the flight's figures."""
    system = PowerSystem.from_mission(load_mission(scenario))
    settings = ManagerSettings(planner_model=planner_model, tell_fault=tell_fault)
    cpu_s = []
    plan_with = closed_loop.plan_with

    def timed(*args, **kwargs):  # CPU time of each re-plan: the machine is shared, wall-clock is not ours
        started = time.process_time()
        result = plan_with(*args, **kwargs)
        cpu_s.append(time.process_time() - started)
        return result
    closed_loop.plan_with = timed
    try:
        started = time.perf_counter()
        result = fly(system, "optimal", settings)
        flight_s = time.perf_counter() - started
    finally:
        closed_loop.plan_with = plan_with
    times, cpu = np.array([plan["solve_s"] for plan in result.plans]), np.array(cpu_s)
    summary = flight_summary(result)
    return {"replans": int(times.size),
            "median_replan_s": float(np.median(times)) if times.size else None,
            "max_replan_s": float(np.max(times)) if times.size else None,
            "replan_s": [round(float(t), 3) for t in times],
            "median_replan_cpu_s": float(np.median(cpu)) if cpu.size else None,
            "max_replan_cpu_s": float(np.max(cpu)) if cpu.size else None,
            "replan_cpu_s": [round(float(t), 3) for t in cpu],
            "ipopt_iterations": [plan.get("ipopt_iterations") for plan in result.plans],
            "flight_wall_s": flight_s,
            "mission_time_s": summary["mission_time_s"], "added_rest_s": summary["added_rest_s"],
            "max_T_winding": summary["max_T_winding"], "breach_s": summary["breach_s"],
            "feasible": summary["feasible"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default="blockage_large")
    parser.add_argument("--tell-fault", action="store_true", help="hand the manager the fault (no identification)")
    args = parser.parse_args()
    report = {"scenario": args.scenario, "tell_fault": args.tell_fault}
    for planner_model in ("affine", "nonlinear"):  # "auto" is one of them (the optimal scheduler: nonlinear)
        report[planner_model] = replan_times(args.scenario, planner_model, args.tell_fault)
    for key in ("median_replan_s", "median_replan_cpu_s"):
        affine, nonlinear = report["affine"][key], report["nonlinear"][key]
        report[f"{key}_ratio_nonlinear_to_affine"] = nonlinear / affine if affine and nonlinear else None
    report["load_average_1min"] = os.getloadavg()[0]
    print(json.dumps(report))


if __name__ == "__main__":
    main()
