"""The README's robustness table and plot from a ``genthermal sweep`` JSON.

Usage::

    python benchmarks/robustness_report.py benchmarks/figures/robustness.json [--png benchmarks/figures/robustness.png]
    python benchmarks/robustness_report.py benchmarks/figures/robustness.json --merge refly.json
    python benchmarks/robustness_report.py copy_of_the_grid.json --merge refly.json --merged-only
    python benchmarks/robustness_report.py benchmarks/figures/robustness.json --add other_schedulers.json

``--merge`` puts the cases of a partial re-fly (``genthermal sweep --only ...``, same ``--cases`` and
seed, some or all of the grid's schedulers) that every re-flown scheduler flew to the end in place of
those schedulers' flights of the same cases of the whole grid, recomputes every summary key with
:func:`genthermal.schedule.sweeps.sweep.summarise`, records the re-fly under ``provenance.merged`` and
writes the whole grid's JSON back before reporting on it (with ``--merged-only``, cut to the re-fly's
cases: run it on a copy). ``--add`` joins the flights of the same
grid flown with other schedulers (``genthermal sweep --schedulers heuristic_flown``, same
``--cases`` and seed) to each case, recomputes every summary key over all the schedulers (the best
baseline then counts the added ones, :mod:`genthermal.schedule.sweeps.baseline_comparison`) and records
that sweep under ``provenance.added``.

Prints two markdown tables: one row per scheduler (cases flown to the end, breach-free share,
longest breach, median and max detection delay, false alarms), then the figures of the optimal
scheduler against the best baseline (heuristic, engineer or, when flown, heuristic_flown, whichever rests less in that case;
and, at the manager's price of rest min + 1000 min per A·h not served, whichever costs less),
the rest ratio over the cases where no scheduler sheds load (the same for the optimal scheduler on
the flown model, ``optimal_flown``, when the grid has it: the comparison with the information of
``heuristic_flown``), and the cases where a target is missed (a breach, a flight that did not finish, more rest than the
best baseline), each with what the flight reports about it. Draws, per case and scheduler, the
time above θmax and the added rest of the optimal scheduler over the best baseline's.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from genthermal.schedule.sweeps.baseline_comparison import FLOWN_OPTIMAL, FLOWN_OPTIMAL_KEY  # noqa: E402

SCHEDULER_COLOURS = {"heuristic": "tab:blue", "engineer": "tab:orange", "optimal": "tab:green", "milp": "tab:red",
                     "heuristic_flown": "tab:purple", FLOWN_OPTIMAL: "tab:olive"}


def _minutes(seconds) -> str:
    return "–" if seconds is None else f"{seconds / 60:.1f}"


def scheduler_table(report: dict) -> str:
    """One row per scheduler of the sweep."""
    robustness = report["robustness"]
    cases = report["cases"]
    lines = ["| scheduler | flown to the end | breach-free cases | longest breach, s | cases with a breach "
             "| median / max detection delay, min | false alarms (healthy flights) |",
             "|---|---|---|---|---|---|---|"]
    for scheduler in robustness["breach_s"]:
        runs = [c["runs"][scheduler] for c in cases]
        ok = [r for r in runs if r.get("status", "ok") == "ok"]
        delays = [r["detect_delay_s"] for c, r in zip(cases, runs) if c["faulty"] and r.get("status", "ok") == "ok"
                  and r.get("detect_delay_s") is not None]
        healthy_alarms = sum(r["false_alarms"] for c, r in zip(cases, runs)
                             if not c["faulty"] and r.get("status", "ok") == "ok")
        alarms = sum(r["false_alarms"] for r in ok)
        breach = robustness["breach_s"][scheduler]
        lines.append(f"| {scheduler} | {len(ok)}/{len(runs)} | "
                     f"{robustness['breach_free_fraction'][scheduler] * 100:.0f} % | "
                     f"{'–' if breach is None else f'{breach:.0f}'} | {len(robustness['breached_cases'][scheduler])} | "
                     f"{_minutes(float(np.median(delays)) if delays else None)} / "
                     f"{_minutes(max(delays) if delays else None)} | {alarms} ({healthy_alarms}) |")
    return "\n".join(lines)


def _ratio_text(ratio) -> str:
    return "–" if ratio is None else f"{ratio:.2f}"


def comparison(report: dict, key: str = "rest_vs_best_baseline") -> dict | None:
    """The report's ``key`` comparison (``rest_vs_best_baseline`` or ``FLOWN_OPTIMAL_KEY``); the first
    recomputed from its cases when the JSON predates the comparison at the manager's price
    (:mod:`genthermal.schedule.sweeps.baseline_comparison`)."""
    rest = report.get(key)
    if rest and "mean_cost_ratio" not in rest:
        from genthermal.schedule.sweeps.baseline_comparison import rest_versus_best_baseline

        rest = rest_versus_best_baseline(report["cases"])
    return rest


def rest_lines(report: dict, key: str = "rest_vs_best_baseline") -> list[str]:
    """The optimal scheduler's added rest against the best baseline's, over all faulty cases and
    over those where nobody sheds, and its cost at the manager's price against the best baseline's
    (``key``: :func:`comparison`)."""
    rest = comparison(report, key)
    if not rest:
        return ["(the sweep did not fly heuristic, engineer and optimal)"]
    resting = [c for c in rest["per_case"] if c["best_baseline_rest_s"] > 0 or c["optimal_rest_s"] > 0]
    calm = rest["without_shedding"]
    return [f"Faulty cases flown to the end by every scheduler: {len(rest['per_case'])}; with added rest by the "
            f"optimal scheduler or the best baseline: {len(resting)}. Added rest over those cases: optimal {rest['optimal_total_rest_s'] / 60:.1f} min, "
            f"best baseline {rest['best_baseline_total_rest_s'] / 60:.1f} min (ratio "
            f"{_ratio_text(rest['mean_ratio'])}; target ≤ 0.8). Cases where the optimal scheduler rests "
            f"more than the best baseline: {len(rest['cases_optimal_rests_more'])} "
            f"({', '.join(rest['cases_optimal_rests_more']) or 'none'}).",
            f"Over the {calm['cases']} cases where no scheduler sheds load: optimal "
            f"{calm['optimal_total_rest_s'] / 60:.1f} min, best baseline {calm['best_baseline_total_rest_s'] / 60:.1f} "
            f"min (ratio {_ratio_text(calm['mean_ratio'])}).",
            f"At the manager's price (rest min + 1000 min per A·h not served), over all of them: optimal "
            f"{rest['optimal_total_cost_min']:.1f} min, best baseline by that cost "
            f"{rest['best_baseline_total_cost_min']:.1f} min (ratio {_ratio_text(rest['mean_cost_ratio'])}). Cases "
            f"where the optimal scheduler costs more: {len(rest['cases_optimal_costs_more'])} "
            f"({', '.join(rest['cases_optimal_costs_more']) or 'none'})."]


def rest_table(report: dict, key: str = "rest_vs_best_baseline") -> str:
    """One row per faulty case where anyone rests or leaves load unserved: the optimal
    scheduler's rest and load not served, the best baseline's and the hindsight plan's (``key``:
    :func:`comparison`)."""
    rest = comparison(report, key) or {}
    rows = [c for c in rest.get("per_case", []) if c["optimal_rest_s"] > 0 or c["best_baseline_rest_s"] > 0
            or c.get("optimal_not_served_Ah") or c.get("best_baseline_not_served_Ah")]
    lines = ["| case | optimal rest, min | best baseline rest, min | hindsight rest, min "
             "| not served optimal / baseline / hindsight, A·h | cost optimal / best baseline by cost, min "
             "| cost ratio |", "|---|---|---|---|---|---|---|"]

    def amount(value, digits=2):
        return "–" if value is None else f"{value:.{digits}f}"
    for c in rows:
        hindsight = c.get("hindsight_rest_s")
        lines.append(f"| {c['case']} | {c['optimal_rest_s'] / 60:.1f} | {c['best_baseline_rest_s'] / 60:.1f} "
                     f"({c['best_baseline']}) | {'–' if hindsight is None else f'{hindsight / 60:.1f}'} | "
                     f"{amount(c.get('optimal_not_served_Ah'))} / {amount(c.get('best_baseline_not_served_Ah'))} / "
                     f"{amount(c.get('hindsight_not_served_Ah'))} | {c['optimal_cost_min']:.1f} / "
                     f"{c['best_baseline_cost_min']:.1f} ({c['best_baseline_by_cost']}) | "
                     f"{_ratio_text(c['cost_vs_best_baseline'])} |")
    return "\n".join(lines)


def merge_cases(report: dict, partial: dict) -> dict:
    """``report`` (a whole grid) with the flights of ``partial`` (a re-fly of some of its cases with some
    or all of its schedulers) in place of its own, every summary key recomputed and the re-fly's
    provenance under ``provenance.merged``.

    Raises
    ------
    ValueError
        When ``partial`` names a case the grid does not have, or flies a scheduler the grid does not.
    """
    from genthermal.schedule.sweeps.sweep import summarise

    schedulers, refly_schedulers = list(report["robustness"]["breach_s"]), list(partial["robustness"]["breach_s"])
    if not set(refly_schedulers) <= set(schedulers):
        raise ValueError(f"the re-fly flew {refly_schedulers}, the grid {schedulers}: re-fly some of the grid's "
                         "--schedulers (--add joins new ones)")
    names = [c["name"] for c in report["cases"]]
    unknown = [c["name"] for c in partial["cases"] if c["name"] not in names]
    if unknown:
        raise ValueError(f"cases {unknown} of the re-fly are not in the grid (same --cases and --seed?)")
    new = {c["name"]: c for c in partial["cases"]  # a case the re-fly did not finish keeps the grid's record
           if all(run.get("status", "ok") == "ok" for run in c["runs"].values())}
    # the re-flown schedulers' runs replace the grid's; the others' stay
    cases = [{**case, "runs": {**case["runs"], **new[name]["runs"]}} if name in new else case
             for name, case in zip(names, report["cases"])]
    provenance = dict(report.get("provenance") or {})
    provenance["merged"] = list(provenance.get("merged") or []) + [
        {**(partial.get("provenance") or {}), "cases": sorted(new, key=names.index), "schedulers": refly_schedulers}]
    return {**report, **summarise(cases, schedulers), "provenance": provenance, "cases": cases}


def merged_cases_only(report: dict) -> dict:
    """``report`` (a grid after :func:`merge_cases`) cut to the cases of its last merge, every summary key
    recomputed over them: the figures of a re-fly that did not cover the whole grid, against the same
    cases' baselines, without the grid's own flights of the cases it did not fly."""
    from genthermal.schedule.sweeps.sweep import summarise

    kept = set(report["provenance"]["merged"][-1]["cases"])
    cases = [case for case in report["cases"] if case["name"] in kept]
    return {**report, **summarise(cases, list(report["robustness"]["breach_s"])), "cases": cases}


def add_schedulers(report: dict, other: dict) -> dict:
    """``report`` (a whole grid) with the flights of ``other`` (the same grid flown with other
    schedulers) added to each case, every summary key recomputed over all the schedulers and
    ``other``'s provenance under ``provenance.added``.

    Raises
    ------
    ValueError
        When the two grids differ in their cases or share a scheduler.
    """
    from genthermal.schedule.sweeps.sweep import summarise

    schedulers, added = list(report["robustness"]["breach_s"]), list(other["robustness"]["breach_s"])
    shared = sorted(set(schedulers) & set(added))
    if shared:
        raise ValueError(f"both flew {shared}: use --merge to replace a re-flown scheduler's cases")
    names, other_names = [c["name"] for c in report["cases"]], [c["name"] for c in other["cases"]]
    if names != other_names:
        raise ValueError(f"the grids differ in their cases ({len(names)} against {len(other_names)}, first "
                         f"difference {next((a, b) for a, b in zip(names + [None], other_names + [None]) if a != b)}):"
                         " fly the same --cases and --seed")
    cases = [{**case, "runs": {**case["runs"], **{s: more["runs"][s] for s in added}}}
             for case, more in zip(report["cases"], other["cases"])]
    provenance = dict(report.get("provenance") or {})
    provenance["added"] = list(provenance.get("added") or []) + [{**(other.get("provenance") or {}), "schedulers": added}]
    return {**report, **summarise(cases, schedulers + added), "provenance": provenance, "cases": cases}


def missed_lines(report: dict) -> list[str]:
    """One line per case and scheduler that misses a target, with its cause as the flight reports it."""
    lines = []
    for case in report["cases"]:
        for scheduler, run in case["runs"].items():
            if run.get("status", "ok") != "ok":
                lines.append(f"- {case['name']} / {scheduler}: {run['status']}: {run.get('error')}")
            elif run["breach_s"] > 0:
                peaks = {**run["max_T_winding"]}
                hottest = max(peaks, key=peaks.get)
                response = "; ".join(run.get("manager_response") or []) or "no infeasible plan reported"
                lines.append(f"- {case['name']} / {scheduler}: {run['breach_s']:.0f} s above θmax (hottest "
                             f"{hottest} {peaks[hottest]:.1f} °C, feasible {run['feasible']}, lowest reachable "
                             f"peak {run['lowest_reachable_peak_C'] if run['lowest_reachable_peak_C'] is None else round(run['lowest_reachable_peak_C'], 1)} °C, "
                             f"detected after {_minutes(run.get('detect_delay_s'))} min; manager: {response[:160]})")
    return lines


def plot(report: dict, path: Path) -> None:
    """Breach (s) per case and scheduler, and the optimal/best-baseline added-rest ratio per case (of
    the optimal scheduler on the flown model too, when the grid has it)."""
    cases = report["cases"]
    schedulers = list(report["robustness"]["breach_s"])
    x = np.arange(len(cases))
    width = 0.8 / len(schedulers)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(13, 7), sharex=True)
    failure_labelled = False
    for i, scheduler in enumerate(schedulers):
        runs = [c["runs"][scheduler] for c in cases]
        breach = [r["breach_s"] if r.get("status", "ok") == "ok" else np.nan for r in runs]
        offsets = x + (i - (len(schedulers) - 1) / 2) * width
        top.bar(offsets, breach, width, label=scheduler, color=SCHEDULER_COLOURS.get(scheduler))
        failed = [o for o, r in zip(offsets, runs) if r.get("status", "ok") != "ok"]
        top.plot(failed, [0] * len(failed), "kx", ms=8, label=None if failure_labelled or not failed else "did not finish")
        failure_labelled = failure_labelled or bool(failed)
    top.set_ylabel("time above θmax [s]")
    top.set_yscale("symlog", linthresh=10)
    top.legend(ncol=4, fontsize=8)
    top.grid(alpha=0.3, axis="y")
    top.set_title(f"Robustness grid: {len(cases)} cases (plant ±30 %, unknown fault, 2-4 generators, 2-8 h)")
    compared = [(key, name) for key, name in (("rest_vs_best_baseline", "optimal"), (FLOWN_OPTIMAL_KEY, FLOWN_OPTIMAL))
                if report.get(key)]
    bar_width = 0.8 / max(len(compared), 1)
    for i, (key, name) in enumerate(compared):
        rest = {c["case"]: c for c in report[key].get("per_case", [])}
        ratios = [rest[c["name"]]["ratio"] if c["name"] in rest and rest[c["name"]]["ratio"] is not None else np.nan
                  for c in cases]
        only_optimal = [j for j, c in enumerate(cases) if c["name"] in rest and rest[c["name"]]["ratio"] is None
                        and rest[c["name"]]["optimal_rest_s"] > 0]
        offsets = x + (i - (len(compared) - 1) / 2) * bar_width
        bottom.bar(offsets, ratios, bar_width, color=SCHEDULER_COLOURS[name], label=f"{name} / best baseline added rest")
        bottom.plot(offsets[only_optimal], [1.0] * len(only_optimal), "^", color="red" if i == 0 else "darkred",
                    label=f"{name} rests, baseline does not")
    bottom.axhline(1.0, color="k", lw=0.8)
    bottom.axhline(0.8, color="k", lw=0.8, ls="--", label="target 0.8 (grid mean)")
    bottom.set_ylabel("rest ratio [-]")
    bottom.legend(fontsize=8, loc="center right")
    bottom.grid(alpha=0.3, axis="y")
    bottom.set_xticks(x, [c["name"].split(":")[0] + ":" + c["name"].split(":")[1][:8] for c in cases],
                      rotation=90, fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("json", help="a genthermal sweep --json file")
    parser.add_argument("--png", help="write the plot here (default: next to the JSON, .png)")
    parser.add_argument("--merge", metavar="REFLY_JSON", help="a partial re-fly of the grid: its cases replace "
                        "the grid's, and the JSON is written back with the summary recomputed")
    parser.add_argument("--merged-only", action="store_true", help="with --merge: keep only the cases the re-fly "
                        "flew to the end (a partial grid's figures against the whole grid's baselines)")
    parser.add_argument("--add", metavar="SWEEP_JSON", help="the same grid flown with other schedulers: their "
                        "flights join each case, and the JSON is written back with the summary recomputed")
    args = parser.parse_args(argv)
    path = Path(args.json)
    report = json.loads(path.read_text())
    if "cases" not in report or "robustness" not in report:
        print(f"{path}: not a genthermal sweep JSON (needs 'robustness' and 'cases')", file=sys.stderr)
        return 2
    for option, combine in ((args.merge, merge_cases), (args.add, add_schedulers)):
        if not option:
            continue
        try:
            report = combine(report, json.loads(Path(option).read_text()))
            if combine is merge_cases and args.merged_only:
                report = merged_cases_only(report)
        except (KeyError, ValueError) as error:
            print(f"{option}: cannot {'merge into' if combine is merge_cases else 'add to'} {path}: {error}",
                  file=sys.stderr)
            return 2
        from genthermal.outputs import report_json

        report_json(path, report)
    print(scheduler_table(report))
    print()
    print("\n".join(rest_lines(report)))
    print()
    print(rest_table(report))
    if report.get(FLOWN_OPTIMAL_KEY):
        print(f"\nThe optimal scheduler on the flown model ({FLOWN_OPTIMAL}) against the same baselines:\n")
        print("\n".join(rest_lines(report, FLOWN_OPTIMAL_KEY)))
        print()
        print(rest_table(report, FLOWN_OPTIMAL_KEY))
    missed = missed_lines(report)
    print(f"\nTargets missed ({len(missed)}):" if missed else "\nNo target missed.")
    print("\n".join(missed))
    png = Path(args.png) if args.png else path.with_suffix(".png")
    plot(report, png)
    print(f"\nwrote {png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
