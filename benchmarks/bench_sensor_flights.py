"""Sensor faults in flight: when each is claimed, and what it does to the load plan.

The Fig. 7.7 mission (two generators, engineer scheduler, closed loop with detection) flown to a
limit of 88 °C, where the healthy flight peaks near 85 °C: a winding sensor reading a few kelvin
high would make the manager re-plan for nothing. Every case is flown with the same seed as the
healthy flight, so the plant, its noise and the plan are the same until a fault changes them.

Cases:

* ``sensor``: bias ±4 K, drift ±1.5 K/h and stuck on the winding and the iron sensor (generator 1
  or 2), onsets 50-90 min; bias ±3 K and drift 2 K/h of the coolant-inlet sensor, bias -8 and +5 K
  of the ambient sensor (onsets 40-60 min);
* ``physical``: a shorted turn, an end-winding stray loss and a partial coolant blockage (with a
  5-K inlet rise: the inlet readings then disagree for real) on generator 1 from 60 min, no sensor
  fault (no sensor fault may be claimed).

Figures per case: ``claimed`` (sensor and kind claimed), ``claim_delay_min`` (claim time minus the
true onset), ``replans_caused`` (re-plans at times the healthy flight did not re-plan, and the
healthy flight's re-plans missing), ``load_changes`` (management cycles whose applied currents
differ from the healthy flight's by more than 1 mA on any generator) and, for the physical cases,
what was identified, the first re-plan after the onset, the hottest winding and the time above the
limit. Usage: ``python benchmarks/bench_sensor_flights.py [--json FILE] [--only NAME ...]``
(``--only`` flies the healthy flight and the named cases alone, names as :func:`case_name` gives
them, e.g. ``T_winding-drift-1.5-gen2`` or ``phase_short_circuit-gen1``).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

from genthermal.mission import load_mission
from genthermal.resources import SCENARIO_DIR
from genthermal.schedule.flight.closed_loop import fly
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.power_system import PowerSystem
from genthermal.schedule.report import flight_summary

#: Winding limit of the flights, °C (the healthy flight peaks near 85 °C).
LIMIT_C = 88.0
SENSOR_CASES = (
    {"generator": 1, "sensor": "T_winding", "kind": "bias", "onset_min": 60, "value": 4.0},
    {"generator": 1, "sensor": "T_winding", "kind": "bias", "onset_min": 60, "value": -4.0},
    {"generator": 1, "sensor": "T_winding", "kind": "drift", "onset_min": 60, "value": 1.5},
    {"generator": 2, "sensor": "T_winding", "kind": "drift", "onset_min": 70, "value": -1.5},
    {"generator": 1, "sensor": "T_winding", "kind": "stuck", "onset_min": 50},
    {"generator": 2, "sensor": "T_iron", "kind": "bias", "onset_min": 40, "value": -4.0},
    {"generator": 1, "sensor": "T_iron", "kind": "bias", "onset_min": 60, "value": 4.0},
    {"generator": 1, "sensor": "T_iron", "kind": "drift", "onset_min": 90, "value": 1.5},
    {"generator": 2, "sensor": "T_iron", "kind": "drift", "onset_min": 60, "value": -1.5},
    {"generator": 2, "sensor": "T_iron", "kind": "stuck", "onset_min": 80},
    {"generator": 1, "sensor": "T_inlet", "kind": "bias", "onset_min": 60, "value": 3.0},
    {"generator": 2, "sensor": "T_inlet", "kind": "bias", "onset_min": 60, "value": -3.0},
    {"generator": 1, "sensor": "T_inlet", "kind": "drift", "onset_min": 60, "value": 2.0},
    {"generator": 2, "sensor": "T_ambient", "kind": "bias", "onset_min": 40, "value": -8.0},
    {"generator": 1, "sensor": "T_ambient", "kind": "bias", "onset_min": 60, "value": 5.0},
)
PHYSICAL_CASES = (
    {"generator": 1, "kind": "effect", "effect": "phase_short_circuit", "onset_min": 60, "values": {"R_short": 0.3}},
    {"generator": 1, "kind": "effect", "effect": "end_winding_stray_loss", "onset_min": 60,
     "values": {"R_stray": 0.3}},
    {"generator": 1, "kind": "coolant_blockage", "onset_min": 60, "k_flow": 0.6, "inlet_rise_C": 5},
)
#: A cycle's currents differ from the healthy flight's by more than this, A.
LOAD_CHANGE_A = 1e-3


def case_name(entry: dict) -> str:
    """A case's name for ``--only``: sensor, kind, value and unit of a sensor case
    (``T_iron-stuck-gen2``), the effect or kind and unit of a physical one."""
    if "sensor" in entry:
        value = f"{entry['value']:+g}" if "value" in entry else ""
        return f"{entry['sensor']}-{entry['kind']}{value}-gen{entry['generator']}"
    return f"{entry.get('effect', entry['kind'])}-gen{entry['generator']}"


def flight(sensor_faults=(), faults=(), settings: ManagerSettings = ManagerSettings()):
    """Fly the Fig. 7.7 mission at :data:`LIMIT_C` with the given scenario entries."""
    document = yaml.safe_load((SCENARIO_DIR / "thesis_fig_7_7.yaml").read_text())
    document["generators"] = {"limit_C": LIMIT_C}
    if sensor_faults:
        document["sensor_faults"] = list(sensor_faults)
    if faults:
        document["faults"] = list(faults)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "scenario.yaml"
        path.write_text(yaml.safe_dump(document))
        return fly(PowerSystem.from_mission(load_mission(str(path))), "engineer", settings)


def compared(result, healthy, onset_s: float, cycle_s: float) -> dict:
    """Re-plans and load changes of ``result`` that the healthy flight did not make."""
    plans = {round(p["time_s"]) for p in result.plans if p["time_s"] >= onset_s}
    healthy_plans = {round(p["time_s"]) for p in healthy.plans if p["time_s"] >= onset_s}
    n = min(result.currents_A.shape[1], healthy.currents_A.shape[1])
    differs = np.abs(result.currents_A[:, :n] - healthy.currents_A[:, :n]).max(axis=0) > LOAD_CHANGE_A
    steps_per_cycle = max(int(round(cycle_s / float(np.diff(result.time_s[:2])[0]))), 1)
    cycles = {int(i) // steps_per_cycle for i in np.flatnonzero(differs)}
    return {"replans_caused": len(plans ^ healthy_plans), "load_changes": len(cycles)
            + int(result.currents_A.shape[1] != healthy.currents_A.shape[1])}


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="also write the result to this file")
    parser.add_argument("--only", nargs="+", metavar="NAME", help="fly only these cases (and the healthy flight)")
    args = parser.parse_args(argv)
    names = [case_name(entry) for entry in SENSOR_CASES + PHYSICAL_CASES]
    unknown = [name for name in args.only or () if name not in names]
    if unknown:
        parser.error(f"--only {unknown[0]}: no such case; the cases are {', '.join(names)}")
    chosen = set(args.only or names)
    settings, started = ManagerSettings(), time.perf_counter()
    healthy = flight()
    rows = [{"case": "healthy", "replans": len(healthy.plans),
             "claimed": flight_summary(healthy)["sensor_faults"]["claimed"]}]
    for entry in [e for e in SENSOR_CASES if case_name(e) in chosen]:
        result = flight([entry], settings=settings)
        claims = flight_summary(result)["sensor_faults"]["claimed"]
        onset = 60.0 * entry["onset_min"]
        right = [c for c in claims if c["generator"] == f"gen{entry['generator']}" and c["sensor"] == entry["sensor"]]
        rows.append({"case": "sensor", "name": case_name(entry), "injected": entry,
                     "claimed": [(c["generator"], c["sensor"], c["kind"]) for c in claims],
                     "right_sensor": bool(right),
                     "claim_delay_min": (right[0]["claimed_at_s"] - onset) / 60.0 if right else None,
                     **compared(result, healthy, onset, settings.cycle_s)})
        print(json.dumps(rows[-1]), flush=True)
    for entry in [e for e in PHYSICAL_CASES if case_name(e) in chosen]:
        result = flight(faults=[entry], settings=settings)
        summary = flight_summary(result)
        rows.append({"case": "physical", "name": case_name(entry), "fault": entry,
                     "claimed": [(c["generator"], c["sensor"], c["kind"]) for c in summary["sensor_faults"]["claimed"]],
                     "identified": [(i["generator"], i["detected_at_s"], i["effect"]) for i in summary["identified"]],
                     "beliefs_held": summary["sensor_faults"].get("beliefs_held", []),
                     "first_replan_after_onset_min": min((p["time_s"] / 60.0 for p in result.plans
                                                          if p["time_s"] >= 60.0 * entry["onset_min"]), default=None),
                     "max_T_winding_C": float(np.max(result.temperatures_C[:, 0, :])),
                     "s_above_limit": float(np.count_nonzero(result.temperatures_C[:, 0, :] > LIMIT_C)
                                            * settings.dt_s)})
        print(json.dumps(rows[-1]), flush=True)
    sensor_rows = [r for r in rows if r["case"] == "sensor"]
    delays = [r["claim_delay_min"] for r in sensor_rows if r["claim_delay_min"] is not None]
    result = {"sensor_flights": len(sensor_rows),
              "right_sensor": sum(r["right_sensor"] for r in sensor_rows),
              "replans_caused": sum(r["replans_caused"] for r in sensor_rows),
              "load_changes": sum(r["load_changes"] for r in sensor_rows),
              "max_claim_delay_min": max(delays) if delays else None,
              "sensor_claims_on_physical_flights": sum(len(r["claimed"]) for r in rows if r["case"] == "physical"),
              "sensor_claims_on_healthy_flight": len(rows[0]["claimed"]),
              "elapsed_s": time.perf_counter() - started, "rows": rows}
    result["targets"] = {"every_faulty_sensor_named": result["right_sensor"] == result["sensor_flights"],
                         "no_sensor_blamed_on_a_healthy_or_machine_fault_flight":
                             result["sensor_claims_on_physical_flights"] + result["sensor_claims_on_healthy_flight"] == 0}
    print(json.dumps({k: v for k, v in result.items() if k != "rows"}, indent=2))
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=2, default=str))
    return result


if __name__ == "__main__":
    main()
