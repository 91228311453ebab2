"""The default scheduler: ``planner_model`` ``auto`` (each planner's own model, as the filter allows)
and the verdict before take-off (``preflight``: whether any plan holds θmax)."""

import json

import pytest

from genthermal.cli import main
from genthermal.errors import InputError
from genthermal.mission import load_mission
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.flight.preflight import preflight_check
from genthermal.schedule.planning.plan import FEASIBLE_TOLERANCE_K
from genthermal.schedule.planning.registry import model_for, planner, register_planner
from genthermal.schedule.power_system import PowerSystem

from flight_scenarios import SHORT


def test_auto_plans_the_optimal_scheduler_on_the_flown_model_only_with_the_extended_kalman_filter():
    assert ManagerSettings().planner_model == "auto"
    assert planner("optimal").default_model == "nonlinear"
    assert {name: model_for(name, "auto", "ekf") for name in ("heuristic", "engineer", "optimal", "milp")} == {
        "heuristic": "affine", "engineer": "affine", "optimal": "nonlinear", "milp": "affine"}
    assert model_for("optimal", "auto", "kf") == "affine"  # the thesis's linear filter has no flown model
    assert model_for("optimal", "affine", "ekf") == "affine" and model_for("heuristic", "nonlinear", "ekf") == "nonlinear"
    resolved = ManagerSettings().for_flight("optimal", "ekf")
    assert resolved.nonlinear and not ManagerSettings().for_flight("optimal", "kf").nonlinear


def test_a_planner_declaring_a_model_it_cannot_plan_on_is_refused():
    with pytest.raises(InputError, match="default_model.*nonlinear.*does not plan on the flown model"):
        register_planner("design_only", lambda problem, settings, previous: None, default_model="nonlinear")
    with pytest.raises(InputError, match="default_model.*quadratic"):
        register_planner("odd_model", lambda problem, settings, previous: None, default_model="quadratic")


@pytest.mark.slow
def test_a_mission_no_plan_can_hold_says_so_before_take_off_and_breaches(tmp_path, capsys):
    """θmax 70 °C on the short blockage, no load shed: the verdict before take-off is printed before
    the flight's lines and recorded in its JSON; the flight then breaches, as it said."""
    scenario = tmp_path / "hot.yaml"
    scenario.write_text(SHORT.replace("generators: {count: 2}", "generators: {count: 2, limit_C: 70}"))
    out = tmp_path / "hot.json"
    assert main(["fly", str(scenario), "--when-infeasible", "best-effort", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    said = text.index("before take-off: no plan holds θmax 70 °C")
    assert said < text.index("mission time") and "(feasible: false; planning on the nonlinear model)" in text
    summary = json.loads(out.read_text())
    preflight = summary["preflight"]
    assert not preflight["feasible"] and not preflight["holds_limit"] and not summary["feasible"]
    assert preflight["lowest_reachable_peak_C"] > 70.0 + FEASIBLE_TOLERANCE_K
    assert preflight["planned_peak_C"] > 70.0 + FEASIBLE_TOLERANCE_K  # the plan's own forecast, no back-off
    assert summary["planner_model"] == "nonlinear" and summary["breach_s"] > 0


def test_a_mission_a_plan_can_hold_says_so_and_holds_it(tmp_path, capsys):
    scenario = tmp_path / "short.yaml"
    scenario.write_text(SHORT)
    out = tmp_path / "short.json"
    assert main(["fly", str(scenario), "--json", str(out)]) == 0
    assert "before take-off: a plan holds θmax 110 °C" in capsys.readouterr().out
    summary = json.loads(out.read_text())
    assert summary["preflight"]["feasible"] and summary["preflight"]["planned_peak_C"] <= 110.0 + FEASIBLE_TOLERANCE_K
    assert summary["breach_s"] == 0.0 and summary["planner_model"] == "nonlinear"


def test_the_chapter7_large_blockage_with_the_linear_filter_says_before_take_off_that_it_breaches():
    """The thesis's large blockage (7.3.3) with the manager's linear filter plans on the design model:
    that plan holds 110 °C on the design model's forecast, but the manager's own nonlinear model of
    the same flight says it breaches (flown, it spends ~1690 s above θmax): feasible false before
    take-off, naming the way out; with the extended Kalman filter a plan on the flown model holds."""
    system = PowerSystem.from_mission(load_mission("chapter7_blockage_large"))
    verdict = preflight_check(system, "optimal", ManagerSettings())
    assert verdict["planner_model"] == "affine" and verdict["faults"] == 1
    assert verdict["planned_peak_C"] <= 110.0 + FEASIBLE_TOLERANCE_K < verdict["flown_model_peak_C"]
    assert not verdict["feasible"] and not verdict["holds_limit"] and "--filter ekf" in verdict["message"]
    system.filter = "ekf"  # what --filter ekf makes of the scenario's say
    verdict = preflight_check(system, "optimal", ManagerSettings())
    assert verdict["planner_model"] == "nonlinear" and verdict["feasible"] and verdict["flown_model_peak_C"] is None
