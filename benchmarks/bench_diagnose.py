"""Time ``genthermal diagnose`` on 4-hour records at 10 s (1441 samples).

Three runs, each from a cold start (models and simulators built inside the timing):

* ``single``: one hidden catalogue effect, the catalogue searched (singles; pairs only if one
  effect leaves the residual unexplained);
* ``pair``: two hidden effects (a blockage from 80 min on top of an end-winding stray loss from
  the start), the catalogue searched with jointly fitted pairs;
* ``open``: the open search over the generic heat-flow library on a record with an excitation
  iron loss from 1.4 h;
* ``lookalike``: a shorted turn from 50 min under balanced load (it looks like end-winding stray
  loss): the separating test designed and the separation it predicts.

Usage: ``python benchmarks/bench_diagnose.py [--json FILE] [--only single|pair|open|lookalike]``. Prints one
JSON document per run (elapsed and CPU seconds: the machine is shared, and CPU time is what the
run would take alone on one core; verdict, ground truth, final RMSE); target ≤ 60 s each.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from genthermal.diagnose.discover import diagnose
from genthermal.diagnose.hidden import Injection, make_hidden_effect_case
from genthermal.diagnose.open_search import describe_term, open_search
from genthermal.machines import build_model

RUNS = {
    "single": ("coolant_flow_reduction", diagnose),
    "pair": ([Injection("coolant_flow_reduction", {"k_flow": 0.6}, 4800.0),
              Injection("end_winding_stray_loss", {"R_stray": 0.2}, 0.0)], diagnose),
    "open": ([Injection("excitation_iron_loss", {"k_exc": 30.0}, 5000.0)], open_search),
    "lookalike": ([Injection("phase_short_circuit", {"R_short": 0.3}, 3000.0)], diagnose),
}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the results to this file as well")
    parser.add_argument("--only", choices=list(RUNS), help="run only this case")
    args = parser.parse_args()
    documents = []
    for name, (effects, method) in RUNS.items():
        if args.only and name != args.only:
            continue
        model = build_model()
        case = make_hidden_effect_case(effects, mission="thesis_fig_7_7", dt_s=10.0, seed=3, plant=model)
        started, cpu_started = time.perf_counter(), time.process_time()
        result = method(model, case.data, progress=lambda line: print(f"  [{time.perf_counter() - started:5.1f} s] "
                                                                       f"{line[:110]}", file=sys.stderr))
        elapsed, cpu = time.perf_counter() - started, time.process_time() - cpu_started
        document = {"benchmark": f"diagnose {name}, 4 h at 10 s", "samples": int(result.series.time_s.size),
                    "candidates": len(result.iterations[0].ranked), "pairs": len(result.iterations[0].pairs),
                    "seconds": round(elapsed, 2), "cpu_seconds": round(cpu, 2), "target_seconds": 60, "verdict": result.verdict,
                    "found": [{"effect": f.effect, "onset_h": round(f.onset_s / 3600, 3), "params": f.values}
                              for f in result.found],
                    "truth": case.truth()["effects"], "rmse_final_K": round(result.iterations[-1].rmse_after, 4),
                    "noise_std_estimated_K": round(result.noise_std, 4), "unexplained": result.unexplained}
        if result.experiment:
            document["experiment"] = {k: v for k, v in result.experiment.to_dict().items() if k != "scenario"}
            document["experiment"]["blocks"] = result.experiment.to_dict()["scenario"]["actions"]
        if method is open_search:
            document["described"] = [describe_term(f, result.catalogue) for f in result.found]
        documents.append(document)
        print(json.dumps(document), flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(documents, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
