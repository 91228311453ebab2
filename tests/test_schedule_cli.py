"""`genthermal plan` and `genthermal fly` end to end, and the closed loop on the large blockage."""

import json

import pytest

from genthermal.cli import main
from genthermal.mission import load_mission
from genthermal.schedule.flight.closed_loop import fly
from genthermal.schedule.power_system import PowerSystem
from genthermal.schedule.report import flight_summary

from flight_scenarios import SHORT

FLY_KEYS = {"mission_time_s", "added_rest_s", "max_T_winding", "max_T_iron", "breach_s", "replans",
            "median_solve_s", "displaced_Ah"}


@pytest.mark.slow
def test_closed_loop_keeps_the_true_plant_below_the_limit_on_the_large_blockage():
    system = PowerSystem.from_mission(load_mission("blockage_large"))
    summary = flight_summary(fly(system, "optimal"))
    assert summary["breach_s"] == 0.0
    assert max(summary["max_T_winding"].values()) <= system.limit_C
    assert max(summary["max_T_iron"].values()) <= system.limit_C
    assert summary["replans"] >= 1 and summary["displaced_Ah"] > 0


def test_plan_command_writes_the_keys_and_the_schedule(tmp_path, capsys):
    out = tmp_path / "plan.json"
    assert main(["plan", "blockage_large", "--scheduler", "heuristic", "--json", str(out)]) == 0
    summary = json.loads(out.read_text())
    assert FLY_KEYS <= set(summary) and summary["feasible"]
    assert set(summary["max_T_winding"]) == {"gen1", "gen2"}
    assert [row["action"] for row in summary["schedule"]] == [5, 6, 7, 8]
    assert "rest_before_min" in capsys.readouterr().out


def test_fly_command_end_to_end(tmp_path):
    scenario = tmp_path / "short.yaml"
    scenario.write_text(SHORT)
    out, png = tmp_path / "fly.json", tmp_path / "fly.png"
    assert main(["fly", str(scenario), "--scheduler", "optimal", "--json", str(out), "--plot", str(png)]) == 0
    summary = json.loads(out.read_text())
    assert FLY_KEYS <= set(summary) and summary["closed_loop"] and png.stat().st_size > 0
    assert summary["breach_s"] == 0.0


def test_infeasible_scenario_is_reported_with_the_lowest_peak(tmp_path, capsys):
    scenario = tmp_path / "hot.yaml"
    scenario.write_text(SHORT.replace("generators: {count: 2}", "generators: {count: 2, limit_C: 70}"))
    out = tmp_path / "hot.json"
    assert main(["plan", str(scenario), "--scheduler", "heuristic", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "infeasible: no schedule keeps θ ≤ 70 °C" in text and "lowest reachable peak" in text
    assert not json.loads(out.read_text())["feasible"]


@pytest.mark.parametrize("edit, field", [
    (("k_flow: 0.2", "k_flow: 7"), "faults[0].k_flow"),
    (("count: 2", "count: 1"), "generators.count"),
    (("onset_min: 10", "onset_time: 10"), "faults[0].onset_time"),
])
def test_bad_scenario_fields_exit_2_naming_the_field(tmp_path, capsys, edit, field):
    scenario = tmp_path / "bad.yaml"
    scenario.write_text(SHORT.replace(*edit))
    assert main(["fly", str(scenario), "--json", str(tmp_path / "x.json")]) == 2
    error = capsys.readouterr().err
    assert field in error and "Traceback" not in error


def test_bad_scheduler_exits_2():
    assert main(["plan", "blockage_large", "--scheduler", "magic"]) == 2
