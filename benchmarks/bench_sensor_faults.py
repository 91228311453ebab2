"""Sensor faults against machine effects: how often ``diagnose`` names the faulty sensor, and how
often it blames a sensor for the machine.

Cases (4-h records of the thesis generator, Fig. 7.7 mission, 10 s samples, the rig's noise):

* ``sensor``: every sensor kind of the record (the three winding phases and the iron) × bias,
  drift and stuck × ``--seeds`` seeds on a healthy machine; the size is drawn from a seeded
  generator (bias ±1-3 K, drift ±0.8-2 K/h, stuck: the reading at the onset is held) and the onset
  uniformly in 25-60 % of the record;
* ``input``: the coolant-inlet and ambient sensors (model inputs) × bias and drift × seeds, same
  sizes and onsets (a stuck input is not a case: the records log inputs without noise, so a
  constant reading is what a healthy one looks like);
* ``healthy``: healthy records, one per seed;
* ``physical``: every catalogue effect (random values and onset, :mod:`genthermal.diagnose.hidden`),
  no sensor fault.

Plants (``--plant``): ``model`` (default) records the model's own plant, and the physical cases are
diagnosed on the plant they came from; ``rig`` records ``scenarios/data/rig_plant.yaml`` (four
parameters off by 20-30 %, an excitation iron loss the model lacks) and diagnoses every case on
the built-in model, as a record of a real machine would be. Catalogue effects the rig plant cannot
take (the two that need the linear design model) are left out of its physical cases.

Figures: ``right_sensor_fraction`` (the sensor claimed is the faulty one, over the sensor cases;
``input_right_sensor_fraction`` over the input cases, ``by_sensor`` per sensor),
``right_kind_fraction``, ``false_sensor_claims`` (any sensor fault claimed on a healthy or physical
case), ``physical_verdict_kept`` (physical cases whose verdict is still the injected effect) and the
elapsed seconds; ``physical_sensor_claims`` counts the sensor faults claimed on physical cases
alone. Usage: ``python benchmarks/bench_sensor_faults.py [--seeds 2] [--plant model|rig]
[--json FILE]``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from genthermal.diagnose.discover import diagnose
from genthermal.diagnose.discovery import Discovery
from genthermal.diagnose.fitter import OnsetFitter
from genthermal.diagnose.hidden import make_hidden_effect_case
from genthermal.effects import CATALOGUE
from genthermal.machines import build_model
from genthermal.model_file import load_model
from genthermal.sensor_faults import SensorFault, inject_sensor_faults

#: The plant that differs from the model (parameters off by 20-30 %, a missing effect).
RIG_PLANT_FILE = Path(__file__).resolve().parent.parent / "scenarios" / "data" / "rig_plant.yaml"

SENSORS = ("T_winding_u", "T_winding_v", "T_winding_w", "T_iron")
KINDS = ("bias", "drift", "stuck")
INPUT_SENSORS = ("T_inlet", "T_ambient")
INPUT_KINDS = ("bias", "drift")
#: Magnitude ranges of the drawn faults (bias K, drift K/h).
SIZES = {"bias": (1.0, 3.0), "drift": (0.8, 2.0)}
ONSET_SHARE = (0.25, 0.60)


def drawn_fault(sensor: str, kind: str, duration_s: float, rng: np.random.Generator) -> SensorFault:
    """A fault of ``kind`` on ``sensor`` with a seeded size and onset (module docstring)."""
    value = 0.0 if kind == "stuck" else float(rng.choice((-1.0, 1.0)) * rng.uniform(*SIZES[kind]))
    return SensorFault(sensor, kind, value, float(rng.uniform(*ONSET_SHARE) * duration_s))


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=2, help="seeds of the sensor and healthy cases")
    parser.add_argument("--plant", choices=("model", "rig"), default="model",
                        help="records of the model's own plant, or of the rig plant that differs from it")
    parser.add_argument("--json", help="also write the result to this file")
    args = parser.parse_args(argv)
    model, started = build_model(), time.perf_counter()
    rig = load_model(RIG_PLANT_FILE) if args.plant == "rig" else None
    discovery = Discovery(fitter=OnsetFitter(pairs=False), design_experiment=False)
    rows = []
    for seed in range(args.seeds):
        healthy = make_hidden_effect_case(None, seed=100 + seed, plant=rig).data
        duration = float(healthy["time_s"].iloc[-1] - healthy["time_s"].iloc[0])
        rng = np.random.default_rng(seed)
        result = discovery.fit(model, healthy)
        rows.append({"case": "healthy", "seed": seed, "claimed": [h.fault.to_dict() for h in result.sensor_faults],
                     "verdict": result.verdict})
        cases = [("sensor", s, k) for s in SENSORS for k in KINDS] + \
            [("input", s, k) for s in INPUT_SENSORS for k in INPUT_KINDS]
        for case, sensor, kind in cases:
            fault = drawn_fault(sensor, kind, duration, rng)
            data = inject_sensor_faults(healthy, [fault], seed=seed)
            result = discovery.fit(model, data)
            rows.append({"case": case, "seed": seed, "injected": fault.to_dict(),
                         "claimed": [h.fault.to_dict() for h in result.sensor_faults], "verdict": result.verdict})
            print(json.dumps({"injected": fault.describe(), "claimed": [c["text"] for c in rows[-1]["claimed"]],
                              "verdict": result.verdict}, ensure_ascii=False), flush=True)
    for effect in CATALOGUE:
        if rig is not None and CATALOGUE[effect].unavailable_reason(rig) is not None:
            continue
        case = make_hidden_effect_case(effect, seed=5, plant=rig)
        result = diagnose(case.plant if rig is None else model, case.data, pairs=False, design_experiment=False)
        rows.append({"case": "physical", "effect": effect, "claimed": [h.fault.to_dict() for h in result.sensor_faults],
                     "verdict": result.verdict})
        print(json.dumps({"effect": effect, "claimed": [c["text"] for c in rows[-1]["claimed"]],
                          "verdict": result.verdict}, ensure_ascii=False), flush=True)
    def right(row):
        return any(c["sensor"] == row["injected"]["sensor"] for c in row["claimed"])

    sensor_rows = [r for r in rows if r["case"] == "sensor"]
    input_rows = [r for r in rows if r["case"] == "input"]
    right_sensor = [right(r) for r in sensor_rows]
    by_sensor = {name: f"{sum(right(r) for r in rows if r.get('injected', {}).get('sensor') == name)}/"
                       f"{sum(1 for r in rows if r.get('injected', {}).get('sensor') == name)}"
                 for name in (*SENSORS, *INPUT_SENSORS)}
    right_kind = [any(c["sensor"] == r["injected"]["sensor"] and c["kind"] == r["injected"]["kind"]
                      for c in r["claimed"]) for r in sensor_rows]
    innocent = [r for r in rows if r["case"] in ("healthy", "physical")]
    physical = [r for r in rows if r["case"] == "physical"]
    summary = {"plant": args.plant, "cases": len(rows), "sensor_cases": len(sensor_rows),
               "right_sensor_fraction": float(np.mean(right_sensor)), "right_kind_fraction": float(np.mean(right_kind)),
               "input_cases": len(input_rows),
               "input_right_sensor_fraction": float(np.mean([right(r) for r in input_rows])) if input_rows else None,
               "by_sensor": by_sensor,
               "wrong_sensor_claims": sum(1 for r in sensor_rows + input_rows for c in r["claimed"]
                                          if c["sensor"] != r["injected"]["sensor"]),
               "false_sensor_claims": sum(len(r["claimed"]) for r in innocent),
               "physical_sensor_claims": sum(len(r["claimed"]) for r in physical),
               "healthy_or_physical_cases": len(innocent),
               "physical_verdict_kept": sum(1 for r in physical if r["effect"] in r["verdict"].split(" + ")),
               "physical_cases": len(physical), "elapsed_s": time.perf_counter() - started, "rows": rows}
    print(json.dumps({k: v for k, v in summary.items() if k != "rows"}, indent=2))
    if args.json:
        Path(args.json).write_text(json.dumps(summary, indent=2, ensure_ascii=False))
    return summary


if __name__ == "__main__":
    main()
