"""Sensor faults on records made in conditions the sensor screen was not built on.

Every (sensor kind, fault kind) pair — a winding phase (which one drawn per case), the iron,
the cooling-air outlet, the inlet and the ambient × bias, drift, stuck, gain and noise
(:mod:`sensor_robustness_records`) — is one case on a record whose plant, sampling period,
duration, noise and input noise are drawn from a seeded generator; plus healthy records and every catalogue effect the plant can take, on both
plants (these must claim no sensor). Every case is diagnosed blind on the built-in model
(:class:`~genthermal.diagnose.discovery.Discovery`, single effects, no experiment design).

Seed sets: ``train`` (seeds from 0) is the set looked at while the screens were changed;
``holdout`` (seeds from 1000) was only run to report. A 1-s record is at most
:data:`MAX_ONE_SECOND_H` long and is diagnosed on a :data:`DIAGNOSIS_DT_S` grid (``dt_s`` of
:meth:`~genthermal.diagnose.discovery.Discovery.fit`, linear interpolation of the readings): at
its own 1-s grid one record cost 220-410 s on the shared 2-core machine (70 of them a set).

Figures: right sensor (a claim names the faulty sensor) and right kind, tallied per plant,
sampling period, sensor and kind; wrong-sensor claims on the fault cases; false claims (any sensor
fault claimed on a healthy or physical record); elapsed seconds. Usage::

    python benchmarks/bench_sensor_robustness.py --set train|holdout [--repeats 1]
        [--only SENSOR_KIND:KIND|SEED ...] [--json FILE]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from sensor_robustness_records import (KINDS, PLANTS, draw_conditions, effects_for, faulty_record,  # noqa: E402
                                       make_record)

from genthermal.diagnose.discovery import Discovery  # noqa: E402
from genthermal.diagnose.fitter import OnsetFitter  # noqa: E402
from genthermal.machines import build_model  # noqa: E402

SEED_BASE = {"train": 0, "holdout": 1000}
#: Longest 1-s record, h (run time; the longer periods take the full 2-6 h).
MAX_ONE_SECOND_H = 2.0
#: Sensor kinds of the fault cases; "phase" is one winding phase sensor, drawn per case.
SENSOR_KINDS = ("phase", "T_iron", "T_outlet", "T_inlet", "T_ambient")
PHASES = ("T_winding_u", "T_winding_v", "T_winding_w")
#: Diagnosis grid of records sampled faster, s (the fastest winding mode of the thesis model is 6.5 min).
DIAGNOSIS_DT_S = 10.0
#: Healthy records per plant.
HEALTHY_PER_PLANT = 2


def conditions_for(seed: int, plant: str | None = None):
    """The drawn conditions of case ``seed`` (a 1-s record shortened to :data:`MAX_ONE_SECOND_H`)."""
    conditions = draw_conditions(np.random.default_rng(seed), seed)
    if plant is not None:
        conditions = dataclasses.replace(conditions, plant=plant)
    if conditions.dt_s == 1.0:
        conditions = dataclasses.replace(conditions, duration_h=min(conditions.duration_h, MAX_ONE_SECOND_H))
    return conditions


def planned_cases(seed_set: str, repeats: int, only=()):
    """(case, seed, sensor/effect, kind, plant) of a seed set, in run order."""
    base, cases, index = SEED_BASE[seed_set], [], 0
    for _ in range(repeats):
        for sensor_kind in SENSOR_KINDS:
            for kind in KINDS:
                sensor = PHASES[(base + index) % 3] if sensor_kind == "phase" else sensor_kind
                if not only or f"{sensor_kind}:{kind}" in only or f"{base + index}" in only:
                    cases.append(("sensor", base + index, sensor, kind, None))
                index += 1
    if only:
        return cases
    for plant in PLANTS:
        for _ in range(HEALTHY_PER_PLANT):
            cases.append(("healthy", base + index, None, None, plant))
            index += 1
        for effect in effects_for(plant):
            cases.append(("physical", base + index, effect, None, plant))
            index += 1
    return cases


def run_case(discovery, model, case, seed, name, kind, plant) -> dict:
    """Diagnose one planned case (:func:`planned_cases`); its JSON row with the elapsed seconds."""
    conditions = conditions_for(seed, plant)
    started = time.perf_counter()
    if case == "sensor":
        record, fault = faulty_record(conditions, name, kind)
        row = {"injected": fault.to_dict()}
    else:
        record, truth = make_record(conditions, name if case == "physical" else None)
        row = {"effect": name, "truth": truth}
    result = discovery.fit(model, record, dt_s=DIAGNOSIS_DT_S if conditions.dt_s < DIAGNOSIS_DT_S else None)
    return {"case": case, **row, "conditions": conditions.to_dict(),
            "claimed": [h.to_dict() for h in result.sensor_faults], "verdict": result.verdict,
            "elapsed_s": time.perf_counter() - started}


def right_sensor(row) -> bool:
    """A claim of the fault case ``row`` names the faulty sensor."""
    return any(c["sensor"] == row["injected"]["sensor"] for c in row["claimed"])


def right_kind(row) -> bool:
    """A claim of the fault case ``row`` names the faulty sensor and the fault's kind."""
    return any(c["sensor"] == row["injected"]["sensor"] and c["kind"] == row["injected"]["kind"]
               for c in row["claimed"])


def tally(rows, key) -> dict:
    """``key(row)`` → "right sensor / cases" over the fault cases."""
    counts = defaultdict(lambda: [0, 0])
    for row in rows:
        counts[key(row)][0] += right_sensor(row)
        counts[key(row)][1] += 1
    return {str(k): f"{v[0]}/{v[1]}" for k, v in sorted(counts.items(), key=lambda item: str(item[0]))}


def summarize(rows, seed_set: str, elapsed_s: float) -> dict:
    """The figures of the module docstring over ``rows``."""
    faults = [r for r in rows if r["case"] == "sensor"]
    innocent = [r for r in rows if r["case"] in ("healthy", "physical")]
    return {
        "set": seed_set, "cases": len(rows), "fault_cases": len(faults),
        "right_sensor": f"{sum(map(right_sensor, faults))}/{len(faults)}",
        "right_kind": f"{sum(map(right_kind, faults))}/{len(faults)}",
        "by_plant": tally(faults, lambda r: r["conditions"]["plant"]),
        "by_sampling_s": tally(faults, lambda r: r["conditions"]["dt_s"]),
        "by_sensor": tally(faults, lambda r: r["injected"]["sensor"]),
        "by_kind": tally(faults, lambda r: r["injected"]["kind"]),
        "by_sensor_and_kind": tally(faults, lambda r: f'{r["injected"]["sensor"]}:{r["injected"]["kind"]}'),
        "by_input_noise": tally(faults, lambda r: r["conditions"]["input_noise"]),
        "wrong_sensor_claims": sum(1 for r in faults for c in r["claimed"] if c["sensor"] != r["injected"]["sensor"]),
        "healthy_or_physical_cases": len(innocent),
        "false_sensor_claims": sum(len(r["claimed"]) for r in innocent),
        "false_claims": [{"case": r["case"], "effect": r["effect"], "plant": r["conditions"]["plant"],
                          "claimed": [c["text"] for c in r["claimed"]]} for r in innocent if r["claimed"]],
        "missed": [{"injected": r["injected"]["text"], "conditions": r["conditions"],
                    "claimed": [c["text"] for c in r["claimed"]]} for r in faults if not right_sensor(r)],
        "elapsed_s": elapsed_s,
    }


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--set", choices=tuple(SEED_BASE), default="train", dest="seed_set")
    parser.add_argument("--repeats", type=int, default=1, help="passes over every (sensor, kind) pair")
    parser.add_argument("--only", nargs="*", default=(),
                        help="fault cases to run alone: SENSOR_KIND:KIND (phase, T_iron, ...) or a case seed")
    parser.add_argument("--json", help="also write the summary and rows to this file")
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error(f"--repeats must be >= 1, got {args.repeats}")
    model, started = build_model(), time.perf_counter()
    discovery = Discovery(fitter=OnsetFitter(pairs=False), design_experiment=False)
    rows = []
    for planned in planned_cases(args.seed_set, args.repeats, set(args.only)):
        rows.append(run_case(discovery, model, *planned))
        row = rows[-1]
        print(json.dumps({"case": row["case"], "seed": row["conditions"]["seed"],
                          "what": row["injected"]["text"] if row["case"] == "sensor" else row["effect"],
                          "conditions": row["conditions"], "claimed": [c["text"] for c in row["claimed"]],
                          "verdict": row["verdict"], "s": round(row["elapsed_s"], 1)}, ensure_ascii=False), flush=True)
    summary = summarize(rows, args.seed_set, time.perf_counter() - started)
    print(json.dumps(summary, indent=2, ensure_ascii=False))
    if args.json:
        Path(args.json).write_text(json.dumps({**summary, "rows": rows}, indent=2, ensure_ascii=False, default=str))
    return summary


if __name__ == "__main__":
    main()
