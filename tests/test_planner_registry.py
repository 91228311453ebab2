"""Planners by name: a scheduler written in one file outside genthermal is registered and flown."""

import json
from pathlib import Path

import pytest

from genthermal.cli import main
from genthermal.errors import InputError
from genthermal.schedule.flight.flight import Flight, Manager
from genthermal.schedule.flight.manager_settings import SCHEDULERS, ManagerSettings
from genthermal.schedule.planning.registry import (BUILT_IN_PLANNERS, load_planner_file, planner, planner_names,
                                                  register_planner, unregister_planner)

from test_plants import EXAMPLE, HOT_MISSION, LumpedPlant, _system

TOY_FILE = Path(__file__).resolve().parent / "toy_planner.py"


@pytest.fixture()
def toy():
    """The toy planner of tests/toy_planner.py, registered by running its file, for one test."""
    entry = planner(load_planner_file(TOY_FILE))
    yield entry
    unregister_planner(entry.name)


def test_the_built_in_planners_are_registered():
    assert BUILT_IN_PLANNERS == SCHEDULERS == ("heuristic", "engineer", "optimal", "milp")
    assert planner("optimal").settings_field == "optimal" and planner("optimal").settings is None
    assert [name for name in BUILT_IN_PLANNERS if planner(name).on_flown_model] == ["heuristic", "optimal"]


def test_a_planner_from_a_file_of_its_own_is_flown_by_name(tmp_path, toy):
    """The toy planner's rests are what the flight flies: the hot mission on the example numpy plant
    (unmanaged 330 s above θmax) needs rests, and only the toy's plans are in the record."""
    assert "rest_first" in planner_names()
    system, path = _system(tmp_path, HOT_MISSION)
    result = Flight(LumpedPlant(), Manager("rest_first"), path).run()
    methods = {plan["method"] for plan in result.plans}
    assert methods and all(m.startswith("rest_first") for m in methods), methods
    summary = result.summary()
    assert summary["rested_s"] > 0.0 and summary["plant_fault"] is None
    unmanaged = Flight(LumpedPlant(), Manager("rest_first", ManagerSettings(replan=False)), path).run()
    assert unmanaged.summary()["rested_s"] == 0.0
    assert max(summary["max_T_winding"].values()) < max(unmanaged.summary()["max_T_winding"].values())
    assert summary["breach_s"] < unmanaged.summary()["breach_s"]


def test_a_planner_name_is_checked(toy):
    with pytest.raises(InputError, match="registered already"):
        register_planner("rest_first", toy.plan)
    with pytest.raises(InputError, match="not a function"):
        register_planner("another", 3)
    with pytest.raises(InputError, match="letters, digits"):
        register_planner("has space", toy.plan)
    with pytest.raises(InputError, match="rest_first"):  # the message lists the registered ones
        Manager("magic")
    with pytest.raises(InputError, match="planner_model"):  # the toy plans on the design model only
        Manager("rest_first", ManagerSettings(planner_model="nonlinear"))
    with pytest.raises(InputError, match="built-in"):
        unregister_planner("optimal")


def test_an_unregistered_planner_is_gone(toy):
    unregister_planner(toy.name)
    assert toy.name not in planner_names()
    with pytest.raises(InputError, match="scheduler"):
        Manager(toy.name)
    assert register_planner(toy.name, toy.plan, toy.settings).name in planner_names()  # registered again


def test_a_planner_file_is_flown_from_the_command_line(tmp_path):
    _, path = _system(tmp_path, HOT_MISSION)
    out = tmp_path / "flight.json"
    try:
        assert main(["fly", str(path), "--scheduler", str(TOY_FILE), "--plant", str(EXAMPLE), "--json", str(out)]) == 0
    finally:
        unregister_planner("rest_first")
    summary = json.loads(out.read_text())
    assert summary["rested_s"] > 0.0 and {plan["method"] for plan in summary["plans"]} == {"rest_first"}


@pytest.mark.parametrize("text, words", [
    ("raise RuntimeError('no solver here')", "raised RuntimeError: no solver here"),
    ("x = 1", "registered 0 planners"),
    ("from genthermal.schedule.planning.registry import register_planner\n"
     "register_planner('one_a', lambda p, s, q: None)\nregister_planner('one_b', lambda p, s, q: None)",
     "registered 2 planners"),
])
def test_a_planner_file_that_fails_is_a_clear_error(tmp_path, capsys, text, words):
    _, path = _system(tmp_path, HOT_MISSION)
    planner_file = tmp_path / "bad_planner.py"
    planner_file.write_text(text + "\n")
    assert main(["fly", str(path), "--scheduler", str(planner_file)]) == 2
    err = capsys.readouterr().err
    assert words in err and "--scheduler" in err and "Traceback" not in err
    assert not {"one_a", "one_b"} & set(planner_names())  # nothing half-registered is left
