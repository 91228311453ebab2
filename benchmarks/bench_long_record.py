"""Time ``genthermal diagnose`` on one week logged at 1 s (604 800 samples): issue-10 target ≤ 5 min, ≤ 2 GB.

The record is synthesised from a plant that is not the diagnosing model (``h_end_air`` 25 % low)
with a coolant-flow blockage from day 5: the load changes every 30 min between 27.3 % and 100 % of
rated current (seeded), inlet and ambient at 20 °C. ``genthermal diagnose`` then runs as a user
runs it, in a child process from the CSV, so the wall time includes loading, validating and
decimating the record (:mod:`genthermal.long_records`), and the peak memory is that of the child.

Usage: ``python benchmarks/bench_long_record.py [--days D] [--workdir DIR]``. Prints one JSON line:
wall and CPU seconds, peak resident memory (MB), the load average at the start (the machine is
shared), the verdict and the targets.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from genthermal.exciter import exciter_current
from genthermal.machines import build_model
from genthermal.synth import synthesize

#: Rated phase current of the thesis generator, A RMS.
RATED_CURRENT_A = 7.0
#: Onset of the hidden blockage, days after the start.
BLOCKAGE_ONSET_DAYS = 5.0


def week_inputs(days: float, dt_s: float = 1.0, seed: int = 1) -> pd.DataFrame:
    """Input frame of ``days`` at ``dt_s``: a load level drawn every 30 min, constant temperatures."""
    n = int(round(days * 86400 / dt_s)) + 1
    time_s = np.arange(n) * dt_s
    levels = np.random.default_rng(seed).uniform(0.273, 1.0, int(np.ceil(n * dt_s / 1800)) + 1)
    current = RATED_CURRENT_A * levels[(time_s // 1800).astype(int)]
    return pd.DataFrame({"time_s": time_s, "I_u": current, "I_v": current, "I_w": current,
                         "I_exc": exciter_current(current), "T_inlet": 20.0, "T_ambient": 20.0})


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, default=7.0, help="record length in days (default 7)")
    parser.add_argument("--workdir", help="folder for the CSV (default: a temporary folder)")
    args = parser.parse_args()
    workdir = Path(args.workdir or tempfile.mkdtemp(prefix="gt-long-record-"))
    csv = workdir / f"record_{args.days:g}d_1s.csv"
    if not csv.exists():
        healthy = build_model().with_parameters("assumed", "benchmark plant", h_end_air=0.75 * build_model().parameters["h_end_air"].value)
        blocked = healthy.with_effect("coolant_flow_reduction", k_flow=0.5)
        frame = synthesize(healthy, week_inputs(args.days), dt_s=1.0, seed=2,
                           switches=[(BLOCKAGE_ONSET_DAYS * 86400.0, blocked)] if args.days > BLOCKAGE_ONSET_DAYS else ())
        frame.to_csv(csv, index=False)
    load_average = os.getloadavg()
    report = workdir / "diagnosis.json"
    started, before = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
    run = subprocess.run([sys.executable, "-c", "from genthermal.cli import main; raise SystemExit(main())",
                          "diagnose", str(csv), "--json", str(report), "--force"],
                         capture_output=True, text=True)
    elapsed, after = time.perf_counter() - started, resource.getrusage(resource.RUSAGE_CHILDREN)
    diagnosis = json.loads(report.read_text()) if run.returncode == 0 else {}
    print(json.dumps({"benchmark": f"diagnose, {args.days:g} days at 1 s", "samples": int(round(args.days * 86400)) + 1,
                      "exit_code": run.returncode, "seconds": round(elapsed, 1),
                      "cpu_seconds": round(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime, 1),
                      "peak_rss_mb": round(after.ru_maxrss / 1024, 0), "load_average_1min": round(load_average[0], 2),
                      "verdict": diagnosis.get("verdict"), "target_seconds": 300, "target_peak_mb": 2048,
                      "stderr_tail": run.stderr.strip().splitlines()[-3:]}))
    return run.returncode


if __name__ == "__main__":
    raise SystemExit(main())
