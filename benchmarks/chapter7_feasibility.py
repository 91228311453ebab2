"""Can one calibration meet every chapter-7 outcome of the thesis? Minimax feasibility study (JSON).

    python3 benchmarks/chapter7_feasibility.py [--json FILE] [--rounds N] [--quick]
    python3 benchmarks/chapter7_feasibility.py --inlet-follows-load [--write] [--json FILE] [--rounds N]
    python3 benchmarks/chapter7_feasibility.py --inlet-follows-load --rated-current [--per-level] [--json FILE] [--rounds N]
    python3 benchmarks/chapter7_feasibility.py --inlet-follows-load --simulation-model-manager [--json FILE]
    python3 benchmarks/chapter7_feasibility.py --inlet-follows-load --simulation-model-manager --rest-min 20

Frees every assumed value of the Genco RF201A's cooling and losses within its physical bounds, the
large blockage's flow fraction (the orifice mapping) and convection exponent, and its inlet rise
(amplitude 51 ± 5 °C and time constant), and minimises with IPOPT (exact derivatives, several starts)
the largest violation, in K of winding temperature past each outcome's band, over all chapter-7
outcomes: the +4 K and +16 K manager thresholds (1-K bands), the no-action blockage (109 °C 44 ± 10 min
after the fault) and the managed blockage (displacement alone in the three K-conditions, a 10-min
rest before landing, both generators at most 111 °C, no current limit)
(:mod:`studies.chapter7_feasibility`). Then traces the Pareto front (the least worst
violation of the other outcomes with the managed peaks capped) and two variants: the rig's 20-min
rest and an inlet rise that follows gen1's load (7.3.3: it "is dependent upon both the fault and the
load"). ``--quick``: the main study from the shipped calibration only, one round, no variants.

``--inlet-follows-load`` runs the study with the load share of the inlet rise free (every start,
no Pareto trace or variants); with ``--write`` its solution becomes the shipped calibration
``genco_rf201a:chapter7`` (:data:`~studies.chapter7.PARAMETER_FILE`: the seven machine
values) and the blockage it fits is printed for the chapter-7 scenarios (``fault``).

``--rated-current`` holds the receiver to the mission's rated current (7 A) at every instant, the
rated-current reading of "spare capacity" (7.3.3: "during landing there is very little spare
capacity in either the faulty or healthy generators"): no displacement in a K-condition whose
nominal load reaches 100 % (landing). ``--per-level`` gives each K-condition's 5-min start-up level
and its continuous level a displaced current of their own (as the heuristic plans them), so the
receiver can take load in landing's continuous level. With ``--write`` its solution ships with the
provenance :data:`SOURCE_RATED`.

``--simulation-model-manager`` holds the manager lags at 0 K: the thresholds of a manager that
predicts on the simulation model itself (the rig test's "Kalman Filter containing the simulation
model", 7.3.4; ``planner_model`` ``nonlinear``) instead of the design model (7.3.2).

``--rest-min`` is the managed outcome's rest of both generators before landing, min: the thesis's
simulation rested 10 (the default), its rig 20 (7.3.5), the two ends of the issue's "a rest before
landing of 10-20 min". (Without ``--inlet-follows-load`` the study also runs 20 min as a variant.)
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

from genthermal.machines import build_model
import yaml

from genthermal.mission import load_mission
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root: studies/
from studies.chapter7 import DT_S, FIT_BOUNDS, PARAMETER_FILE
from studies.chapter7_feasibility import (H_AIR_GAP_BOUNDS, MACHINE_NAMES, default_starts, pareto_trace,
                                                      study)
from studies.chapter7_managed import REST_BEFORE_LANDING_S
from genthermal.model_file import load_model
from genthermal.schedule.flight.manager_settings import ManagerSettings

#: Provenance of every value the study with a load-following inlet ships.
SOURCE = "fitted to thesis ch. 7 outcomes (benchmarks/chapter7_feasibility.py, inlet follows load)"
#: Provenance of the same study with the receiver held to its rated current (``--rated-current``).
SOURCE_RATED = ("fitted to thesis ch. 7 outcomes, rated-current reading (benchmarks/chapter7_feasibility.py, "
                "inlet follows load, receiver held to rated current)")

#: Caps on the managed peaks of the Pareto trace, °C (θmax itself and halfway to the thesis's 111).
MANAGED_CAPS_C = (110.0, 110.5)
#: Caps on the other outcomes' violations of the Pareto trace, K (0: all met).
OTHERS_CAPS_K = (0.0, 0.5, 1.0, 2.0)


def _public(result: dict) -> dict:
    return {k: v for k, v in result.items() if k != "decision"}


def _progress(label: str, result: dict, started: float) -> None:
    """One line on stderr per solve: the run takes minutes."""
    print(f"{time.perf_counter() - started:7.0f} s  {label}: worst violation {result['worst_violation_K']:+.3f} K "
          f"({result['worst_outcome']})", file=sys.stderr, flush=True)


def scenario_fault(best: dict) -> dict:
    """The large blockage of the chapter-7 scenarios as the study ``best`` fits it (fault keys of
    :func:`genthermal.schedule.power_system.parse_fault`)."""
    values = best["values"]
    return {"generator": 1, "kind": "coolant_blockage", "onset_min": 66, "k_flow": round(values["k_flow"], 3),
            "n_flow": round(values["n_flow"], 3), "inlet_rise_C": round(best["inlet_rise_K"], 2),
            "inlet_rise_tau_min": round(best["inlet_tau_min"], 2),
            "inlet_load_share": round(best["inlet_load_share"], 3)}


def write_calibration(best: dict, path: Path, source: str = SOURCE, command: str = "--inlet-follows-load --write") -> None:
    """Write the machine values of the study ``best`` as the model file at ``path``, each with its
    bounds and ``source`` in the provenance (``command``: the options that wrote it, for the header)."""
    bounds = {**FIT_BOUNDS, "h_air_gap": H_AIR_GAP_BOUNDS}
    at_bound = set(best["at_bound"])
    document = {"machine": "genco_rf201a", "variant": "nonlinear", "parameters": {
        n: {"value": round(best["values"][n], 4), "provenance": "fitted",
            "source": f"{source}: {bounds[n][3]}, bounds {bounds[n][0]:g}-{bounds[n][1]:g} {bounds[n][2]}"
                      + (" (at its bound)" if n in at_bound else "")}
        for n in MACHINE_NAMES}}
    header = ("# Chapter-7 calibration of the Genco RF201A (studies.chapter7_feasibility), written by\n"
              f"# benchmarks/chapter7_feasibility.py {command}. load_model('genco_rf201a:chapter7')\n"
              "# reads it. The chapter-7 scenarios fly the blockage the same study fits:\n"
              f"# {json.dumps(scenario_fault(best))}\n")
    path.write_text(header + yaml.safe_dump(document, sort_keys=False))


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", help="also write the JSON here")
    parser.add_argument("--rounds", type=int, default=2, help="solves with the manager lags re-measured (default 2)")
    parser.add_argument("--quick", action="store_true", help="shipped start only, one round, no Pareto or variants")
    parser.add_argument("--inlet-follows-load", action="store_true",
                        help="the study with the inlet rise's load share free only (no Pareto trace or variants)")
    parser.add_argument("--rated-current", action="store_true",
                        help="hold the receiver to the mission's rated current at every instant (rated-current reading)")
    parser.add_argument("--per-level", action="store_true",
                        help="one displaced current per level (5-min start-up, continuous) of each K-condition")
    parser.add_argument("--simulation-model-manager", action="store_true",
                        help="manager lags 0: a manager predicting on the simulation model (thesis 7.3.4) instead of "
                             "the design model (7.3.2)")
    parser.add_argument("--rest-min", type=float, default=REST_BEFORE_LANDING_S / 60.0,
                        help="rest of both generators before landing in the managed outcome, min (default "
                             f"{REST_BEFORE_LANDING_S / 60.0:g}, the thesis's simulation; its rig rested 20)")
    parser.add_argument("--write", action="store_true",
                        help="with --inlet-follows-load: ship its solution as genco_rf201a:chapter7")
    args = parser.parse_args(argv)
    if args.rounds < 1:
        parser.error(f"--rounds must be >= 1 (one solve, then one more per re-measured lag), got {args.rounds}")
    budget_min = ManagerSettings().rest_budget_for(load_mission("thesis_fig_7_7").duration_s) / 60.0
    step_min = DT_S / 60.0
    if not (math.isfinite(args.rest_min) and 0 < args.rest_min <= budget_min
            and abs(args.rest_min / step_min - round(args.rest_min / step_min)) < 1e-9):
        parser.error(f"--rest-min must be a rest in min, > 0 and at most {budget_min:g} (the chapter-7 flights' rest "
                     f"budget) in steps of {step_min:g} min (the study's sample period), got {args.rest_min:g}")
    if args.write and args.rest_min != REST_BEFORE_LANDING_S / 60.0:
        parser.error("--write ships the study with the thesis's 10-min rest: leave --rest-min out")
    if args.write and not args.inlet_follows_load:
        parser.error("--write ships the study with the load-following inlet: give --inlet-follows-load")
    started = time.perf_counter()
    chapter7, default = load_model("genco_rf201a:chapter7"), build_model()
    receiver_limit_A = load_mission("thesis_fig_7_7").rated_current_A if args.rated_current else None
    starts = default_starts(chapter7, default)[:1] if args.quick else None
    lags_K = dict.fromkeys(("landing", "cruise_combat"), 0.0) if args.simulation_model_manager else None
    main_study = study(chapter7, default, rest_s=60.0 * args.rest_min, rounds=1 if args.quick else args.rounds, starts=starts,
                       inlet_follows_load=args.inlet_follows_load, receiver_limit_A=receiver_limit_A, per_level=args.per_level,
                       lags_K=lags_K)
    _progress("main study", main_study["best"], started)
    report = {"study": {"starts": [_public(r) for r in main_study["starts"]], "best": _public(main_study["best"]),
                        "sharp": main_study["sharp"], "rounds": main_study["rounds"]}}
    if args.inlet_follows_load:
        report["study"]["scenario_fault"] = scenario_fault(main_study["best"])
        if args.write:
            path = Path(__file__).resolve().parents[1] / "genthermal" / "machines" / PARAMETER_FILE
            if args.rated_current:
                write_calibration(main_study["best"], path, SOURCE_RATED, "--inlet-follows-load --rated-current "
                                  + ("--per-level " if args.per_level else "") + "--write")
            else:
                write_calibration(main_study["best"], path)
    if not args.quick and not args.inlet_follows_load:
        report["pareto"] = [_public(p) for p in pareto_trace(main_study["problem"], main_study["best"], MANAGED_CAPS_C,
                                                             OTHERS_CAPS_K)]
        for point in report["pareto"]:
            print(f"{time.perf_counter() - started:7.0f} s  pareto: managed cap {point['managed_cap_C']}, others cap "
                  f"{point['others_cap_K']}: managed peak {point['managed_peak_C']:.2f} °C, others' worst "
                  f"{point['others_worst_violation_K']:+.3f} K ({point['others_worst_outcome']})", file=sys.stderr, flush=True)
        best_start = [s for s in default_starts(chapter7, default) if s.label == main_study["best"]["start"]] or None
        for label, options in (("rig rest 20 min", {"rest_s": 1200.0}),
                               ("inlet rise follows gen1's load", {"inlet_follows_load": True})):
            variant = study(chapter7, default, rounds=args.rounds, starts=best_start, receiver_limit_A=receiver_limit_A,
                            per_level=args.per_level, lags_K=lags_K, **options)
            report[label] = {"best": _public(variant["best"]), "sharp": variant["sharp"], "rounds": variant["rounds"]}
            _progress(label, variant["best"], started)
    best, sharp = main_study["best"], main_study["sharp"]
    report["verdict"] = {"receiver_limit_A": receiver_limit_A, "per_level": args.per_level,
                         "manager": "simulation model" if args.simulation_model_manager else "design model",
                         "rest_before_landing_min": args.rest_min, "min_worst_violation_K": best["worst_violation_K"], "worst_outcome": best["worst_outcome"],
                         "sharp_worst_violation_K": sharp["worst_violation_K"], "sharp_worst_outcome": sharp["worst_outcome"],
                         "feasible": sharp["worst_violation_K"] <= 0.0,
                         "conflicting": sorted(k for k, v in best["violations_K"].items()
                                               if v >= best["worst_violation_K"] - 0.02)}
    report["wall_s"] = time.perf_counter() - started
    text = json.dumps(report, indent=2, ensure_ascii=False)
    print(text)
    if args.json:
        Path(args.json).write_text(text)


if __name__ == "__main__":
    main()
