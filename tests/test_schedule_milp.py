"""The MILP scheduler proves its optimum on a small case and says how far it got when stopped early."""

import numpy as np
import pytest

from genthermal.mission import load_mission
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.flight.open_loop import plan_mission
from genthermal.schedule.planning.milp import MilpSettings, milp_objective, milp_plan
from genthermal.schedule.planning.plan import PlanningProblem, Segment, predict
from genthermal.schedule.power_system import AffineGenerator, PowerSystem
from genthermal.schedule.report import flight_summary, summary_text


@pytest.fixture(scope="module")
def six_segments(design_model):
    """A blocked generator (flow 20 %, inlet 51 °C) and a healthy one over six 15 min segments."""
    faulty = AffineGenerator(design_model.with_effect("coolant_flow_reduction", k_flow=0.2, n_flow=0.0))
    healthy = AffineGenerator(design_model)
    inlets = np.array([51.0, 20.0])
    x0 = np.array([g.steady_state(g.input(4.5, t, 20.0)) for g, t in zip((faulty, healthy), inlets)])
    segments = tuple(Segment(i, "cruise", 900.0, ((0.0, 5.5 + 0.5 * (i % 2)),)) for i in range(6))
    return PlanningProblem(segments, [faulty, healthy], x0, inlets, 20.0, 1.911, 7.0, limit_C=108.0,
                           max_rest_s=900.0)


def test_small_case_is_certified_within_one_percent(six_segments):
    result = milp_plan(six_segments, MilpSettings(max_rest_s=900.0))
    details = result.details
    assert result.method == "milp" and details["certified"] and details["plan_used"] == "milp incumbent"
    assert details["bound_min"] <= details["incumbent_objective_min"] + 1e-9
    assert 0.0 <= details["mip_gap"] <= 0.01
    assert details["incumbent_objective_min"] == pytest.approx(milp_objective(six_segments, result.schedule,
                                                                              MilpSettings(max_rest_s=900.0)))
    assert result.feasible and not result.warnings
    assert predict(six_segments, result.schedule).peak()[0] <= six_segments.limit_C + 0.05


def test_stopped_at_once_flies_the_rounded_baseline_and_says_so(six_segments):
    settings = MilpSettings(max_rest_s=900.0, time_limit_s=0.0)
    result = milp_plan(six_segments, settings)
    details = result.details
    assert not details["certified"]
    assert details["plan_used"].startswith("rounded ") and details["plan_used"].endswith("(MILP start)")
    schedule = result.schedule
    assert np.allclose(schedule.rest_before_s % settings.block_s, 0.0)
    assert np.allclose(np.round(schedule.displaced_A / settings.chunk_A) * settings.chunk_A, schedule.displaced_A)
    assert details["incumbent_objective_min"] == pytest.approx(milp_objective(six_segments, schedule, settings))
    assert result.feasible  # the rounded start keeps the limit on the design model
    assert result.warnings and result.warnings[0].startswith("MILP not certified")
    certified = milp_plan(six_segments, MilpSettings(max_rest_s=900.0)).details["incumbent_objective_min"]
    assert certified <= details["incumbent_objective_min"] + 1e-9


def test_no_incumbent_names_the_plan_flown_in_the_plan_record_and_the_text():
    system = PowerSystem.from_mission(load_mission("blockage_large"))
    settings = ManagerSettings(milp=MilpSettings(time_limit_s=0.0, warm_start=False))
    flown = plan_mission(system, "milp", settings)
    plan = flown.plans[0]
    assert plan["method"] == "milp->heuristic" and plan["plan_used"] == "heuristic"
    assert plan["certified"] is False and plan["incumbent_objective_min"] is None
    text = summary_text(flight_summary(flown), system.limit_C)
    assert "flying the thesis heuristic's plan instead" in text
