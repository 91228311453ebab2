"""Two partial re-flies of the robustness grid side by side (``genthermal sweep --only ...`` of the
same cases and schedulers, before and after a change of the monitor): per scheduler the breach-free
cases, the detection delay, the false alarms and the added rest.

Usage::

    python benchmarks/flight_evidence_compare.py BEFORE.json[,MORE.json] AFTER.json[,MORE.json]

Each argument is one or more sweep JSON files (comma-separated) joined case by case. Prints a
markdown table (one row per scheduler and side) and the cases whose figures differ.
"""

from __future__ import annotations

import json
import sys

import numpy as np


def cases(paths: str) -> dict:
    """Case name → case record of the sweep JSON files ``paths`` (comma-separated)."""
    joined = {}
    for path in paths.split(","):
        joined.update({c["name"]: c for c in json.load(open(path))["cases"]})
    return joined


def figures(grid: dict, scheduler: str) -> dict:
    """The compared figures of ``scheduler`` over the cases of ``grid``."""
    runs = [(c, c["runs"][scheduler]) for c in grid.values() if c["runs"].get(scheduler, {}).get("status") == "ok"]
    delays = [r["detect_delay_s"] for c, r in runs if c["faulty"] and r.get("detect_delay_s") is not None]
    return {"flown": len(runs), "breach_free": sum(r["breach_s"] <= 0 for _, r in runs),
            "faulty": sum(c["faulty"] for c, _ in runs), "detected": len(delays),
            "median_delay_min": float(np.median(delays)) / 60 if delays else None,
            "max_delay_min": max(delays) / 60 if delays else None,
            "false_alarms": sum(r["false_alarms"] for _, r in runs),
            "false_on_healthy": sum(r["false_alarms"] for c, r in runs if not c["faulty"]),
            "rest_min": sum(max(r["added_rest_s"], 0.0) for c, r in runs if c["faulty"]) / 60}


def main(before: str, after: str) -> None:
    grids = {"before": cases(before), "after": cases(after)}
    common = sorted(set(grids["before"]) & set(grids["after"]))
    grids = {side: {name: grid[name] for name in common} for side, grid in grids.items()}
    schedulers = sorted({s for c in grids["after"].values() for s in c["runs"]})
    print(f"{len(common)} cases\n")
    print("| scheduler | side | flown | breach-free | detected / faulty | median / max delay, min "
          "| false alarms (on healthy flights) | added rest on faulty cases, min |")
    print("|---|---|---|---|---|---|---|---|")
    for scheduler in schedulers:
        for side, grid in grids.items():
            f = figures(grid, scheduler)
            delay = "-" if f["median_delay_min"] is None else f"{f['median_delay_min']:.1f} / {f['max_delay_min']:.1f}"
            print(f"| {scheduler} | {side} | {f['flown']} | {f['breach_free']} | {f['detected']} / {f['faulty']} "
                  f"| {delay} | {f['false_alarms']} ({f['false_on_healthy']}) | {f['rest_min']:.1f} |")
    print("\ncases that differ (before → after: delay s, false alarms, rest min, breach s):")
    for name in common:
        for scheduler in schedulers:
            pair = [grids[side][name]["runs"].get(scheduler, {}) for side in ("before", "after")]
            keys = ("detect_delay_s", "false_alarms", "added_rest_s", "breach_s")
            values = [tuple(None if r.get(k) is None else round(r[k] / (60 if k == "added_rest_s" else 1), 1)
                            for k in keys) for r in pair]
            if values[0] != values[1]:
                print(f"- {name} {scheduler}: {values[0]} → {values[1]}")


if __name__ == "__main__":
    main(*sys.argv[1:3])
