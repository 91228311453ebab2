"""One command-line dialect: every sub-command's parser, read without running it, spells the same idea
the same way (docs/guide/cli.md), and a bad choice or ``--param`` is one clear line and exit code 2."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

from genthermal import cli
from genthermal.commands import _vocabulary as words
from genthermal.commands._common import OUT_KINDS
from genthermal.outputs import FOLDER_OUT_COMMANDS

ROOT = Path(__file__).resolve().parents[1]
#: Commands that produce a result: all of them write it as JSON on request.
RESULT_COMMANDS = set(cli.COMMANDS)
#: Commands that build no model of their own: sysid fits ARX models to data, sweep generates its cases.
NO_MODEL_COMMANDS = {"sysid", "sweep"}
#: What ``--out`` writes, by command.
OUT_KIND = {"demo": "folder", "codegen": "folder", "cortex-m4": "folder", "simulate": "csv", "synth": "csv",
            "calibrate": "model", "diagnose": "model", "fmu": "fmu"}
#: Choices spelt as a column of the measurement CSV, not as a word (sysid --input I_u).
COLUMN_CHOICES = set(words.ARX_INPUTS) - {"auto"}
CHOICE_WORD = re.compile(r"^[a-z0-9]+(-[a-z0-9]+)*$")
HEAVY = ("casadi", "sympy", "matplotlib", "scipy", "pandas", "dask", "numpy", "tqdm", "yaml")


def _parsers() -> dict:
    return next(a for a in cli.build_parser()._actions if a.dest == "command").choices


PARSERS = _parsers()


def _options(parser) -> dict:
    return {option: action for action in parser._actions for option in action.option_strings}


def test_the_table_of_commands_is_every_registered_command():
    assert set(PARSERS) == set(cli.COMMANDS) and len(PARSERS) >= 16


@pytest.mark.parametrize("name", sorted(cli.COMMANDS))
def test_each_command_speaks_the_dialect(name):
    parser = PARSERS[name]
    options = _options(parser)
    assert "docs/guide/cli.md" in parser.epilog and f"docs/{cli.COMMANDS[name][2]}" in parser.epilog
    if name in RESULT_COMMANDS:
        assert options["--json"].metavar == "FILE.json" and "JSON" in options["--json"].help
        assert "--force" in options  # an existing --json file is replaced only when asked
    if name not in NO_MODEL_COMMANDS:
        assert options["--model"].metavar == "NAME|FILE", name
        assert options["--param"].metavar == "NAME=VALUE" and options["--param"].default == []
    else:
        assert "--param" not in options
    if "--out" in options:
        metavar, text = OUT_KINDS[OUT_KIND[name]]
        assert options["--out"].metavar == metavar
        assert options["--out"].help.startswith(text.split("{what}")[0])
        assert (OUT_KIND[name] == "folder") == (name in FOLDER_OUT_COMMANDS)
    else:
        assert name not in OUT_KIND
    assert "--quiet" in options


@pytest.mark.parametrize("name", sorted(cli.COMMANDS))
def test_choices_are_written_one_way(name):
    for action in PARSERS[name]._actions:
        if action.dest == "help" or not action.option_strings:
            continue
        choice_or_file = f"{{{','.join(action.choices)}}}|FILE{getattr(action.choices, 'suffix', '')}" \
            if action.choices else None
        if action.choices:
            assert action.metavar is None or (hasattr(action.choices, "suffix") and action.metavar == choice_or_file), \
                f"{name} {action.option_strings}: shown as {{a,b}} (or {{a,b}}|FILE.py), not {action.metavar}"
            for choice in action.choices:
                assert CHOICE_WORD.match(choice) or choice in COLUMN_CHOICES, (name, action.option_strings, choice)
            assert " | " not in (action.help or "")
        metavar = action.metavar or ""
        assert "|" not in metavar or metavar in ("NAME|FILE", choice_or_file), \
            f"{name} {action.option_strings}: metavar {metavar}"


def test_old_spellings_the_docs_use_are_hidden_and_still_accepted():
    """docs/results/robustness-grid.md runs ``sweep --schedulers heuristic_flown`` and
    docs/guide/flights.md ``sweep --no-progress``; nothing used ``--when-infeasible best_effort``."""
    from genthermal.commands.sweep import run

    assert words.cli_spelling("heuristic_flown") == "heuristic-flown"
    assert words.cli_spelling("best_effort") == "best_effort"  # not an old command-line spelling
    sweep_help = PARSERS["sweep"].format_help()
    assert "heuristic_flown" not in sweep_help and "--no-progress" not in sweep_help
    assert cli.build_parser(["sweep"]).parse_args(["sweep", "--no-progress"]).quiet is True
    assert "best_effort" not in PARSERS["plan"].format_help()
    assert words.library_value("best-effort") == "best_effort" and words.library_value("optimal") == "optimal"
    with pytest.raises(Exception, match="--schedulers"):
        run(cli.build_parser(["sweep"]).parse_args(["sweep", "--schedulers", "heuristic_flow"]))


def test_the_words_agree_with_the_library():
    from genthermal.embedded.mission import PRECISIONS
    from genthermal.estimation.arx_search import INPUT_SIGNALS
    from genthermal.estimation.node_observer import DEFAULT_OFFSET_STEP_K, DEFAULT_PROCESS_STD_K
    from genthermal.estimation.prediction import DEFAULT_EVERY_MIN, DEFAULT_MARGIN_K, THESIS_STARTS_MIN
    from genthermal.machines.registry import BUILT_IN
    from genthermal.schedule.flight.manager_settings import (DEFAULT_REST_BUDGET_FRACTION, FLOWN_SCHEDULERS, PLANNER_MODELS,
                                                      SCHEDULERS, ManagerSettings)
    from genthermal.schedule.planning.shed import INFEASIBLE_RESPONSES
    from genthermal.schedule.state_estimator import FLIGHT_FILTERS
    from genthermal.schedule.sweeps.sweep import DEFAULT_FLIGHT_CPU_LIMIT_S, SWEEP_SCHEDULERS
    from genthermal.synth import DEFAULT_CURRENT_NOISE, THESIS_NOISE_VARIANCE_K2

    assert words.BUILT_IN_MACHINES == tuple(BUILT_IN) and words.DEFAULT_MODEL in BUILT_IN
    assert words.SCHEDULERS == SCHEDULERS and set(words.FLOWN_SCHEDULERS) == set(FLOWN_SCHEDULERS)
    assert words.PLANNER_MODELS == PLANNER_MODELS and words.FILTERS == tuple(FLIGHT_FILTERS)
    assert tuple(map(words.library_value, words.INFEASIBLE_RESPONSES)) == INFEASIBLE_RESPONSES
    assert tuple(map(words.library_value, words.SWEEP_SCHEDULERS)) == SWEEP_SCHEDULERS
    assert words.PRECISIONS == PRECISIONS and words.ARX_INPUTS == ("auto", *INPUT_SIGNALS)
    settings = ManagerSettings()
    assert words.MANAGER_DEFAULTS == {"margin_K": settings.margin_K, "rise_backoff": settings.rise_backoff,
                                      "confidence_sigmas": settings.confidence_sigmas,
                                      "when_infeasible": settings.when_infeasible, "filter": settings.filter,
                                      "cycle_min": settings.cycle_s / 60.0, "planner_model": settings.planner_model}
    assert (words.DEFAULT_REST_BUDGET_FRACTION, words.DEFAULT_FLIGHT_CPU_LIMIT_S) == (DEFAULT_REST_BUDGET_FRACTION,
                                                                                        DEFAULT_FLIGHT_CPU_LIMIT_S)
    assert (words.THESIS_NOISE_VARIANCE_K2, words.DEFAULT_CURRENT_NOISE) == (tuple(THESIS_NOISE_VARIANCE_K2),
                                                                             DEFAULT_CURRENT_NOISE)
    assert (words.DEFAULT_EVERY_MIN, words.THESIS_STARTS_MIN, words.DEFAULT_MARGIN_K) == (
        DEFAULT_EVERY_MIN, tuple(THESIS_STARTS_MIN), DEFAULT_MARGIN_K)
    assert (words.DEFAULT_OFFSET_STEP_K, words.DEFAULT_PROCESS_STD_K) == (DEFAULT_OFFSET_STEP_K, DEFAULT_PROCESS_STD_K)


def test_diagnose_phases_are_the_discoverys():
    from genthermal.diagnose.discovery import Discovery

    assert words.PHASES == tuple(Discovery.PHASE_MODES)


def test_no_help_imports_a_numerical_library():
    """``genthermal --help`` and every ``genthermal CMD --help`` in one process: none loads casadi,
    sympy, matplotlib, scipy, pandas, dask, numpy, tqdm or yaml (the guard of the 0.5 s help target)."""
    code = ("import contextlib, io, sys\nfrom genthermal.cli import COMMANDS, main\n"
            "for argv in [['--help']] + [[name, '--help'] for name in COMMANDS]:\n"
            "    with contextlib.redirect_stdout(io.StringIO()):\n"
            "        try:\n            main(argv)\n        except SystemExit:\n            pass\n"
            f"print(','.join(sorted(m for m in sys.modules if m.split('.')[0] in {HEAVY!r})))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT, timeout=60)
    assert out.stdout.strip() == ""


# (argv, the option and the value the one-line error must name); all refused before any work
BAD_WORDS = [
    (["estimate", "rig.csv", "--filter", "ukf"], "--filter", "ukf"),
    (["fly", "blockage_large", "--filter", "EKF"], "--filter", "EKF"),
    (["plan", "blockage_large", "--scheduler", "greedy"], "--scheduler", "greedy"),
    (["fly", "blockage_large", "--when-infeasible", "drop"], "--when-infeasible", "drop"),
    (["sweep", "--planner-model", "cubic"], "--planner-model", "cubic"),
    (["diagnose", "rig.csv", "--phases", "split"], "--phases", "split"),
    (["cortex-m4", "--out", "build", "--precision", "half"], "--precision", "half"),
    (["sysid", "a.csv", "b.csv", "--input", "I_x"], "--input", "I_x"),
    (["describe", "--param", "R0"], "--param", "R0"),
    (["fmu", "--out", "m.fmu", "--param", "R0:1.2"], "--param", "R0:1.2"),
    (["cortex-m4", "--out", "build", "--param", "=3"], "--param", "=3"),
    (["plan", "blockage_large", "--param", "R0"], "--param", "R0"),
    (["fly", "blockage_large", "--param", "R0=warm"], "--param R0", "warm"),
    (["simulate", "step_rated", "--out", "s.csv", "--param", "h_end_air=1e"], "--param h_end_air", "1e"),
    (["fmu", "--out", "m.fmu", "--param", "R9=1"], "--param R9", "R9"),
    (["plan", "blockage_large", "--param", "no_such=1"], "--param no_such", "no_such"),
]


@pytest.mark.parametrize("argv, option, value", BAD_WORDS, ids=[" ".join(c[0][:1] + c[0][-2:]) for c in BAD_WORDS])
def test_a_bad_choice_or_param_exits_2_naming_the_option_and_value(argv, option, value, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert option in err and value in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_a_usage_error_returns_2_with_the_usage_line(capsys):
    assert cli.main(["plan", "blockage_large", "--scheduler", "greedy"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: genthermal plan") and "invalid choice: 'greedy'" in err


def test_param_changes_the_model_of_the_new_commands(tmp_path):
    """``--param`` on plan (and fly: the same settings) changes the planning model, and with it the
    plant built from it; fmu and cortex-m4 load their model through the same function."""
    import argparse

    from genthermal.commands.plan import add_schedule_arguments, settings_from_args

    parser = argparse.ArgumentParser()
    add_schedule_arguments(parser)
    system, _ = settings_from_args(parser.parse_args(["blockage_large", "--param", "R0=1.5"]))
    assert system.planning_model.parameters.value("R0") == 1.5
    assert system.planning_model.parameters["R0"].provenance == "assumed"
    nominal, _ = settings_from_args(parser.parse_args(["blockage_large"]))
    factor = nominal.plant_model(0).parameters.value("R0") / nominal.planning_model.parameters.value("R0")
    assert system.plant_model(0).parameters.value("R0") == pytest.approx(1.5 * factor)
    _, settings = settings_from_args(parser.parse_args(["blockage_large", "--when-infeasible", "best-effort"]))
    assert settings.when_infeasible == "best_effort"
