"""Time ``genthermal diagnose`` on 4-hour records at 10 s (1441 samples).

Three runs, each from a cold start (models and simulators built inside the timing):

* ``single``: one hidden catalogue effect, the catalogue searched (singles; pairs only if one
  effect leaves the residual unexplained);
* ``pair``: two hidden effects (a blockage from 80 min on top of an end-winding stray loss from
  the start), the catalogue searched with jointly fitted pairs;
* ``open``: the open search over the generic heat-flow library on a record with an excitation
  iron loss from 1.4 h;
* ``lookalike``: a shorted turn from 50 min under balanced load (it looks like end-winding stray
  loss) with the winding lumped (``phases="lumped"``: the record's three phase sensors read one
  plant node, and trusted as phase sensors they would rule the shorted turn out): the separating
  test designed and the separation it predicts;
* ``full``: the whole issue-12 diagnosis of the two-effect record of ``pair``: the catalogue with
  jointly fitted pairs, then the open search over the generic library with its pairs, one
  :class:`~genthermal.diagnose.discovery.Discovery` (what the catalogue search built is reused).

Usage: ``python benchmarks/bench_diagnose.py [--json FILE] [--only single|pair|open|lookalike|full]
[--workers N]``. Prints progress with elapsed wall and CPU seconds, then one JSON document per run:
``wall_s`` (elapsed), ``cpu_s`` (CPU seconds of this process and its workers), ``load_avg`` (the
1-minute load average at the end: on a shared machine the wall time depends on the other load),
``critical_cpu_s`` (this process's CPU plus the busiest worker's of each parallel map: the wall
time on an idle machine with a core per worker cannot be less), ``stages`` (wall, CPU and critical
CPU of each stage, a stage ending at each progress line), verdict, ground truth, final RMSE; target
≤ 60 s wall each.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import time
from pathlib import Path

from genthermal.diagnose.discovery import Discovery
from genthermal.diagnose.fitter import OnsetFitter
from genthermal.diagnose.hidden import Injection, make_hidden_effect_case
from genthermal.diagnose.open_search import describe_term, heat_flow_library
from genthermal.diagnose.parallel import cpu_clock
from genthermal.machines import build_model

TWO_EFFECTS = [Injection("coolant_flow_reduction", {"k_flow": 0.6}, 4800.0),
               Injection("end_winding_stray_loss", {"R_stray": 0.2}, 0.0)]
#: name: (hidden effects, searches: "catalogue" and/or "open")
RUNS = {
    "single": ("coolant_flow_reduction", ("catalogue",)),
    "pair": (TWO_EFFECTS, ("catalogue",)),
    "open": ([Injection("excitation_iron_loss", {"k_exc": 30.0}, 5000.0)], ("open",)),
    "lookalike": ([Injection("phase_short_circuit", {"R_short": 0.3}, 3000.0)], ("catalogue",)),
    "full": (TWO_EFFECTS, ("catalogue", "open")),
}


def _cpu_seconds() -> float:
    """CPU seconds of this process and of its finished worker processes."""
    times = os.times()
    return times.user + times.system + times.children_user + times.children_system


#: A progress line of one pair among several ("pair 3/8 fitted: a + b (onset grid)").
_PAIR_LINE = re.compile(r"pair (\d+)/(\d+) fitted: (?:swap: )?.*?(\(.*\))?$")


def _stage_label(line: str) -> str | None:
    """The stage a progress line ends, or None for a pair that is not the last of its map."""
    match = _PAIR_LINE.match(line)
    if match is None:
        return line[:90]
    done, total, what = match.groups()
    if done != total:
        return None
    what = (what or "").split(":")[0].rstrip(")") + (")" if what else "")  # "(on the full series: polished)"
    return f"{total} pairs {'swapped ' if 'swap: ' in line else ''}{what}".strip()


class StageTimer:
    """Wall and CPU time of each stage of a run, a stage ending at each progress line."""

    def __init__(self):
        self.started, self.cpu_started, self.clock_started = time.perf_counter(), _cpu_seconds(), cpu_clock()
        self.stage_started, self.stage_clock = self.started, self.clock_started
        self.search, self.stages = "", []

    def progress(self, line: str) -> None:
        """Print ``line`` with the elapsed wall and CPU time; close the stage it ends."""
        now, clock = time.perf_counter(), cpu_clock()
        print(f"  [{now - self.started:5.1f} s wall, {(clock - self.clock_started).total_s:5.1f} s cpu] "
              f"{line[:110]}", file=sys.stderr, flush=True)
        label = _stage_label(line)
        if label is None:
            return
        spent = clock - self.stage_clock
        self.stages.append({"search": self.search, "stage": label, "wall_s": round(now - self.stage_started, 2),
                            "cpu_s": round(spent.total_s, 2), "workers_cpu_s": round(spent.workers_s, 2),
                            "critical_cpu_s": round(spent.critical_s, 2)})
        self.stage_started, self.stage_clock = now, clock

    def totals(self) -> dict:
        """Elapsed wall, CPU (this process and its reaped workers) and critical CPU, s."""
        return {"wall_s": round(time.perf_counter() - self.started, 2),
                "cpu_s": round(_cpu_seconds() - self.cpu_started, 2),
                "critical_cpu_s": round((cpu_clock() - self.clock_started).critical_s, 2)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the results to this file as well")
    parser.add_argument("--only", choices=list(RUNS), help="run only this case")
    parser.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1),
                        help="worker processes of the fits (default: both cores)")
    args = parser.parse_args()
    documents = []
    for name, (effects, searches) in RUNS.items():
        if args.only and name != args.only:
            continue
        model = build_model()
        case = make_hidden_effect_case(effects, mission="thesis_fig_7_7", dt_s=10.0, seed=3, plant=model)
        timer = StageTimer()
        discovery = Discovery(fitter=OnsetFitter(workers=args.workers), progress=timer.progress,
                              phases="lumped" if name == "lookalike" else "auto")
        results = {}
        for search in searches:
            timer.search = search
            searched = discovery if search == "catalogue" else discovery.with_settings(
                candidates=heat_flow_library(model))
            results[search] = searched.fit(model, case.data)
            timer.progress(f"{search} search done: {results[search].verdict}")
        result = results[searches[0]]
        document = {"benchmark": f"diagnose {name}, 4 h at 10 s", "searches": list(searches),
                    "samples": int(result.series.time_s.size), "workers": args.workers,
                    "candidates": sum(len(r.iterations[0].ranked) for r in results.values()),
                    "pairs": sum(len(r.iterations[0].pairs) for r in results.values()),
                    **timer.totals(), "target_seconds": 60, "load_avg": round(os.getloadavg()[0], 2),
                    "verdict": result.verdict,
                    "found": [{"effect": f.effect, "onset_h": round(f.onset_s / 3600, 3), "params": f.values}
                              for f in result.found],
                    "truth": case.truth()["effects"], "rmse_final_K": round(result.iterations[-1].rmse_after, 4),
                    "noise_std_estimated_K": round(result.noise_std, 4), "unexplained": result.unexplained}
        if result.experiment:
            document["experiment"] = {k: v for k, v in result.experiment.to_dict().items() if k != "scenario"}
            document["experiment"]["blocks"] = result.experiment.to_dict()["scenario"]["actions"]
        if "open" in results:
            document["open_search"] = {"verdict": results["open"].verdict,
                                       "described": [describe_term(f, results["open"].catalogue)
                                                     for f in results["open"].found]}
        document["stages"] = timer.stages
        named = {f["effect"] for f in document["found"]} == {t["effect"] for t in document["truth"]}
        document["targets"] = {"names_the_hidden_effects": named if name != "open" else bool(document["found"]),
                               "within_target_seconds": document["wall_s"] <= document["target_seconds"]}
        documents.append(document)
        print(json.dumps(document), flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(documents, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
