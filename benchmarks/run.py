"""The benchmark dashboard: run every benchmark, collect its figures and targets, check them.

``python benchmarks/run.py --quick`` runs the benchmarks that have a small size (the whole set in a
few minutes); ``--full`` runs every benchmark at the sizes the docs quote. Each benchmark runs as a
child process (``python benchmarks/<script> ...``) and prints JSON; its documents and the targets
they state (``"targets": {name: true/false}``) go into one JSON file
(``benchmarks/results/quick.json`` or ``full.json``) and one Markdown table
(``docs/results/benchmarks.md``).

``--check`` compares the targets with the committed baseline ``benchmarks/results/baseline.json``
(per size, the targets that held when it was written) and exits 1 when one of them is missed; a benchmark
that misses one is run once more first, and only a target missed both times counts (timing ratios
on a shared machine are noisy: the benchmarks time their methods side by side in one process and
take medians, and the Cortex-M figures are instruction counts of QEMU ``-icount``, which do not
vary). ``--write-baseline`` records the targets that held in this run as the new baseline.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
BASELINE = RESULTS / "baseline.json"
MARKDOWN = ROOT / "docs" / "results" / "benchmarks.md"


@dataclasses.dataclass(frozen=True)
class Benchmark:
    """One script of ``benchmarks/`` and how the dashboard runs it.

    Attributes
    ----------
    name : str
        Key in the results.
    script : str
        File name in ``benchmarks/``.
    full : tuple of str
        Arguments of the full run (the sizes the docs quote).
    quick : tuple of str or None
        Arguments of the quick run; None: full runs only (``reason`` says why).
    json_flag : bool
        The script takes ``--json FILE`` (else its standard output is read).
    figures : tuple of str
        Dotted paths of the figures shown in the Markdown table (``*`` over JSON lines).
    reason : str
        Why a benchmark is full-only, what it needs, or why targets are unchecked.
    unchecked : tuple of str
        Targets reported but never written into the baseline (absolute wall times).
    requires : dict of str to tuple
        Programs on PATH and the targets that need them (empty: the whole benchmark); without one,
        those targets are not checked (the benchmark is skipped when it needs the program itself).
    """

    name: str
    script: str
    full: tuple = ()
    quick: tuple | None = ()
    json_flag: bool = True
    figures: tuple = ()
    reason: str = ""
    unchecked: tuple = ()
    requires: dict = dataclasses.field(default_factory=dict)


BENCHMARKS = (
    Benchmark("simulate", "bench_simulate.py", ("--repeats", "7"), ("--repeats", "3"),
              figures=("ratios.c_over_floor.linear", "ratios.c_over_floor.nonlinear",
                       "ratios.c_over_floor_instructions.linear", "ratios.c_over_floor_instructions.nonlinear",
                       "ratios.scipy_bdf_over_c.linear", "ratios.scipy_bdf_over_c.nonlinear",
                       "max_abs_diff_from_python_step_K.linear.floor"),
              requires={"valgrind": ("c_linear_instructions_within_3x_floor", "c_nonlinear_instructions_within_6x_floor")}),
    Benchmark("kalman", "bench_kalman.py", figures=("c_update_ns", "ekf_c_update_ns"),
              unchecked=("c_update_within_1_us",),
              reason="c_update_within_1_us is an absolute wall time: reported, not checked on a shared machine"),
    Benchmark("embedded", "bench_embedded.py",
              figures=("*.load_percent_at_100MHz_1cpi", "*.max_error_vs_host_K", "*.instructions_step"),
              requires={"arm-none-eabi-gcc": (), "qemu-system-arm": ()},
              reason="needs arm-none-eabi-gcc, newlib and qemu-system-arm (.ci/run installs them)"),
    Benchmark("fmu", "bench_fmu.py", figures=("*.max_error_K_ModelExchange", "*.max_error_K_CoSimulation")),
    Benchmark("milp", "bench_milp.py", (), ("--hours", "2", "--generators", "2", "--no-nlp"), json_flag=False,
              figures=("*.certified", "*.wall_s")),
    Benchmark("diagnose", "bench_diagnose.py", (), ("--only", "single"), figures=("*.verdict", "*.wall_s", "*.cpu_s"),
              unchecked=("within_target_seconds",),
              reason="within_target_seconds is an absolute wall time: reported, not checked"),
    Benchmark("followed_as_data", "bench_followed_as_data.py", ("--scenario", "blockage_large", "--scheduler", "optimal"),
              None, json_flag=False, figures=("files_entered", "objects.model.n_files", "objects.system.n_files",
                                              "objects.settings.n_files"),
              reason="one traced 4-h flight, about 1 min"),
    Benchmark("replan", "bench_replan.py", json_flag=False, quick=None,
              reason="two 4-h closed-loop flights with the optimal scheduler: 30 s idle, 280 s at load 11"),
    Benchmark("replan_build", "bench_replan_build.py", json_flag=False, quick=None,
              figures=("expanded.build_cpu_s", "mx.build_cpu_s", "total_ratio_mx_to_expanded"),
              reason="a grid flight to its first flown-model re-plan and two solver builds, about 40 s"),
    Benchmark("sensor_flights", "bench_sensor_flights.py", (), ("--only", "T_winding-bias+4-gen1"),
              figures=("right_sensor", "sensor_flights", "replans_caused")),
    Benchmark("detection", "bench_detection.py", ("--healthy", "20", "--faulty", "8"), None,
              reason="closed-loop flights: 150 s for 3 flights at load 11"),
    Benchmark("inlet_hold_price", "bench_inlet_hold_price.py", quick=None,
              reason="5 scenarios x every scheduler, each flown twice"),
    Benchmark("inlet_confirmation", "bench_inlet_confirmation.py", quick=None,
              reason="healthy, bias and rise flights per noise seed"),
    Benchmark("prediction", "bench_prediction.py", quick=None,
              reason="calibrations and filters on 2 plants x 3 noise draws x 4 records"),
    Benchmark("sensor_faults", "bench_sensor_faults.py", ("--seeds", "2"), None,
              reason="diagnose on every (sensor, fault kind) record: tens of 4-h diagnoses"),
    Benchmark("scheduler", "bench_scheduler.py", (), None,
              reason="30 closed-loop scenarios x 4 schedulers: 400-830 s per mission"),
    Benchmark("long_record", "bench_long_record.py", (), None, json_flag=False,
              reason="one week at 1 s through diagnose: about 210 s and 1.4 GB at its smallest meaningful size"),
    Benchmark("joint", "bench_joint.py", (), None, reason="8 joint pair searches, about 10 min"),
    Benchmark("open_search", "bench_open_search.py", (), None, reason="8 leave-one-out open searches, about 18 min"),
    Benchmark("sensor_robustness", "bench_sensor_robustness.py", (), None,
              reason="every (sensor, fault) pair diagnosed blind: tens of minutes"),
    Benchmark("reproduce_thesis", "reproduce_thesis.py", (), None,
              reason="every published outcome of chapters 3-7 with its flights: tens of minutes"),
    Benchmark("chapter7_feasibility", "chapter7_feasibility.py", ("--quick",), None,
              reason="an IPOPT calibration over the chapter-7 outcomes: minutes even at --quick"),
    Benchmark("fit_chapter7", "fit_chapter7.py", (), None, reason="the chapter-7 calibration: about 10 min"),
    Benchmark("managed_blockage", "managed_blockage.py", (), None, reason="managed blockage studies: about 5 min"),
    Benchmark("independent", "bench_independent.py", ("--jobs", "2", "--plants", "2", "--faults"), None,
              json_flag=False, reason="command-line diagnosis of 30 independent and injected 4-h records: "
              "12-70 CPU-s each; needs ../shared/records"),
    Benchmark("ipmsm", "bench_ipmsm.py", (), None, json_flag=False,
              reason="cross-validated calibration over 12 real bench profiles (4 folds and one fit over all): "
              "about 10 min; needs ../shared/records"),
    Benchmark("ipmsm_diagnose", "bench_ipmsm_diagnose.py", (), None, json_flag=False,
              reason="diagnosis of the plain model on 4 folds of the real bench profiles, then a calibration "
              "with the effect named: about 10 min; needs ../shared/records"),
)
#: Scripts of ``benchmarks/`` that are not benchmarks (helpers, report writers), with what they are.
NOT_BENCHMARKS = {
    "run.py": "this dashboard",
    "readme_figures.py": "redraws the README's pictures",
    "robustness_report.py": "report of a `genthermal sweep` JSON (the robustness grid is the sweep)",
    "flight_evidence_compare.py": "table of two partial `genthermal sweep` re-flies side by side (before/after a change)",
    "prediction_references.py": "helper of bench_prediction.py",
    "sensor_robustness_records.py": "helper of bench_sensor_robustness.py",
    "ipmsm_rotor_candidates.py": "study of rotor terms for the bench IPMSM, none kept (docs/results/ipmsm.md, round 4)",
}


def unregistered_scripts() -> list:
    """Scripts of ``benchmarks/`` that are neither in :data:`BENCHMARKS` nor in :data:`NOT_BENCHMARKS`."""
    known = {b.script for b in BENCHMARKS} | set(NOT_BENCHMARKS)
    return sorted(p.name for p in (ROOT / "benchmarks").glob("*.py") if p.name not in known)


def parse_documents(text: str) -> list:
    """JSON documents of a benchmark's output: one document, JSON lines, or lines then an
    indented summary (the forms the scripts print)."""
    text = text.strip()
    if not text:
        return []
    try:
        document = json.loads(text)
        return document if isinstance(document, list) else [document]
    except json.JSONDecodeError:
        pass
    documents, lines = [], text.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("{") or line.startswith("["):
            try:
                documents.append(json.loads(line))
                i += 1
                continue
            except json.JSONDecodeError:
                try:  # an indented document to the end of the output
                    documents.append(json.loads("\n".join(lines[i:])))
                    break
                except json.JSONDecodeError:
                    pass
        i += 1
    return documents


def _label(document: dict, index: int, n_documents: int) -> str:
    """Name of one document among several (JSON lines): its identifying fields, else its index."""
    if n_documents == 1:
        return ""
    keys = [str(document[k]) for k in ("model", "precision", "variant", "case", "name") if k in document]
    keys += [f"{document[k]:g}{unit}" for k, unit in (("hours", "h"), ("generators", "gen")) if k in document]
    return "/".join(keys) if keys else str(index)


def collect_targets(documents: list) -> dict:
    """``{"<label>/<target>": bool}`` of every boolean in a ``targets`` block of the documents."""
    targets = {}
    for index, document in enumerate(documents):
        if not isinstance(document, dict) or not isinstance(document.get("targets"), dict):
            continue
        label = _label(document, index, len(documents))
        for name, value in document["targets"].items():
            if isinstance(value, bool):
                targets[f"{label}/{name}" if label else name] = value
    return targets


def figure(documents: list, path: str):
    """The value at a dotted ``path`` (``*.x``: over every document), or None."""
    star = path.startswith("*.")
    keys = (path[2:] if star else path).split(".")
    values = []
    for index, document in enumerate(documents if star else documents[-1:]):
        value = document
        for key in keys:
            value = value.get(key) if isinstance(value, dict) else None
        if value is not None:
            values.append((_label(document, index, len(documents)), value))
    if not values:
        return None
    return dict(values) if star and len(values) > 1 else values[0][1]


def run_one(benchmark: Benchmark, quick: bool, timeout_s: float) -> dict:
    """Run one benchmark as a child process; its documents, targets, wall time and status."""
    arguments = list(benchmark.quick if quick else benchmark.full)
    with tempfile.TemporaryDirectory(prefix="gt-bench-") as scratch:
        output = Path(scratch) / "out.json"
        if benchmark.json_flag:
            arguments += ["--json", str(output)]
        command = [sys.executable, str(ROOT / "benchmarks" / benchmark.script), *arguments]
        environment = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
                       "MPLBACKEND": "Agg"}
        start = time.perf_counter()
        try:
            result = subprocess.run(command, capture_output=True, text=True, timeout=timeout_s, cwd=ROOT,
                                    env=environment)
        except subprocess.TimeoutExpired:
            return {"status": f"timeout after {timeout_s:g} s", "wall_s": timeout_s, "command": command[1:],
                    "targets": {}, "documents": []}
        wall = time.perf_counter() - start
        text = output.read_text() if benchmark.json_flag and output.exists() else result.stdout
    documents = parse_documents(text)
    status = "ok" if result.returncode == 0 else f"exit {result.returncode}: {result.stderr.strip()[-600:]}"
    if result.returncode == 0 and not documents:
        status = "no JSON output"
    return {"status": status, "wall_s": round(wall, 1),
            "command": ["python", f"benchmarks/{benchmark.script}", *arguments[:-2 if benchmark.json_flag else None]],
            "targets": collect_targets(documents),
            "figures": {path: figure(documents, path) for path in benchmark.figures},
            "documents": documents}


def missed_baseline(entry: dict, baseline: dict) -> list:
    """Targets that held in the baseline and do not hold now (missing counts as missed)."""
    return [name for name, held in baseline.items() if held and entry.get("targets", {}).get(name) is not True]


def markdown(results: dict) -> str:
    """The dashboard as a Markdown page."""
    mode = results["mode"]
    lines = [
        "# Benchmarks: figures and targets", "",
        f"Written by `python benchmarks/run.py --{mode}` on {results['finished_utc']} (UTC), "
        f"{results['wall_s']:.0f} s wall, load average {results['load_average']} at the start "
        f"({os.cpu_count()} cores, shared). Every figure below comes from that run; the JSON is "
        f"`benchmarks/results/{mode}.json`. Timing ratios are medians of repeats measured side by side in "
        "one process; the Cortex-M figures are instruction counts (QEMU `-icount`), the same on every run.", "",
        "| benchmark | command | wall (s) | targets met | targets missed | figures |",
        "|---|---|---|---|---|---|",
    ]
    for name, entry in results["benchmarks"].items():
        if "skipped" in entry:
            lines.append(f"| {name} | `{entry['command']}` | | | | {entry['skipped']} |")
            continue
        met = [t for t, v in entry["targets"].items() if v]
        missed = [t for t, v in entry["targets"].items() if not v]
        shown = "; ".join(f"{k} = {_short(v)}" for k, v in entry.get("figures", {}).items() if v is not None)
        status = "" if entry["status"] == "ok" else f"**{entry['status'][:120]}** "
        lines.append(f"| {name} | `{' '.join(entry['command'])}` | {entry['wall_s']} | {len(met)} | "
                     f"{', '.join(missed) or '-'} | {status}{shown} |")
    if results.get("baseline_missed"):
        lines += ["", "**Targets of the baseline missed** (twice): " + ", ".join(results["baseline_missed"])]
    lines += ["", "Run it with `python benchmarks/run.py --quick` (the benchmarks with a small size) or `--full` "
              "(every benchmark at the sizes the docs quote; hours). CI runs `--quick --check`: it fails when a "
              "target recorded in `benchmarks/results/baseline.json` is missed in two runs of its benchmark. "
              "Absolute wall times (the Kalman update within 1 µs, diagnose within 60 s) are reported, not "
              "checked; the simulation targets are checked both as wall-time ratios and as instruction counts "
              "(valgrind's callgrind). `--write-baseline` records the targets a run met.",
              "", "Targets per benchmark (✓ met, ✗ missed):", ""]
    for name, entry in results["benchmarks"].items():
        if entry.get("targets"):
            lines.append(f"* **{name}**: " + ", ".join(f"{t} {'✓' if v else '✗'}" for t, v in entry["targets"].items()))
    return "\n".join(lines) + "\n"


def _short(value) -> str:
    if isinstance(value, float):
        return f"{value:.3g}"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {_short(v)}" for k, v in value.items()) + "}"
    return str(value)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    size = parser.add_mutually_exclusive_group(required=True)
    size.add_argument("--quick", action="store_true", help="every benchmark that has a small size (a few minutes)")
    size.add_argument("--full", action="store_true", help="every benchmark at the sizes the docs quote (hours)")
    parser.add_argument("--only", nargs="+", metavar="NAME", choices=[b.name for b in BENCHMARKS],
                        help="run only these benchmarks")
    parser.add_argument("--check", action="store_true",
                        help="exit 1 when a target of benchmarks/results/baseline.json is missed (twice)")
    parser.add_argument("--write-baseline", action="store_true", help="record the targets met in this run as the baseline")
    parser.add_argument("--timeout", type=float, default=None, help="per benchmark, s (default 600 quick, 7200 full)")
    parser.add_argument("--no-markdown", action="store_true", help="do not write docs/results/benchmarks.md")
    args = parser.parse_args(argv)
    mode = "quick" if args.quick else "full"
    timeout = args.timeout or (600.0 if args.quick else 7200.0)
    baselines = json.loads(BASELINE.read_text()) if BASELINE.exists() else {}
    baseline = baselines.get(mode, {}).get("targets", {})  # the quick and the full run name targets apart
    results = {"mode": mode, "started_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M"),
               "load_average": round(os.getloadavg()[0], 1), "benchmarks": {}, "not_benchmarks": NOT_BENCHMARKS}
    start = time.perf_counter()
    for benchmark in BENCHMARKS:
        if args.only and benchmark.name not in args.only:
            continue
        if args.quick and benchmark.quick is None:
            results["benchmarks"][benchmark.name] = {"skipped": f"full runs only: {benchmark.reason}",
                                                     "command": f"python benchmarks/{benchmark.script}"}
            continue
        missing = [tool for tool in benchmark.requires if shutil.which(tool) is None]
        if any(not benchmark.requires[tool] for tool in missing):
            results["benchmarks"][benchmark.name] = {"skipped": f"{', '.join(missing)} not found: {benchmark.reason}",
                                                     "command": f"python benchmarks/{benchmark.script}"}
            continue
        entry = run_one(benchmark, args.quick, timeout)
        untestable = {t for tool in missing for t in benchmark.requires[tool]}
        expected = {k[len(benchmark.name) + 1:]: v for k, v in baseline.items()
                    if k.startswith(benchmark.name + ":") and k[len(benchmark.name) + 1:] not in untestable}
        if args.check and missed_baseline(entry, expected):
            first = missed_baseline(entry, expected)
            entry = run_one(benchmark, args.quick, timeout)  # once more: a target must be missed twice
            entry["missed_in_first_run"] = first
        entry["baseline_missed"] = missed_baseline(entry, expected) if args.check else []
        results["benchmarks"][benchmark.name] = entry
        print(json.dumps({"benchmark": benchmark.name, "status": entry["status"][:200], "wall_s": entry["wall_s"],
                          "targets": entry["targets"], "figures": entry["figures"]}), flush=True)
    for script in unregistered_scripts():  # a new benchmark shows up until it is registered
        results["benchmarks"][script.removesuffix(".py")] = {
            "skipped": "not registered in benchmarks/run.py: add it to BENCHMARKS (or NOT_BENCHMARKS)",
            "command": f"python benchmarks/{script}"}
    results["wall_s"] = round(time.perf_counter() - start, 1)
    results["finished_utc"] = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M")
    results["baseline_missed"] = [f"{name}:{t}" for name, e in results["benchmarks"].items()
                                  for t in e.get("baseline_missed", [])]
    results["summary"] = {
        "benchmarks_run": sum("skipped" not in e for e in results["benchmarks"].values()),
        "full_only": sorted(n for n, e in results["benchmarks"].items() if e.get("skipped", "").startswith("full")),
        "unregistered": unregistered_scripts(),
        "failed": sorted(n for n, e in results["benchmarks"].items() if e.get("status", "ok") != "ok"),
        "targets_met": sum(v for e in results["benchmarks"].values() for v in e.get("targets", {}).values()),
        "targets_missed": sorted(f"{n}:{t}" for n, e in results["benchmarks"].items()
                                 for t, v in e.get("targets", {}).items() if not v),
        "baseline_missed": results["baseline_missed"], "wall_s": results["wall_s"]}
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / f"{mode}.json").write_text(json.dumps(results, indent=1, default=str) + "\n")
    if not args.no_markdown:
        MARKDOWN.parent.mkdir(parents=True, exist_ok=True)
        MARKDOWN.write_text(markdown(results))
    if args.write_baseline:
        unchecked = {b.name: b.unchecked for b in BENCHMARKS}
        held = {f"{n}:{t}": True for n, e in results["benchmarks"].items() for t, v in e.get("targets", {}).items()
                if v and not any(t == u or t.endswith("/" + u) for u in unchecked.get(n, ()))}
        ran = {n for n, e in results["benchmarks"].items() if "skipped" not in e}
        kept = {k: v for k, v in baseline.items() if k.split(":")[0] not in ran}
        baselines[mode] = {"written_by": f"python benchmarks/run.py --{mode} --write-baseline",
                           "written_utc": results["finished_utc"], "targets": dict(sorted({**kept, **held}.items()))}
        BASELINE.write_text(json.dumps(baselines, indent=1) + "\n")
    print(json.dumps({"summary": results["summary"]}))
    failed = args.check and (results["baseline_missed"] or results["summary"]["failed"])
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
