"""benchmarks/run.py: every script is registered, outputs are parsed in the forms the scripts print,
targets are collected, and a target that held in the baseline but is missed fails the check."""

import importlib.util
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def dashboard():
    spec = importlib.util.spec_from_file_location("benchmark_dashboard", ROOT / "benchmarks" / "run.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def test_every_script_is_a_registered_benchmark_or_named_as_not_one(dashboard):
    assert dashboard.unregistered_scripts() == []
    for benchmark in dashboard.BENCHMARKS:
        assert (ROOT / "benchmarks" / benchmark.script).exists(), benchmark.script
        assert benchmark.quick is not None or benchmark.reason, f"{benchmark.name}: a full-only benchmark says why"


def test_outputs_are_parsed_as_one_document_json_lines_or_lines_then_a_summary(dashboard):
    one = json.dumps({"a": 1, "targets": {"t": True}}, indent=2)
    assert dashboard.parse_documents(one) == [{"a": 1, "targets": {"t": True}}]
    lines = "\n".join(json.dumps({"model": m, "targets": {"fast": m == "linear"}}) for m in ("linear", "nonlinear"))
    assert [d["model"] for d in dashboard.parse_documents(lines)] == ["linear", "nonlinear"]
    mixed = "building...\n" + json.dumps({"row": 1}) + "\n" + json.dumps({"summary": 2, "targets": {"x": 1 > 0}}, indent=2)
    assert dashboard.parse_documents(mixed) == [{"row": 1}, {"summary": 2, "targets": {"x": True}}]
    assert dashboard.parse_documents("no json here\n") == []


def test_targets_are_labelled_per_document_and_only_booleans_count(dashboard):
    documents = [{"model": "linear", "precision": "single", "targets": {"fast": True, "count": "3/4"}},
                 {"model": "linear", "precision": "double", "targets": {"fast": False}}]
    assert dashboard.collect_targets(documents) == {"linear/single/fast": True, "linear/double/fast": False}
    assert dashboard.figure(documents, "*.precision") == {"linear/single": "single", "linear/double": "double"}
    assert dashboard.figure([{"ratios": {"c": 1.5}}], "ratios.c") == 1.5


def test_a_target_that_held_and_is_missed_or_gone_counts_as_missed(dashboard):
    baseline = {"fast": True, "small": True}
    assert dashboard.missed_baseline({"targets": {"fast": True, "small": True, "new": False}}, baseline) == []
    assert dashboard.missed_baseline({"targets": {"fast": False, "small": True}}, baseline) == ["fast"]
    assert dashboard.missed_baseline({"targets": {"fast": True}}, baseline) == ["small"]  # a crashed run


def test_the_committed_baseline_names_registered_benchmarks(dashboard):
    baseline = json.loads((ROOT / "benchmarks" / "results" / "baseline.json").read_text())["quick"]["targets"]
    names = {b.name for b in dashboard.BENCHMARKS if b.quick is not None}
    assert baseline and all(key.split(":")[0] in names for key in baseline)
    assert all(value is True for value in baseline.values())


def test_check_runs_a_benchmark_again_and_fails_only_when_a_target_is_missed_twice(dashboard, tmp_path, monkeypatch):
    (tmp_path / "baseline.json").write_text(json.dumps({"quick": {"targets": {"milp:certified": True}}}))
    monkeypatch.setattr(dashboard, "BASELINE", tmp_path / "baseline.json")
    monkeypatch.setattr(dashboard, "RESULTS", tmp_path)
    outcomes = []

    def fake_run(benchmark, quick, timeout_s):
        held = outcomes.pop(0)
        return {"status": "ok", "wall_s": 1.0, "command": ["python", benchmark.script], "targets": {"certified": held},
                "figures": {}, "documents": []}

    monkeypatch.setattr(dashboard, "run_one", fake_run)
    outcomes[:] = [False, True]  # missed once (noise), held on the second run
    assert dashboard.main(["--quick", "--only", "milp", "--check", "--no-markdown"]) == 0
    outcomes[:] = [False, False]
    assert dashboard.main(["--quick", "--only", "milp", "--check", "--no-markdown"]) == 1
    written = json.loads((tmp_path / "quick.json").read_text())
    assert written["summary"]["baseline_missed"] == ["milp:certified"] and not outcomes


def test_a_benchmark_whose_program_is_missing_is_skipped_not_failed(dashboard, tmp_path, monkeypatch):
    (tmp_path / "baseline.json").write_text(json.dumps({"quick": {"targets": {"embedded:x/flash": True}}}))
    monkeypatch.setattr(dashboard, "BASELINE", tmp_path / "baseline.json")
    monkeypatch.setattr(dashboard, "RESULTS", tmp_path)
    monkeypatch.setattr(dashboard.shutil, "which", lambda name: None)
    monkeypatch.setattr(dashboard, "run_one", lambda *a: pytest.fail("a skipped benchmark must not run"))
    assert dashboard.main(["--quick", "--only", "embedded", "--check", "--no-markdown", "--write-baseline"]) == 0
    written = json.loads((tmp_path / "quick.json").read_text())["benchmarks"]["embedded"]
    assert "qemu-system-arm" in written["skipped"]
    assert json.loads((tmp_path / "baseline.json").read_text())["quick"]["targets"] == {"embedded:x/flash": True}
