"""``when_infeasible``: what the load manager does when even the lowest reachable peak is above θmax.

``shed`` (the default, ``tests/test_closed_loop_shed.py``) sheds load; ``best_effort`` is the thesis
heuristic, which has no load shedding: it displaces and rests as far as it can, serves all load and
reports the breach it predicts (thesis 7.3.3's managed large blockage breached 110.7 and 111 °C).
"""

import argparse

import numpy as np
import pytest

from genthermal.cli import main
from genthermal.commands.plan import add_schedule_arguments, settings_from_args
from genthermal.errors import InputError
from genthermal.mission import load_mission
from genthermal.schedule.flight.closed_loop import fly
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.power_system import PowerSystem
from genthermal.schedule.report import flight_summary

from test_closed_loop_shed import HOT_AT_REST

BEST_EFFORT = HOT_AT_REST.replace("limit_C: 85}", "limit_C: 85, when_infeasible: best_effort}")


def _system(tmp_path, text):
    path = tmp_path / "scenario.yaml"
    path.write_text(text)
    return PowerSystem.from_mission(load_mission(str(path)))


@pytest.mark.slow
def test_best_effort_displaces_and_rests_instead_of_shedding(tmp_path):
    """The plant hot at rest: with best_effort the heuristic sheds nothing, displaces gen1's load to
    gen2 within gen2's room, rests, and the flight reports the breach it could not avoid."""
    system = _system(tmp_path, BEST_EFFORT)
    assert system.when_infeasible == "best_effort"
    result = fly(system, "heuristic", ManagerSettings())
    summary = flight_summary(result)
    onset_s = system.faults[0].onset_s
    assert not summary["shed"]["events"] and summary["shed"]["generators"] == []
    assert sum(summary["shed"]["not_served_Ah"].values()) == 0.0
    assert summary["feasible"] is False and summary["lowest_reachable_peak_C"] > system.limit_C
    best_effort = [plan for plan in result.plans if plan.get("best_effort")]
    assert best_effort and all(plan["method"] == "heuristic" for plan in best_effort)
    assert all(plan["planned_peak_C"] > system.limit_C for plan in best_effort)
    assert any("best effort, no load shed" in response for response in summary["manager_response"])
    flying = (result.time_s[:-1] >= onset_s) & ~result.resting
    moved = result.nominal_A[flying] - result.currents_A[0, flying]
    assert moved.max() > 0.5  # gen1's load displaced ...
    np.testing.assert_allclose(result.currents_A[:, flying].sum(axis=0), 2 * result.nominal_A[flying], atol=1e-6)
    assert np.count_nonzero(result.resting[result.time_s[:-1] >= onset_s]) > 0  # ... and rests taken
    assert summary["breach_s"] > 0 and summary["max_T_winding"]["gen1"] > system.limit_C  # reported, not hidden
    # gen2 took load only within its room on its design model; with the manager's margin it stays below θmax
    assert summary["max_T_winding"]["gen2"] <= system.limit_C


def test_shed_is_the_default_and_the_scenario_or_the_option_choose(tmp_path):
    assert ManagerSettings().when_infeasible == "shed"
    shed_system = _system(tmp_path, HOT_AT_REST)
    assert shed_system.when_infeasible is None
    assert ManagerSettings().with_scenario(shed_system.manager_say).when_infeasible == "shed"
    system = _system(tmp_path, BEST_EFFORT)
    scenario_first = ManagerSettings(when_infeasible="shed").with_scenario(system.manager_say)
    assert scenario_first.when_infeasible == "best_effort"
    parser = argparse.ArgumentParser()
    add_schedule_arguments(parser)
    system, settings = settings_from_args(parser.parse_args(["chapter7_blockage_large"]))
    # the chapter-7 scenarios fly the thesis's way
    assert settings.with_scenario(system.manager_say).when_infeasible == "best_effort"
    system, settings = settings_from_args(parser.parse_args(["chapter7_blockage_large", "--when-infeasible", "shed"]))
    assert system.when_infeasible is None and settings.with_scenario(system.manager_say).when_infeasible == "shed"


def test_bad_when_infeasible_names_the_field(tmp_path, capsys):
    with pytest.raises(InputError, match="when_infeasible"):
        ManagerSettings(when_infeasible="drop")
    with pytest.raises(InputError, match="generators.when_infeasible"):
        _system(tmp_path, HOT_AT_REST.replace("limit_C: 85}", "limit_C: 85, when_infeasible: drop}"))
    path = tmp_path / "bad.yaml"
    path.write_text(HOT_AT_REST.replace("limit_C: 85}", "limit_C: 85, when_infeasible: 3}"))
    assert main(["fly", str(path), "--scheduler", "heuristic"]) == 2
    err = capsys.readouterr().err
    assert "generators.when_infeasible" in err and "shed, best_effort" in err and "Traceback" not in err
    assert main(["fly", "chapter7_inlet_3C", "--when-infeasible", "maybe"]) == 2
    err = capsys.readouterr().err
    assert "--when-infeasible" in err and "maybe" in err and "Traceback" not in err
