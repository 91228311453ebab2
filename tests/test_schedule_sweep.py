"""The robustness sweep: its cases differ from the planning model, and its summary keys."""

import pytest

from genthermal.cli import main
from genthermal.mission import Mission
from genthermal.schedule.power_system import PowerSystem
from genthermal.schedule.sweep import FAULT_TYPES, robustness_case, summarise


def test_cases_cover_the_grid_and_differ_from_the_planning_model():
    cases = [robustness_case(i) for i in range(60)]
    systems = [PowerSystem.from_mission(Mission.from_dict(c)) for c in cases]
    assert {c["name"].split(":")[1] for c in cases} == set(FAULT_TYPES)
    assert {s.n_generators for s in systems} == {2, 3, 4}
    hours = [s.mission.duration_s / 3600 for s in systems]
    assert 2.0 <= min(hours) and max(hours) <= 8.0 + 1e-9
    factors = [f for s in systems for f in s.plant_mismatch.values()]
    assert min(factors) < 0.8 and max(factors) > 1.2 and all(0.7 - 1e-9 <= f <= 1.3 + 1e-9 for f in factors)
    assert robustness_case(7) == robustness_case(7) != robustness_case(7, seed=1)


def run(breach, rest, delay=None, alarms=0):
    return {"breach_s": breach, "added_rest_s": rest, "detect_delay_s": delay, "false_alarms": alarms}


def test_summary_keys_and_the_best_baseline_ratio():
    records = [
        {"name": "a", "faulty": True, "runs": {"heuristic": run(0, 600), "engineer": run(0, 300),
                                               "optimal": run(20, 150, 300.0)}},
        {"name": "b", "faulty": False, "runs": {"heuristic": run(0, 0), "engineer": run(0, 0),
                                                "optimal": run(0, 0, None, 1)}},
    ]
    summary = summarise(records, ("heuristic", "engineer", "optimal"))
    assert summary["robustness"]["cases"] == 2
    assert summary["robustness"]["breach_s"]["optimal"] == 20
    assert summary["robustness"]["breach_free_fraction"]["optimal"] == pytest.approx(0.5)
    assert summary["rest_vs_best_baseline"] == [pytest.approx(0.5)]  # against the engineer, not the thesis heuristic
    assert summary["detect_delay_s"]["median"] == 300.0
    assert summary["false_alarms"]["on_healthy_flights"] == 1


def test_sweep_rejects_an_unknown_scheduler(tmp_path, capsys):
    assert main(["sweep", "--cases", "1", "--schedulers", "engineer,magic", "--json", str(tmp_path / "s.json")]) == 2
    assert "--schedulers" in capsys.readouterr().err


def test_sweep_prints_json_without_a_file_and_writes_one_with_it(tmp_path, capsys, monkeypatch):
    import json

    import genthermal.schedule.sweep as sweep
    records = [{"name": "a", "faulty": False, "runs": {"engineer": run(0, 0.0)}}]
    monkeypatch.setattr(sweep, "run_sweep", lambda documents, schedulers, *rest: records)
    assert main(["sweep", "--cases", "1", "--schedulers", "engineer"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed["cases"] == records and printed["robustness"]["cases"] == 1
    target = tmp_path / "s.json"
    assert main(["sweep", "--cases", "1", "--schedulers", "engineer", "--json", str(target)]) == 0
    assert json.loads(target.read_text())["cases"] == records
    assert main(["sweep", "--cases", "1", "--schedulers", "engineer", "--json", str(target)]) == 2  # no --force
    assert main(["sweep", "--cases", "1", "--schedulers", "engineer", "--json", str(target), "--force"]) == 0
