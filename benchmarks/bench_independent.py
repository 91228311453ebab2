"""Score ``genthermal diagnose DATA --baseline healthy_baseline.csv --iterate`` on the independent records.

Runs the command-line diagnosis (``genthermal.cli.main`` in a fresh process per record) on every
record of ``../shared/records/independent_batch1/`` (or ``--records``) and scores its JSON against
the record's truth file:

* ``verdict``: ``right`` (the machine effects claimed are the true ones, mapped to genthermal's
  names, and no sensor is blamed; for a single-effect record, one effect claimed with a flagged
  look-alike that contains the true one counts too; for the stretch records, "not explained by
  the catalogue" with an open-search term in the right node group (:data:`STRETCH_GROUPS`) and no
  confident catalogue verdict, a flagged look-alike or a nearest catalogue effect (claim
  confidence ``nearest``) being none; for the control record without
  the copper resistance rise, no catalogue or sensor claim), ``partly`` (some true effect named or
  flagged, or a healthy record with only an "unexplained" flag), ``wrong``;
* ``false_claims``: claims (machine effects or sensor faults; on a record without an effect also
  open-search terms) that are not in the truth;
* ``onset_error_min``: per true effect with an onset after the start, |fitted - true| onset, min
  (of the claimed effect when the true one is its flagged look-alike);
* ``rmse_over_floor``: the RMSE after the found effects over the discrepancy floor of the error
  model (``residual.floor_K`` of the JSON);
* ``wall_s``: wall time of the command (the machine may be shared: see ``load_avg``); ``cpu_s``:
  its CPU time (user + system, with its worker processes), which the load does not change.

``--faults`` adds ``healthy_mission_B`` with each sensor fault of :data:`INJECTED_FAULTS` injected
(right: that sensor blamed, no machine effect). ``--plants K`` adds K healthy records of genthermal's own nonlinear model with its convection,
flow, losses, conductivities and heat capacities 10-30 % off, each diagnosed with its own healthy
baseline (any claim on them is false).

Usage: ``python benchmarks/bench_independent.py [--records NAME ...] [--plants K] [--workers N]
[--jobs J] [--out FILE]``. ``--workers`` is passed to ``diagnose`` (processes per record), ``--jobs`` records
run side by side. Prints one JSON line per record, then a summary line (``"summary": true``).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RECORDS = ROOT / ".." / "shared" / "records" / "independent_batch1"
#: Effect names of the independent implementation -> genthermal catalogue names.
EFFECT_NAMES = {"coolant_blockage": "coolant_flow_reduction", "inter_turn_short": "phase_short_circuit",
                "end_winding_stray_loss": "end_winding_stray_loss", "excitation_iron_loss": "excitation_iron_loss",
                "insulation_degradation": "winding_insulation_degradation",
                "fan_flow_reduction": "coolant_flow_reduction", "frame_radiation": "frame_cooling_change"}
#: Open-search terms in the right node group for the stretch records (prefixes of the term names of
#: :func:`genthermal.diagnose.open_search.heat_flow_library`): a flow-dependent convection is a
#: change of the air streams or the internal convection, a phase-resolved short a heat flow into
#: the slot winding (of every surface or of one, ``conductance_internal_convection_h_top_air``).
STRETCH_GROUPS = {"stretch_a_blockage_flow_dependent_h": ("conductance_air_streams", "conductance_internal_convection"),
                  "stretch_d_short_phase_resolved": ("heat_I_w2_slot_winding", "heat_I2_slot_winding",
                                                     "heat_I_u2_slot_winding", "heat_I_v2_slot_winding")}
#: Healthy and load-only records: the false-claim set (the baseline itself is the calibration record).
#: Folder the diagnose JSON documents are kept in (``--keep``), or None.
KEEP = None
NO_CLAIM_CATEGORIES = ("healthy", "step", "varying", "plant")


def expected_effects(truth: dict) -> set:
    """genthermal names of the effects the model lacks in ``truth`` (the copper resistance rise is
    part of genthermal's model already, so effect_b and control_b expect no catalogue effect)."""
    return {EFFECT_NAMES[e["name"]] for e in truth["effects"] if e["name"] in EFFECT_NAMES}


def claims_of(document: dict) -> dict:
    """Machine effects, sensor faults and 'unexplained' of a diagnose JSON document."""
    machine = [f["effect"] for f in document.get("found", [])]
    sensors = [f.get("sensor", f.get("text", "")) for f in document.get("sensor_faults", [])
               if f.get("claimed", True)]
    lookalike = None
    if document.get("experiment"):
        lookalike = document["experiment"].get("explanations") or document["experiment"].get("candidates")
    nearest = [c["effect"] for c in document.get("claims", [])
               if c.get("kind") == "machine_effect" and c.get("confidence") == "nearest"]
    return {"machine": machine, "nearest": nearest, "sensors": sensors, "unexplained": bool(document.get("unexplained")),
            "open_terms": [t.get("term", t.get("name")) for t in document.get("open_search", {}).get("terms", [])]
            if isinstance(document.get("open_search"), dict) else [],
            "lookalike": lookalike}


def _lookalike_names(lookalike) -> set:
    names = set()
    if isinstance(lookalike, dict):
        lookalike = list(lookalike.values())
    for item in lookalike or []:
        if isinstance(item, str):
            names.update(item.split(" + "))
        elif isinstance(item, (list, tuple)):
            names.update(str(x) for x in item)
        elif isinstance(item, dict):
            names.update(item)
    return names


def score(name: str, truth: dict, document: dict) -> dict:
    """Score one record's diagnosis against its truth (module docstring)."""
    expected = expected_effects(truth)
    claims = claims_of(document)
    machine, sensors = set(claims["machine"]), claims["sensors"]
    category = truth["category"]
    false_claims = sorted(machine - expected) + sensors
    lookalike = _lookalike_names(claims["lookalike"])
    if category == "stretch":
        nearest = expected
        flagged = (machine & lookalike if lookalike else set()) | set(claims["nearest"])
        confident = machine - flagged
        right_group = any(t.startswith(STRETCH_GROUPS.get(name, ("-",))) for t in claims["open_terms"])
        if claims["unexplained"] and right_group and not confident and not sensors:
            verdict = "right"
        elif (machine | lookalike) & nearest and not sensors:
            verdict = "partly"
        else:
            verdict = "wrong"
        false_claims = sorted(confident - nearest) + sensors
    elif category == "control":
        # the record lacks what the model has (the copper resistance rise): no catalogue effect can
        # remove it, an open-search term may describe it
        verdict = "right" if not machine and not sensors else "wrong"
    elif not expected:
        false_claims += [f"open search: {t}" for t in claims["open_terms"]]
        if not machine and not sensors and not claims["open_terms"]:
            verdict = "right" if not claims["unexplained"] or category == "control" else "partly"
        else:
            verdict = "wrong"
    elif machine == expected and not sensors:
        verdict = "right"
    elif len(expected) == 1 and len(machine) == 1 and expected <= lookalike and machine <= lookalike and not sensors:
        verdict = "right"
        false_claims = sensors
    elif machine & expected:
        verdict = "partly"
    else:
        verdict = "wrong"
    onset_error = {}
    found = {f["effect"]: f for f in document.get("found", [])}
    for effect in truth["effects"]:
        mapped = EFFECT_NAMES.get(effect["name"])
        # a true effect flagged as the look-alike of the claimed one: the claimed one's onset
        stand_in = mapped if mapped in found else next(
            (f for f in found if mapped in lookalike and f in lookalike and len(found) == 1), None)
        if stand_in is not None and effect.get("onset_s"):
            onset_error[mapped] = abs(found[stand_in]["onset_s"] - float(effect["onset_s"])) / 60.0
    residual = document.get("residual", {})
    floor = residual.get("floor_K")
    rmse = document.get("rmse_final")
    return {"record": name, "category": category, "expected": sorted(expected), "verdict": verdict,
            "claimed_machine": sorted(machine), "claimed_sensors": sensors, "unexplained": claims["unexplained"],
            "open_terms": claims["open_terms"], "lookalike": sorted(lookalike), "false_claims": false_claims, "n_false_claims": len(false_claims),
            "onset_error_min": onset_error, "rmse_after_K": rmse, "floor_K": floor,
            "rmse_over_floor": (rmse / floor) if (rmse is not None and floor) else None}


def diagnose_command(data: Path, out: Path, workers: int) -> tuple:
    """The command line a user runs on ``data`` (the shared healthy baseline, ``--iterate``, JSON to
    ``out``) and its environment (this source tree first on the path)."""
    command = [sys.executable, "-m", "genthermal.cli", "diagnose", str(data), "--baseline",
               str(RECORDS / "data" / "healthy_baseline.csv"), "--iterate", "--json", str(out),
               "--workers", str(workers)]
    return command, dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))


def timed_run(command, env, timeout_s: float) -> tuple:
    """Run ``command``; (return code or None on timeout, stderr text, wall s, CPU s of the process
    and its children: user + system, from ``os.wait4``, so side-by-side records are told apart)."""
    with tempfile.TemporaryFile("w+") as stderr:
        start = time.perf_counter()
        process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=stderr, text=True, env=env)
        timer = threading.Timer(timeout_s, process.kill)
        timer.start()
        try:
            _, status, usage = os.wait4(process.pid, 0)
        finally:
            timer.cancel()
        wall = time.perf_counter() - start
        process.returncode = os.waitstatus_to_exitcode(status)
        stderr.seek(0)
        text = stderr.read()
    code = None if wall >= timeout_s and process.returncode < 0 else process.returncode
    return code, text, wall, usage.ru_utime + usage.ru_stime


def _failed(name: str, category: str, code, text: str, wall: float, cpu: float) -> dict:
    error = "timeout" if code is None else (text.strip().splitlines() or ["no output"])[-1]
    return {"record": name, "category": category, "verdict": "wrong", "wall_s": round(wall, 1),
            "cpu_s": round(cpu, 1), "error": error}


def run_record(name: str, workers: int, timeout_s: float) -> dict:
    """Run the CLI on one record in a fresh process; its JSON scored (``error`` when it failed)."""
    data = RECORDS / "data" / f"{name}.csv"
    truth = json.loads((RECORDS / "truth" / f"{name}.json").read_text())
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "diagnosis.json"
        command, env = diagnose_command(data, out, workers)
        code, text, wall, cpu = timed_run(command, env, timeout_s)
        if code != 0 or not out.exists():
            return _failed(name, truth["category"], code, text, wall, cpu)
        document = json.loads(out.read_text())
        if KEEP is not None:
            (KEEP / f"{name}.json").write_text(out.read_text())
    result = score(name, truth, document)
    result["wall_s"], result["cpu_s"] = round(wall, 1), round(cpu, 1)
    result["duration_h"] = truth["summary"]["duration_s"] / 3600.0
    result["load_avg"] = round(os.getloadavg()[0], 2)
    return result


#: Parameters of genthermal's own plants drawn 10-30 % off the model (``--plants``): the uncertain
#: convection, flow, losses and conductivities, of which the baseline calibrates only some.
PLANT_PARAMETERS = ("h_ambient", "h_top_air", "h_end_air", "h_air_gap", "m_dot_fan", "air_gap_flow_share", "R0",
                    "P_iron", "k_cr", "k_sa", "k_l", "c_steel", "c_copper")


def make_plant_records(index: int, folder: Path) -> tuple[Path, Path, dict]:
    """A healthy baseline and a healthy test record of genthermal's nonlinear model with every
    :data:`PLANT_PARAMETERS` 10-30 % off (random sign and size, seed ``index``), driven by the
    inputs of ``healthy_baseline`` and ``healthy_mission_B``: (baseline CSV, record CSV, the
    factors)."""
    import numpy as np
    import pandas as pd

    from genthermal.machines import build_model
    from genthermal.synth import synthesize

    rng = np.random.default_rng(1000 + index)
    model = build_model()
    factors = {n: float(1 + rng.choice([-1, 1]) * rng.uniform(0.1, 0.3)) for n in PLANT_PARAMETERS
               if n in model.parameters}
    plant = model.with_parameters(source=f"bench_independent plant {index}",
                                  **{n: model.parameters.value(n) * f for n, f in factors.items()})
    paths = []
    for k, name in enumerate(("healthy_baseline", "healthy_mission_B")):
        frame = pd.read_csv(RECORDS / "data" / f"{name}.csv")
        inputs = frame[["time_s", *[c for c in frame.columns if c.startswith("I_")], "T_inlet", "T_ambient"]]
        inputs = inputs.iloc[::5].reset_index(drop=True)  # 10 s
        record = synthesize(plant, inputs, seed=10 * index + k)
        path = folder / f"plant{index}_{name}.csv"
        record.to_csv(path, index=False)
        paths.append(path)
    return paths[0], paths[1], factors


def run_plant(index: int, workers: int, timeout_s: float) -> dict:
    """Diagnose a healthy record of one of genthermal's own plants 10-30 % off, with its own healthy
    baseline: any claim is a false one."""
    with tempfile.TemporaryDirectory() as folder:
        baseline, data, factors = make_plant_records(index, Path(folder))
        out = Path(folder) / "diagnosis.json"
        command = [sys.executable, "-m", "genthermal.cli", "diagnose", str(data), "--baseline", str(baseline),
                   "--iterate", "--json", str(out), "--workers", str(workers)]
        env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
        code, text, wall, cpu = timed_run(command, env, timeout_s)
        name = f"plant_{index}_healthy"
        if code != 0 or not out.exists():
            return _failed(name, "plant", code, text, wall, cpu)
        document = json.loads(out.read_text())
    truth = {"category": "plant", "effects": []}
    result = score(name, truth, document)
    result.update(wall_s=round(wall, 1), cpu_s=round(cpu, 1), duration_h=document["samples"] * document["dt_s"] / 3600.0,
                  plant_factors=factors, load_avg=round(os.getloadavg()[0], 2))
    return result


#: Sensor faults injected into ``healthy_mission_B`` (``--faults``): (sensor, kind, value, onset s).
INJECTED_FAULTS = (("T_iron", "drift", 1.6, 5400.0), ("T_winding_v", "bias", 2.5, 4300.0),
                   ("T_inlet", "bias", 3.0, 7200.0), ("T_ambient", "drift", -2.0, 3600.0),
                   ("T_outlet", "stuck", 0.0, 7900.0))


def run_fault(index: int, workers: int, timeout_s: float) -> dict:
    """Diagnose ``healthy_mission_B`` with one sensor fault of :data:`INJECTED_FAULTS` injected:
    right when that sensor is blamed and no machine effect is claimed."""
    import pandas as pd

    from genthermal.sensor_faults import SensorFault, inject_sensor_faults

    sensor, kind, value, onset = INJECTED_FAULTS[index]
    fault = SensorFault(sensor, kind, value, onset)
    name = f"healthy_mission_B+{sensor}_{kind}"
    with tempfile.TemporaryDirectory() as folder:
        data = Path(folder) / "record.csv"
        inject_sensor_faults(pd.read_csv(RECORDS / "data" / "healthy_mission_B.csv"), [fault]).to_csv(data, index=False)
        out = Path(folder) / "diagnosis.json"
        command, env = diagnose_command(data, out, workers)
        code, text, wall, cpu = timed_run(command, env, timeout_s)
        if code != 0 or not out.exists():
            return _failed(name, "sensor_fault", code, text, wall, cpu)
        document = json.loads(out.read_text())
    claims = claims_of(document)
    blamed = claims["sensors"]
    right_sensor = any(b == sensor for b in blamed)
    others = [b for b in blamed if b != sensor]
    verdict = "right" if right_sensor and not claims["machine"] and not others else \
        "partly" if right_sensor else "wrong"
    return {"record": name, "category": "sensor_fault", "injected": fault.describe(), "verdict": verdict,
            "claimed_machine": claims["machine"], "claimed_sensors": blamed,
            "false_claims": claims["machine"] + others, "n_false_claims": len(claims["machine"]) + len(others),
            "rmse_after_K": document.get("rmse_final"), "floor_K": document.get("residual", {}).get("floor_K"),
            "wall_s": round(wall, 1), "cpu_s": round(cpu, 1), "duration_h": document["samples"] * document["dt_s"] / 3600.0,
            "load_avg": round(os.getloadavg()[0], 2)}


def summary(results: list) -> dict:
    """Counts over the records: verdicts, false claims on the no-claim set, onset and RMSE figures."""
    verdicts = {k: sum(r["verdict"] == k for r in results) for k in ("right", "partly", "wrong")}
    no_claim = [r for r in results if r.get("category") in NO_CLAIM_CATEGORIES]
    onset = [v for r in results for v in r.get("onset_error_min", {}).values()]
    ratios = [r["rmse_over_floor"] for r in results if r.get("rmse_over_floor") is not None]
    per_hour = [r["wall_s"] / r["duration_h"] * 4 for r in results if "duration_h" in r]
    cpu_per_hour = [r["cpu_s"] / r["duration_h"] * 4 for r in results if "duration_h" in r and "cpu_s" in r]
    return {"summary": True, "records": len(results), **verdicts,
            "claims_on_healthy_and_load_only": sum(r.get("n_false_claims", 1) for r in no_claim),
            "healthy_and_load_only_records": len(no_claim),
            "false_claims_total": sum(r.get("n_false_claims", 0) for r in results),
            "onset_error_min_max": max(onset) if onset else None,
            "onsets_within_10_min": sum(v <= 10 for v in onset), "onsets_scored": len(onset),
            "rmse_over_floor_max": max(ratios) if ratios else None,
            "wall_s_per_4h_max": max(per_hour) if per_hour else None,
            "cpu_s_per_4h_max": max(cpu_per_hour) if cpu_per_hour else None,
            "wall_s_total": round(sum(r.get("wall_s", 0) for r in results), 1)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", nargs="*", help="record names (default: all of independent_batch1; "
                        "none with an empty list, to run only --plants or --faults)")
    parser.add_argument("--workers", type=int, default=1, help="diagnose --workers (default 1)")
    parser.add_argument("--jobs", type=int, default=1, help="records run side by side (default 1)")
    parser.add_argument("--timeout", type=float, default=1800.0, help="seconds per record before it is failed")
    parser.add_argument("--out", help="also write the JSON lines to this file")
    parser.add_argument("--keep", metavar="DIR", help="keep each record's diagnose JSON in DIR")
    parser.add_argument("--faults", action="store_true",
                        help="also diagnose healthy_mission_B with each sensor fault of INJECTED_FAULTS injected")
    parser.add_argument("--plants", type=int, default=0,
                        help="also diagnose this many healthy records of genthermal plants 10-30 %% off")
    args = parser.parse_args(argv)
    global KEEP
    KEEP = None if args.keep is None else Path(args.keep)
    if KEEP is not None:
        KEEP.mkdir(parents=True, exist_ok=True)
    if not RECORDS.is_dir():
        print(json.dumps({"error": f"records not found: {RECORDS.resolve()}"}))
        return 2
    names = sorted(p.stem for p in (RECORDS / "data").glob("*.csv")) if args.records is None else args.records
    unknown = [n for n in names if not (RECORDS / "data" / f"{n}.csv").exists()]
    if unknown:
        print(json.dumps({"error": f"unknown record {unknown[0]}"}))
        return 2
    lines = []
    tasks = ([(run_record, n) for n in names] + [(run_plant, k) for k in range(args.plants)]
             + [(run_fault, k) for k in range(len(INJECTED_FAULTS) if args.faults else 0)])
    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        for result in pool.map(lambda task: task[0](task[1], args.workers, args.timeout), tasks):
            line = json.dumps(result)
            print(line, flush=True)
            lines.append(result)
    total = json.dumps(summary(lines))
    print(total, flush=True)
    if args.out:
        Path(args.out).write_text("\n".join([*map(json.dumps, lines), total]) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
