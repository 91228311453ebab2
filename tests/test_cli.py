"""The command line on the shipped scenarios, and its answers to bad input."""

import pandas as pd
import pytest

from genthermal.cli import main
from genthermal.mission import available_scenarios


@pytest.mark.parametrize("scenario", available_scenarios())
def test_simulate_runs_on_every_shipped_scenario(scenario, tmp_path, capsys):
    out = tmp_path / "sim.csv"
    assert main(["simulate", scenario, "--out", str(out), "--plot", str(tmp_path / "sim.png")]) == 0
    frame = pd.read_csv(out)
    expected = ["time_s", "I_u", "I_v", "I_w", "I_exc", "T_inlet", "T_ambient", "T_frame", "T_stator_iron",
                "T_stator_teeth", "T_stator_winding", "T_end_winding_in", "T_end_winding_out", "T_rotor",
                "T_shaft", "T_winding", "T_iron", "T_outlet"]
    assert list(frame.columns) == expected
    assert (tmp_path / "sim.png").stat().st_size > 10_000
    assert frame["T_winding"].max() < 110.0  # normal missions stay below the thesis limit
    assert "peak T_winding" in capsys.readouterr().out


def test_simulate_linear_variant(tmp_path):
    assert main(["simulate", "step_rated", "--out", str(tmp_path / "s.csv"), "--model", "genco_rf201a:linear"]) == 0


def test_describe_prints_formulas_and_provenance(capsys):
    assert main(["describe", "--latex"]) == 0
    text = capsys.readouterr().out
    assert "\\frac" in text and "19 -> 12 without intermediate nodes -> 8 states" in text
    assert "thesis Table 4.2" in text and "assumed" in text


def _bad_scenario(tmp_path, text):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    return str(path)


BAD = [
    (["simulate", "no_such_mission", "--out", "x.csv"], "available scenarios"),
    (["simulate", "step_rated", "--out", "x.csv", "--dt", "-5"], "--dt"),
    (["simulate", "step_rated", "--out", "x.csv", "--dt", "ten"], "--dt"),
    (["simulate", "step_rated", "--out", "x.csv", "--param", "h_end_air"], "NAME=VALUE"),
    (["simulate", "step_rated", "--out", "x.csv", "--param", "h_end_air=abc"], "h_end_air"),
    (["simulate", "step_rated", "--out", "x.csv", "--param", "m_dot_fan=-0.02"], "m_dot_fan"),
    (["simulate", "step_rated", "--out", "x.csv", "--param", "no_such=1"], "no_such"),
    (["simulate", "step_rated", "--out", "x.csv", "--model", "genco_rf201a:quadratic"], "--model"),
]


@pytest.mark.parametrize("argv, named", BAD, ids=[" ".join(a[1:]) for a, _ in BAD])
def test_bad_arguments_give_a_clear_error(argv, named, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert named in err and "Traceback" not in err


@pytest.mark.parametrize("document, named", [
    ("name: x\nactions:\n  - {condition: 9, duration_min: 20}\n", "actions[0].condition"),
    ("name: x\nactions:\n  - {condition: 5, duration_min: 10}\n", "actions[0].duration_min"),
    ("name: x\nactions:\n  - {load_percent: -20, duration_min: 20}\n", "actions[0].load_percent"),
    ("name: x\nactions:\n  - {condition: 5, duraton_min: 20}\n", "duraton_min"),
    ("name: x\n", "actions"),
    ("name: x\nactions: [\n", "line"),
])
def test_bad_scenarios_name_the_field(document, named, tmp_path, capsys):
    assert main(["simulate", _bad_scenario(tmp_path, document), "--out", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err
    assert named in err and "Traceback" not in err


@pytest.mark.parametrize("command", ["demo", "simulate", "describe", "codegen", "fmu", "cortex-m4", "synth", "estimate", "sysid",
                                     "compare-models", "compare", "calibrate", "diagnose", "plan", "fly", "sweep"])
def test_every_command_documents_itself(command, capsys):
    with pytest.raises(SystemExit) as stopped:
        main([command, "--help"])
    assert stopped.value.code == 0 and "usage: genthermal" in capsys.readouterr().out


@pytest.mark.parametrize("command", ["demo", "simulate", "describe", "codegen", "fmu", "cortex-m4", "synth", "estimate",
                                     "compare-models", "compare", "calibrate", "diagnose", "plan", "fly"])
def test_every_model_command_names_the_model_one_way(command, capsys):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    text = capsys.readouterr().out
    assert "--model NAME|FILE" in text and "--param NAME=VALUE" in text
    assert "--machine" not in text and "--variant" not in text
