"""What ``diagnose`` names on the real bench IPMSM's plain model, and the held-out error after adding it.

Per cross-validation fold of ``bench_ipmsm.py`` (4 folds of 3 profiles): the plain model (copper
loss, constant convection) is calibrated on the other 9 profiles as the tutorial does (every
assumed parameter, 30-s blocks, prior 30); each held-out profile is diagnosed on 60-s blocks
against the sensor noise and against the error model of the 9 training profiles (``--baseline``);
the effect with the most evidence over the held-out profiles (the sum of its ΔBIC where it was
fitted within its plausible range, :func:`evidence_by_effect`) is added, the plain model with it is calibrated
on the same 9 profiles, and both are scored open loop on the 3 (10-s blocks, node groups of
``bench_ipmsm.py``). The effect is chosen on the profiles it is then scored on: that choice, one
discrete one, is not held out. Prints JSON lines. Run: ``python3 benchmarks/bench_ipmsm_diagnose.py
[--folds 4] [--only 0]``; 2-4 min per fold on 2 loaded cores.
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_ipmsm as bench  # noqa: E402  (a script beside this one: its data, folds and groups)

DIAGNOSIS_STEP_S = 60.0
PRIOR_WEIGHT = 30.0


def diagnosis_summary(result) -> dict:
    """Verdict, the three best single effects, and the sensor faults claimed and refused (with the
    reason) of a Diagnosis."""
    document = result.to_dict()
    top = [{"effect": c["effect"], "rmse_after_K": round(c["rmse_after"], 3), "delta_ic": round(c["delta_ic"], 1),
            "params": {k: round(v, 4) for k, v in c["params"].items()}} for c in document["ranked"][:3]]
    return {"verdict": document["verdict"], "rmse_before_K": round(document["ranked"][0]["rmse_before"], 3)
            if document["ranked"] else None, "top": top, "floor_K": document["residual"].get("floor_K"),
            "sensor_faults": [f["text"] for f in document["sensor_faults"]],
            "refused_sensor_faults": [f["refused"] for f in document["refused_sensor_faults"]]}


def evidence_by_effect(result) -> dict:
    """ΔBIC of each effect plausibly fitted on one held-out profile (fits outside their plausible
    range, :func:`~genthermal.diagnose.discover.implausible_reason`, count nothing)."""
    from genthermal.diagnose.discover import implausible_reason

    return {c.effect: float(c.delta_bic) for c in result.iterations[0].ranked if implausible_reason(c) is None}


def held_out_rmse(model, records) -> dict:
    """Open-loop RMSE and max |error| per node group over ``records``, K."""
    from genthermal.diagnose.multi_record import simulate_record

    errors = collections.defaultdict(list)
    for record in records:
        predicted, measured = bench.groups(model, simulate_record(model, record)), bench.groups(model, record.outputs)
        for g in predicted:
            errors[g].append(predicted[g] - measured[g])
    out = {}
    for g, parts in errors.items():
        e = np.concatenate(parts)
        e = e[np.isfinite(e)]
        out[g] = {"rmse_K": round(float(np.sqrt(np.mean(e ** 2))), 3), "max_abs_K": round(float(np.max(np.abs(e))), 2)}
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--folds", type=int, default=4)
    parser.add_argument("--only", type=int, action="append", help="run only these folds (repeatable)")
    args = parser.parse_args()
    if not bench.DATA.is_dir():
        print(json.dumps({"skipped": f"no data at {bench.DATA}"}))
        return 0
    from genthermal.diagnose.discovery import Discovery
    from genthermal.diagnose.fitter import OnsetFitter
    from genthermal.diagnose.multi_record import decimated, fit_records
    from genthermal.effects import CATALOGUE
    from genthermal.machines import build_model

    _, names, data, to_record = bench.load(bench.SCORE_STEP_S)
    plain = build_model(f"{bench.MACHINE_FILE}:MACHINE_PLAIN")
    plain_names = [n for n in plain.parameter_names if plain.parameters[n].provenance == "assumed"]
    fit_grid = [to_record(plain, d, bench.FIT_STEP_S) for d in data]
    score_grid = [to_record(plain, d, bench.SCORE_STEP_S) for d in data]
    diagnosis_grid = [decimated(d, DIAGNOSIS_STEP_S) for d in data]
    folds = [list(range(i, len(names), args.folds)) for i in range(args.folds)]
    for fold, held_out in enumerate(folds):
        if args.only and fold not in args.only:
            continue
        train = [i for i in range(len(names)) if i not in held_out]
        started = time.perf_counter()
        fit = fit_records(plain, [fit_grid[i] for i in train], plain_names, factor=30.0, prior_weight=PRIOR_WEIGHT)
        discovery = Discovery(fitter=OnsetFitter(workers=1, pairs=False), design_experiment=False)
        baseline = [diagnosis_grid[i] for i in train]
        report = {"fold": fold, "held_out": [names[i] for i in held_out], "plain_fit_converged": fit.converged,
                  "diagnoses": {}}
        evidence = collections.Counter()
        for i in held_out:
            result = discovery.fit(fit.model, diagnosis_grid[i])
            against_noise = diagnosis_summary(result)
            against_floor = diagnosis_summary(discovery.fit(fit.model, diagnosis_grid[i], baseline=baseline))
            report["diagnoses"][names[i]] = {"against_noise": against_noise, "against_training_floor": against_floor}
            evidence.update(evidence_by_effect(result))
        report["evidence_delta_bic"] = {e: round(v, 1) for e, v in evidence.most_common()[::-1]}
        chosen = min(evidence, key=evidence.get) if evidence and min(evidence.values()) < 0 else None
        if chosen is None:
            report["added"] = None
            print(json.dumps(report), flush=True)
            continue
        effect = CATALOGUE[chosen]
        extended = plain.with_effect(chosen, **{p.name: p.typical for p in effect.parameters})
        extended_names = plain_names + [p.name for p in effect.all_parameters]
        refit = fit_records(extended, [fit_grid[i] for i in train], extended_names, factor=30.0,
                            prior_weight={n: PRIOR_WEIGHT for n in plain_names})
        scored = [score_grid[i] for i in held_out]
        report.update({"added": chosen, "added_fit_converged": refit.converged,
                       "added_values": {p.name: round(float(refit.model.parameters.value(p.name)), 4)
                                        for p in effect.all_parameters},
                       "held_out_plain": held_out_rmse(fit.model, scored),
                       "held_out_with_added": held_out_rmse(refit.model, scored),
                       "fold_wall_s": round(time.perf_counter() - started, 1)})
        print(json.dumps(report), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
