"""``genthermal sweep --cases N [--schedulers a,b] [--json FILE]``: the robustness grid of closed-loop
flights (:mod:`genthermal.schedule.sweeps.sweep`) in local worker processes, or on Dask
(genthermal[sweep]). Reference: docs/results/robustness-grid.md and docs/guide/cli.md.
"""

from __future__ import annotations

import argparse
import json
import math
import shlex
import subprocess
import time
from pathlib import Path

from ..errors import InputError
from ._common import add_choice_argument, add_json_argument
from ._vocabulary import (DEFAULT_FLIGHT_CPU_LIMIT_S, MANAGER_DEFAULTS, PLANNER_MODELS, SWEEP_SCHEDULERS, cli_spelling,
                          library_value)

#: What ``sweep --help`` says the command does.
SWEEP_DESCRIPTION = ("Robustness sweep of the closed loop: N seeded cases (missions of 2-8 h, 2-4 generators, plant "
                     "parameters off by up to ±30 %, a fault the manager is not told) flown with each scheduler in "
                     "local worker processes of one thread each (no port opened), or on Dask (--cluster, or "
                     "--dashboard for a local Dask cluster with its dashboard; both need the extra "
                     "genthermal[sweep]).")


def register(subparsers) -> None:
    """Add the ``sweep`` sub-command."""
    parser = subparsers.add_parser("sweep", help="robustness grid of closed-loop flights in worker processes",
                                   description=SWEEP_DESCRIPTION)
    parser.add_argument("--cases", default=60, type=int, help="number of cases (default 60)")
    parser.add_argument("--schedulers", default="heuristic,engineer,optimal",
                        metavar="NAME,...",
                        help=f"comma-separated, of {', '.join(SWEEP_SCHEDULERS)} (default heuristic,engineer,optimal; "
                        "heuristic-flown: the thesis heuristic on the flown model, a third baseline; "
                        "optimal-flown: the optimal scheduler on the flown model, whatever --planner-model)")
    parser.add_argument("--cluster", help="address of an existing Dask scheduler (default: local worker processes, "
                        "no Dask; needs genthermal[sweep])")
    parser.add_argument("--dashboard", nargs="?", const=":8787", metavar="ADDRESS",
                        help="fly on a local Dask cluster serving its dashboard at ADDRESS (default :8787; "
                        "needs genthermal[sweep]); without it no port is opened")
    parser.add_argument("--workers", default=2, type=int, help="local worker processes, one thread each (default 2)")
    parser.add_argument("--seed", default=0, type=int, help="seed of the cases (default 0)")
    add_json_argument(parser, "the summary and every case (without it the whole document goes to standard "
                      "output, and only the summary does with it)")
    parser.add_argument("--flight-limit-s", default=DEFAULT_FLIGHT_CPU_LIMIT_S, type=float,
                        help="processor-time limit of one flight, s: a flight past it is recorded as a timeout "
                             f"(default {DEFAULT_FLIGHT_CPU_LIMIT_S:g})")
    parser.add_argument("--timeout-s", type=float, help="wall-clock limit of the whole sweep, s: flights not "
                        "done by then are recorded as unfinished (default: none)")
    parser.add_argument("--only", metavar="INDICES", help="fly only these cases of the --cases grid, "
                        "comma-separated indices from 0 (e.g. 0,15,50: each is the same seeded case as in the whole grid)")
    add_choice_argument(parser, "--planner-model", PLANNER_MODELS, default=MANAGER_DEFAULTS["planner_model"],
                        help="model the optimal scheduler plans on (the baselines plan on the design model; "
                        "default auto: the flown model, the extended Kalman filter's)")
    parser.add_argument("--no-hindsight", action="store_true", help="do not plan the faulty cases in hindsight "
                        "(the least rest with the true plant and fault known from the onset, a few seconds a case)")
    parser.add_argument("--no-progress", dest="quiet", action="store_true", default=argparse.SUPPRESS,
                        help=argparse.SUPPRESS)  # the old spelling of --quiet (docs/guide/flights.md)
    parser.set_defaults(func=run)


def run(args) -> int:
    """Run the sweep; print the summary and write every case to ``--json``, or print it all."""
    from ..outputs import finite_document, report_json
    from ..progress import enabled as progress_enabled
    from ..schedule.sweeps.sweep import robustness_case, run_sweep, summarise

    schedulers = [cli_spelling(s.strip()) for s in args.schedulers.split(",") if s.strip()]
    bad = [s for s in schedulers if s not in SWEEP_SCHEDULERS]
    if bad or not schedulers:
        raise InputError("--schedulers", args.schedulers, f"each must be one of {', '.join(SWEEP_SCHEDULERS)}")
    if args.cases < 1:
        raise InputError("--cases", args.cases, "must be a whole number >= 1")
    if args.cluster and args.dashboard:
        raise InputError("--dashboard", args.dashboard, "is the dashboard of a local Dask cluster: the cluster at "
                         "--cluster serves its own")
    if args.workers < 1:
        raise InputError("--workers", args.workers, "must be a whole number >= 1")
    for option, value in (("--flight-limit-s", args.flight_limit_s), ("--timeout-s", args.timeout_s)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise InputError(option, value, "must be a number of seconds > 0")
    documents = [robustness_case(i, args.seed) for i in case_indices(args.only, args.cases)]
    started, commit = time.perf_counter(), source_commit()  # the code flown, read before the flights
    schedulers = [library_value(s) for s in schedulers]
    records = run_sweep(documents, schedulers, args.cluster, args.workers, progress_enabled(),
                        args.flight_limit_s, args.timeout_s, args.planner_model, not args.no_hindsight,
                        dashboard=args.dashboard)
    report = {**summarise(records, schedulers),
              "provenance": {"command": equivalent_command(args),
                             "commit": commit, "workers": None if args.cluster else args.workers,
                             "cluster": args.cluster, "dashboard": args.dashboard, "seed": args.seed, "only": args.only,
                             "optimal_planner_model": args.planner_model, "hindsight": not args.no_hindsight,
                             "sweep_wall_s": time.perf_counter() - started},
              "cases": records}
    if not args.json:
        print(json.dumps(finite_document(report), indent=2, default=str, allow_nan=False))
        return 0
    print(json.dumps(finite_document({k: v for k, v in report.items() if k != "cases"}), default=str,
                     allow_nan=False))
    report_json(args.json, report)
    return 0


def case_indices(only: str | None, cases: int) -> list:
    """The indices of the cases to fly: ``only`` (comma-separated whole numbers in ``[0, cases)``,
    each once) or, when None, all ``cases``."""
    if only is None:
        return list(range(cases))
    words = [w.strip() for w in only.split(",")]
    if not words or not all(w.isdigit() for w in words):
        raise InputError("--only", only, "must be comma-separated case indices (whole numbers from 0)")
    indices = [int(w) for w in words]
    outside = [i for i in indices if i >= cases]
    if outside:
        raise InputError("--only", only, f"cases {outside} are not in the grid of --cases {cases} (indices 0 to {cases - 1})")
    if len(set(indices)) != len(indices):
        raise InputError("--only", only, "names a case more than once")
    return indices


def source_commit() -> str | None:
    """The git commit of the genthermal source tree run (with ``+dirty`` when it has uncommitted
    changes), or None outside a git work tree."""
    here = Path(__file__).resolve().parent
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True,
                                check=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=here,
                               capture_output=True, text=True, check=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return commit + ("+dirty" if dirty else "")


def equivalent_command(args) -> str:
    """The ``genthermal sweep`` command line that runs this sweep again (every option spelt out)."""
    words = ["genthermal", "sweep", "--cases", str(args.cases), "--schedulers", args.schedulers,
             "--seed", str(args.seed), "--flight-limit-s", f"{args.flight_limit_s:g}"]
    words += ["--only", args.only] if args.only is not None else []
    words += ["--planner-model", args.planner_model]
    words += ["--no-hindsight"] if args.no_hindsight else []
    words += ["--cluster", args.cluster] if args.cluster else ["--workers", str(args.workers)]
    words += ["--dashboard", args.dashboard] if args.dashboard else []
    words += ["--timeout-s", f"{args.timeout_s:g}"] if args.timeout_s is not None else []
    words += ["--json", args.json, "--force"] if args.json else []
    return " ".join(shlex.quote(w) for w in words)
