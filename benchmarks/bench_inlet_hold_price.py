"""The price of holding a warmer inlet reading on real inlet rises: chapter-7 and blockage flights.

The inlet hold (:mod:`genthermal.schedule.monitoring.unconfirmed_inlet`) keeps a warmer coolant-inlet reading
out of the plan and the filter until the physics confirms it. On a real rise that may delay the
manager's first action. Each scenario is flown with every scheduler twice: with the hold
(``InputWatchSettings()``) and without it (``unconfirmed_rise_K`` 0: the warmer reading planned and
filtered at once, the rule before the hold). The heuristic flies the chapter-7 scenarios as the
thesis did (their ``margin_K`` 0, so nothing is held); the other schedulers with the manager's own
margin and load shedding, as ``benchmarks/reproduce_thesis.py`` flies them.

Figures per flight: the first re-plan after the fault's onset (min), the hottest winding per
generator, the time above θmax (s), sensor faults claimed (none may be) and the effects identified;
per pair, the first time the applied currents differ (min). Usage:
``python benchmarks/bench_inlet_hold_price.py [--json FILE]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

import numpy as np

from genthermal.mission import load_mission
from genthermal.schedule.flight.closed_loop import fly
from genthermal.schedule.monitoring.input_watch import InputWatchSettings
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.power_system import PowerSystem
from genthermal.schedule.report import flight_summary

SCENARIOS = ("chapter7_inlet_3C", "chapter7_inlet_4C", "chapter7_inlet_16C", "chapter7_blockage_large",
             "blockage_large", "blockage_inlet_4C", "blockage_inlet_16C")
SCHEDULERS = ("heuristic", "engineer", "optimal")


def _flown(scenario: str, scheduler: str, inputs: InputWatchSettings):
    system = PowerSystem.from_mission(load_mission(scenario))
    if scheduler != "heuristic" and scenario.startswith("chapter7"):
        system = dataclasses.replace(system, margin_K=None, when_infeasible=None)
    return system, fly(system, scheduler, dataclasses.replace(ManagerSettings(), input_watch=inputs))


def _figures(system, result) -> dict:
    onset_s = min(fault.onset_s for fault in system.faults)
    summary = flight_summary(result)
    dt = np.diff(result.time_s)
    return {"first_replan_min": min((p["time_s"] / 60.0 for p in result.plans if p["time_s"] >= onset_s),
                                    default=None),
            "max_T_winding_C": [round(float(v), 2) for v in result.temperatures_C[:, 0, :].max(axis=1)],
            "s_above_limit": float(np.sum(dt[np.max(result.temperatures_C[:, 0, 1:], axis=0) > system.limit_C])),
            "claimed": [(c["generator"], c["sensor"], c["kind"]) for c in summary["sensor_faults"]["claimed"]],
            "identified": [(i["generator"], i["detected_at_s"] / 60.0, i["effect"]) for i in summary["identified"]],
            "inlet_holds": [(h["generator"], h["since_s"] / 60.0, None if h["until_s"] is None else h["until_s"] / 60.0,
                             h["ended"]) for h in summary["sensor_faults"]["inlet_readings_unconfirmed"]]}


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="also write the result to this file")
    args = parser.parse_args(argv)
    started, rows = time.perf_counter(), []
    for scenario in SCENARIOS:
        for scheduler in SCHEDULERS:
            system, held = _flown(scenario, scheduler, InputWatchSettings())
            _, not_held = _flown(scenario, scheduler, InputWatchSettings(unconfirmed_rise_K=0.0))
            n = min(held.currents_A.shape[1], not_held.currents_A.shape[1])
            differs = np.flatnonzero(np.abs(held.currents_A[:, :n] - not_held.currents_A[:, :n]).max(axis=0) > 1e-3)
            rows.append({"scenario": scenario, "scheduler": scheduler, "held": _figures(system, held),
                         "not_held": _figures(system, not_held),
                         "loads_differ_from_min": float(held.time_s[differs[0]] / 60.0) if differs.size else None})
            print(json.dumps(rows[-1]), flush=True)
    delays = [r["held"]["first_replan_min"] - r["not_held"]["first_replan_min"] for r in rows
              if r["held"]["first_replan_min"] is not None and r["not_held"]["first_replan_min"] is not None]
    result = {"flights": 2 * len(rows),
              "s_above_limit_held": sum(r["held"]["s_above_limit"] for r in rows),
              "s_above_limit_not_held": sum(r["not_held"]["s_above_limit"] for r in rows),
              "sensor_claims": sum(len(r["held"]["claimed"]) + len(r["not_held"]["claimed"]) for r in rows),
              "largest_first_replan_delay_min": max(delays, default=None),
              "elapsed_s": time.perf_counter() - started, "rows": rows}
    print(json.dumps({k: v for k, v in result.items() if k != "rows"}, indent=2))
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=2, default=str))
    return result


if __name__ == "__main__":
    main()
