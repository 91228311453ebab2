"""A warmer coolant-inlet reading in flight: sensor fault held and claimed, real rise confirmed in time.

The Fig. 7.7 mission of ``benchmarks/bench_sensor_flights.py`` (two generators, engineer scheduler,
limit 88 °C, the healthy flight 0.1-0.2 K below its planning limit), flown with several noise seeds:

* ``healthy``: no fault; any inlet hold or claim is a false alarm;
* ``bias``: an inlet PT100 reading high (or low) from an onset; compared with the healthy flight of
  the same seed: ``load_changes`` (management cycles whose currents differ by more than 1 mA) and
  ``replans_caused`` as in ``bench_sensor_flights``, the claim and its delay, the hold;
* ``rise``: the air at gen1's inlet really rises (``inlet_rise``, a step or with a time constant,
  and a partial blockage recirculating 5 K); no sensor may be claimed. Flown twice, with the hold
  (:mod:`genthermal.schedule.monitoring.unconfirmed_inlet`) and without it (``unconfirmed_rise_K`` 0: the
  warmer reading planned at once, the rule before it): the first re-plan after the onset of each,
  how the hold ended (confirmed by the record check, and when), the hottest winding and the time
  above the limit.

Usage: ``python benchmarks/bench_inlet_confirmation.py [--seeds N] [--json FILE]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

import numpy as np

from bench_sensor_flights import LIMIT_C, compared, flight
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.monitoring.input_watch import InputWatchSettings
from genthermal.schedule.report import flight_summary

#: (generator, value K, onset min) of the inlet-sensor biases.
BIASES = ((1, 3.0, 60), (2, 3.0, 90), (1, 5.0, 40), (2, 2.0, 120), (1, 8.0, 60), (2, -3.0, 60))
#: Real inlet rises on gen1 from 60 min: (size K, time constant min, blockage k_flow or None).
RISES = ((2.0, 0.0, None), (3.0, 0.0, None), (5.0, 0.0, None), (8.0, 0.0, None), (16.0, 0.0, None),
         (8.0, 20.0, None), (5.0, 0.0, 0.6))


def _rise_fault(size_K: float, tau_min: float, k_flow) -> dict:
    if k_flow is None:
        return {"generator": 1, "kind": "inlet_rise", "onset_min": 60, "inlet_rise_C": size_K,
                "inlet_rise_tau_min": tau_min}
    return {"generator": 1, "kind": "coolant_blockage", "onset_min": 60, "k_flow": k_flow, "inlet_rise_C": size_K,
            "inlet_rise_tau_min": tau_min}


def _watch(result) -> dict:
    return flight_summary(result)["sensor_faults"]


def _first_replan_min(result, onset_s: float):
    return min((p["time_s"] / 60.0 for p in result.plans if p["time_s"] >= onset_s), default=None)


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3, help="noise seeds 0..N-1 (default 3)")
    parser.add_argument("--json", help="also write the result to this file")
    args = parser.parse_args(argv)
    started, rows = time.perf_counter(), []
    for seed in range(args.seeds):
        settings = ManagerSettings(seed=seed)
        healthy = flight(settings=settings)
        watch = _watch(healthy)
        rows.append({"case": "healthy", "seed": seed, "inlet_holds": len(watch["inlet_readings_unconfirmed"]),
                     "claimed": len(watch["claimed"])})
        print(json.dumps(rows[-1]), flush=True)
        for generator, value, onset_min in BIASES:
            entry = {"generator": generator, "sensor": "T_inlet", "kind": "bias", "onset_min": onset_min,
                     "value": value}
            result = flight([entry], settings=settings)
            watch = _watch(result)
            right = [c for c in watch["claimed"] if c["generator"] == f"gen{generator}" and c["sensor"] == "T_inlet"]
            rows.append({"case": "bias", "seed": seed, "injected": entry, "right_sensor": bool(right),
                         "other_claims": len(watch["claimed"]) - len(right),
                         "claim_delay_min": (right[0]["claimed_at_s"] / 60.0 - onset_min) if right else None,
                         "holds": [(h["generator"], h["since_s"] / 60.0, None if h["until_s"] is None
                                    else h["until_s"] / 60.0, h["ended"]) for h in watch["inlet_readings_unconfirmed"]],
                         **compared(result, healthy, 60.0 * onset_min, settings.cycle_s)})
            print(json.dumps(rows[-1]), flush=True)
    for size_K, tau_min, k_flow in RISES:
        fault = _rise_fault(size_K, tau_min, k_flow)
        row = {"case": "rise", "fault": fault}
        for label, inputs in (("held", InputWatchSettings()), ("not_held", InputWatchSettings(unconfirmed_rise_K=0.0))):
            result = flight(faults=[fault], settings=dataclasses.replace(ManagerSettings(), input_watch=inputs))
            watch = _watch(result)
            row[label] = {"claimed": [(c["generator"], c["sensor"], c["kind"]) for c in watch["claimed"]],
                          "first_replan_min": _first_replan_min(result, 3600.0),
                          "holds": [(h["generator"], h["since_s"] / 60.0, None if h["until_s"] is None
                                     else h["until_s"] / 60.0, h["ended"]) for h in watch["inlet_readings_unconfirmed"]],
                          "identified": [(i["generator"], i["detected_at_s"] / 60.0, i["effect"])
                                         for i in flight_summary(result)["identified"]],
                          "max_T_winding_C": float(np.max(result.temperatures_C[:, 0, :])),
                          "s_above_limit": float(np.count_nonzero(result.temperatures_C[:, 0, :] > LIMIT_C)
                                                 * ManagerSettings().dt_s)}
        rows.append(row)
        print(json.dumps(row), flush=True)
    biases = [r for r in rows if r["case"] == "bias"]
    rises = [r for r in rows if r["case"] == "rise"]
    result = {"healthy_flights": sum(r["case"] == "healthy" for r in rows),
              "false_alarms_on_healthy_flights": sum(r["inlet_holds"] + r["claimed"] for r in rows
                                                     if r["case"] == "healthy"),
              "bias_flights": len(biases), "bias_right_sensor": sum(r["right_sensor"] for r in biases),
              "bias_load_changes": sum(r["load_changes"] for r in biases),
              "bias_replans_caused": sum(r["replans_caused"] for r in biases),
              "max_bias_claim_delay_min": max((r["claim_delay_min"] for r in biases
                                               if r["claim_delay_min"] is not None), default=None),
              "rise_flights": len(rises),
              "rises_claimed_as_sensor": sum(bool(r["held"]["claimed"]) for r in rises),
              "rise_s_above_limit": sum(r["held"]["s_above_limit"] for r in rises),
              "rise_first_replan_delays_min": [None if r["held"]["first_replan_min"] is None
                                               or r["not_held"]["first_replan_min"] is None
                                               else r["held"]["first_replan_min"] - r["not_held"]["first_replan_min"]
                                               for r in rises],
              "elapsed_s": time.perf_counter() - started, "rows": rows}
    print(json.dumps({k: v for k, v in result.items() if k != "rows"}, indent=2))
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=2, default=str))
    return result


if __name__ == "__main__":
    main()
