"""Time ``genthermal diagnose`` on one 4-hour record at 10 s (1441 samples) against the catalogue.

Usage: ``python benchmarks/bench_diagnose.py [--json FILE] [--effect NAME] [--seed N]``. Prints (and
writes) JSON with the elapsed seconds, the verdict and the ground truth; target ≤ 60 s.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from genthermal.diagnose.discover import diagnose
from genthermal.diagnose.hidden import make_hidden_effect_case
from genthermal.machines import build_model


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the result to this file as well")
    parser.add_argument("--effect", default="coolant_flow_reduction", help="effect hidden in the record")
    parser.add_argument("--seed", type=int, default=3)
    args = parser.parse_args()
    model = build_model()
    case = make_hidden_effect_case(args.effect, mission="thesis_fig_7_7", dt_s=10.0, seed=args.seed, plant=model)
    started = time.perf_counter()
    result = diagnose(model, case.data)
    elapsed = time.perf_counter() - started
    top = result.iterations[0].ranked[0]
    document = {"benchmark": "diagnose, 4 h at 10 s, whole catalogue", "samples": int(result.series.time_s.size),
                "candidates": len(result.iterations[0].ranked), "seconds": round(elapsed, 2),
                "target_seconds": 60, "verdict": result.verdict, "truth": case.truth(),
                "top": top.to_dict(), "noise_std_estimated_K": result.noise_std}
    text = json.dumps(document, indent=2)
    print(text)
    if args.json:
        Path(args.json).write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
