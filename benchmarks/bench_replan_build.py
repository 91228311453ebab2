"""Where a grid flight's first flown-model re-plan spends its time: building the solver or solving.

Flies robustness-grid case ``--case`` with the optimal scheduler until its first solve on the flown
model, then builds that NLP twice in this process, expanded to scalar expressions with its exact
Hessian (``NonlinearSettings.expand=True``, the default) and left as a CasADi MX graph
(``expand=False``), and solves each once from the same guess and back-off. The flight stops there.

Usage::

    python benchmarks/bench_replan_build.py [--case 23]

Prints one JSON object: the NLP's sizes and, per build, the CPU time of building and of solving,
IPOPT's iterations and status, and the ratio of the totals (MX / expanded).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time

from genthermal.schedule.planning import optimal_nlp
from genthermal.schedule.sweeps.sweep import fly_flight, robustness_case


class _Measured(Exception):
    """Raised out of the flight once the first flown-model NLP has been measured."""


def measure(transcription, guess, backoff, solve) -> dict:
    """Build ``transcription``'s NLP expanded and as MX and solve each with ``solve``
    (:meth:`~genthermal.schedule.planning.optimal_nlp.FlownTranscription.solve`) from ``guess`` at
    ``backoff``; CPU times and IPOPT's outcome."""
    out = {"nx": transcription.nx, "generators": transcription.n_gen, "segments_padded": transcription.N_seg,
           "intervals_padded": transcription.N_int, "substeps": transcription.n_sub}
    for name, expand in (("expanded", True), ("mx", False)):
        copy = optimal_nlp.FlownTranscription.__new__(optimal_nlp.FlownTranscription)
        copy.__dict__.update(transcription.__dict__)
        copy.settings = dataclasses.replace(transcription.settings, expand=expand)
        copy.iterations = 0
        started = time.process_time()
        copy._solver()  # built and cached for this structure (the key names the expand setting)
        built = time.process_time()
        _, success, status = solve(copy, guess, backoff)  # the cached solver: IPOPT's run only
        solved = time.process_time()
        out[name] = {"build_cpu_s": round(built - started, 3), "solve_cpu_s": round(solved - built, 3),
                     "iterations": int(copy.iterations), "status": status, "success": success}
    out["total_ratio_mx_to_expanded"] = round(
        (out["mx"]["build_cpu_s"] + out["mx"]["solve_cpu_s"])
        / (out["expanded"]["build_cpu_s"] + out["expanded"]["solve_cpu_s"]), 3)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--case", type=int, default=23, help="robustness-grid case, >= 0 (default 23)")
    args = parser.parse_args(argv)
    if args.case < 0:
        parser.error(f"--case: a grid case is a whole number >= 0, got {args.case}")
    measured = {}
    solve = optimal_nlp.FlownTranscription.solve

    def first_solve(self, guess, backoff):
        measured.update(measure(self, guess, backoff, solve))
        raise _Measured

    optimal_nlp.FlownTranscription.solve = first_solve
    try:
        record = fly_flight(robustness_case(args.case), "optimal")  # records the stop as an error
    finally:
        optimal_nlp.FlownTranscription.solve = solve
    if not measured:
        print(json.dumps({"benchmark": "replan_build", "case": args.case, "error": "no flown-model re-plan",
                          "flight": record.get("status")}))
        return 1
    print(json.dumps({"benchmark": "replan_build", "case": args.case, **measured}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
