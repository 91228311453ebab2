"""``calibrate --prior-weight`` per parameter and ``estimate --sensors/--offset-step/--process-std``
on the shipped slice of the real bench IPMSM (no ../shared needed), and their bad input."""

from __future__ import annotations

import json
import math

import pandas as pd
import pytest

from genthermal.cli import main
from genthermal.commands._prior import prior_weights
from genthermal.errors import InputError
from genthermal.machines import build_model
from genthermal.resources import BENCH_MOTOR_DIR

MACHINE_FILE = str(BENCH_MOTOR_DIR / "ipmsm_machine.py")
SLICE = str(BENCH_MOTOR_DIR / "id_9_first_3000s.csv")
FITTED = "G_jacket,G_rotor_air,G_bearing_endcap"
STATOR = "T_end_winding,T_slot_bottom,T_outer_yoke"


@pytest.fixture(scope="module")
def model():
    return build_model(MACHINE_FILE)


def test_a_bare_weight_is_the_default_and_names_and_globs_override_it(model):
    fitted = ["G_jacket", "G_gap", "G_gap_speed", "C_rotor", "P_pm_ref"]
    weights = prior_weights(["G_gap*=1000", "30", "C_rotor,*pm*=500", "G_gap_speed=0"], model, fitted)
    assert weights == {"G_jacket": 30.0, "G_gap": 1000.0, "G_gap_speed": 0.0, "C_rotor": 500.0, "P_pm_ref": 500.0}
    assert prior_weights([], model, fitted) == dict.fromkeys(fitted, 0.0)


def _calibrate(tmp_path, name, *prior):
    out = tmp_path / f"{name}.json"
    code = main(["calibrate", "--model", MACHINE_FILE, SLICE, "--params", FITTED, "--fit-step", "60",
                 "--json", str(out), *prior])
    assert code == 0
    return {row["name"]: row for row in json.loads(out.read_text())["parameters"]}


def test_a_prior_by_glob_holds_only_the_parameters_it_matches(tmp_path, capsys):
    free = _calibrate(tmp_path, "free")
    held = _calibrate(tmp_path, "held", "--prior-weight", "G_rotor_*=1e6")
    assert "prior weight 1e+06" in capsys.readouterr().out

    def moved(fit, name):
        return abs(math.log(fit[name]["value"] / fit[name]["start"]))

    assert moved(free, "G_rotor_air") > 1e-3  # the record moves it when nothing holds it
    assert moved(held, "G_rotor_air") < 0.1 * moved(free, "G_rotor_air")
    assert held["G_rotor_air"]["prior_weight"] == 1e6 and held["G_jacket"]["prior_weight"] == 0.0
    assert moved(held, "G_jacket") > 1e-3  # a parameter the pattern does not match stays free


@pytest.mark.parametrize("prior, message", [
    (["-1"], "--prior-weight = -1.0: a weight must be a number >= 0"),
    (["G_jacket=nan"], "--prior-weight G_jacket = nan: a weight must be a number >= 0"),
    (["G_jacket=heavy"], "--prior-weight G_jacket = 'heavy': a weight must be a number >= 0"),
    (["30", "40"], "--prior-weight = '40': one weight for every parameter is given already (30)"),
    (["G_rotr_air=5"], "--prior-weight G_rotr_air = 'G_rotr_air': not a parameter of ipmsm_bench (nonlinear); "
                       "did you mean G_rotor_air"),
    (["G_gap=5"], "--prior-weight G_gap = 'G_gap': not among the parameters --params fits"),
    (["rotor_*=1000"], "--prior-weight rotor_* = 'rotor_*': the pattern matches no fitted parameter: the fitted "
                       "parameters are G_jacket, G_rotor_air, G_bearing_endcap"),
    (["G_gap*=1000"], "the pattern matches no fitted parameter: it matches only parameters not fitted (G_gap, "
                      "G_gap_speed); add them to --params"),
    (["G_jacket,=3"], "--prior-weight = 'G_jacket,=3': expected NAMES=W"),
])
def test_a_bad_prior_weight_is_named(prior, message, capsys):
    args = [item for p in prior for item in ("--prior-weight", p)]
    code = main(["calibrate", "--model", MACHINE_FILE, SLICE, "--params", FITTED, *args])
    assert code == 2
    assert message in capsys.readouterr().err


def test_compare_takes_no_fitting_options(capsys):
    assert main(["compare", "--model", MACHINE_FILE, SLICE, "--prior-weight", "30"]) == 2
    assert "unrecognized arguments: --prior-weight" in capsys.readouterr().err


def _estimate(tmp_path, name, *options, data=(SLICE,)):
    out = tmp_path / f"{name}.json"
    code = main(["estimate", "--model", MACHINE_FILE, *data, "--sensors", STATOR, "--fit-step", "30",
                 "--json", str(out), *options])
    assert code == 0
    return json.loads(out.read_text())


def _rmse(report, sensor):
    return report["filter"]["pooled"][sensor]["rmse"]


def test_a_held_end_winding_offset_corrects_the_winding_estimate(tmp_path, capsys):
    loose = _estimate(tmp_path, "loose", "--offset-step", "0.3")
    held = _estimate(tmp_path, "held", "--offset-step", "0.3", "--offset-step", "T_end_winding=0")
    assert loose["offset_step_K"] == {"T_end_winding": 0.3, "T_slot_bottom": 0.3, "T_outer_yoke": 0.3}
    assert held["offset_step_K"]["T_end_winding"] == 0.0
    # the uncalibrated model: the end winding's reading, next to the slot winding, corrects the winding
    assert _rmse(held, "T_winding") < 0.7 * _rmse(loose, "T_winding")
    assert held["open_loop"] == loose["open_loop"]  # the open loop reads no sensor
    out = capsys.readouterr().out
    assert "T_rotor (estimated)" in out and "T_end_winding (read)" in out and "15 min ahead" in out


def test_more_process_noise_lets_the_read_sensors_pull_their_nodes(tmp_path):
    steady = _estimate(tmp_path, "steady", "--process-std", "0.02")
    agile = _estimate(tmp_path, "agile", "--process-std", "2")
    assert steady["process_std_K"] == 0.02 and agile["process_std_K"] == 2.0
    for sensor in STATOR.split(","):
        assert _rmse(agile, sensor) < _rmse(steady, sensor)


def test_several_records_are_filtered_each_from_its_own_start(tmp_path):
    frame = pd.read_csv(SLICE)
    halves = []
    for i, part in enumerate((frame.iloc[:1500], frame.iloc[1500:])):
        halves.append(str(tmp_path / f"half_{i}.csv"))
        part.to_csv(halves[-1], index=False)
    report = _estimate(tmp_path, "halves", data=halves)
    assert len(report["records"]) == 2 and set(report["filter"]["records"]) == set(report["records"])
    pooled = report["filter"]["pooled"]["T_rotor"]["n"]
    assert pooled == sum(r["T_rotor"]["n"] for r in report["filter"]["records"].values())


@pytest.mark.parametrize("options, message", [
    (["--sensors", "T_end_windng"], "--sensors = 'T_end_windng': not a sensor of ipmsm_bench (nonlinear); did you "
                                    "mean T_end_winding"),
    (["--sensors", "T_rotor,T_rotor"], "--sensors = 'T_rotor,T_rotor': a sensor is named twice"),
    (["--sensors", STATOR, "--offset-step", "T_magnet=0.1"], "--offset-step T_magnet = 'T_magnet': not a sensor of "
                                                              "ipmsm_bench (nonlinear); it reads T_end_winding"),
    (["--sensors", STATOR, "--offset-step", "T_rotor=0.1"], "--offset-step T_rotor = 'T_rotor': not a sensor the "
                                                             "filter reads (--sensors)"),
    (["--sensors", STATOR, "--offset-step", "T_outer_yoke=-0.1"], "--offset-step T_outer_yoke = '-0.1': must be a "
                                                                   "number >= 0"),
    (["--offset-step", "nan"], "--offset-step = 'nan': must be a number >= 0"),
    (["--offset-step", "0.1", "--offset-step", "0.3"], "--offset-step = '0.3': one step for every sensor is given "
                                                        "already (0.1)"),
    (["--process-std", "-1"], "--process-std = '-1': must be a number >= 0"),
    (["--sensors", STATOR, "--filter", "kf"], "--filter = 'kf': --sensors runs its own extended Kalman filter"),
    (["--sensors", STATOR, "--plot", "x.png"], "--plot = 'x.png': an option of the filter with disturbance states"),
])
def test_bad_node_observer_options_are_named(options, message, capsys):
    code = main(["estimate", "--model", MACHINE_FILE, SLICE, *options])
    assert code == 2
    assert message in capsys.readouterr().err


def test_each_filter_refuses_the_other_ones_step(tmp_path, capsys):
    data = tmp_path / "rig.csv"
    assert main(["synth", "thesis_fig_3_2", "--out", str(data), "--seed", "3"]) == 0
    capsys.readouterr()
    assert main(["estimate", str(data), "--fit-step", "30"]) == 2
    assert "--fit-step = '30': the filter with disturbance states steps at --dt" in capsys.readouterr().err
    assert main(["estimate", str(data), "--sensors", "T_iron", "--dt", "10"]) == 2
    assert "--dt = '10': records in the CSV schema have a time column" in capsys.readouterr().err
    assert main(["estimate", str(data), "--sensors", "T_iron"]) == 0  # the thesis machine takes it too
    assert "T_winding (estimated)" in capsys.readouterr().out


def test_the_observer_names_a_bad_process_noise_in_python(model):
    from genthermal.estimation.node_observer import NodeObserver

    with pytest.raises(InputError, match=r"process_std_K = -0.5: give a finite number >= 0"):
        NodeObserver(model, 10.0, ("T_rotor",), process_std_K=-0.5)
    with pytest.raises(InputError, match=r"initial_std_K = 0.0: give a finite standard deviation > 0 K"):
        NodeObserver(model, 10.0, ("T_rotor",), initial_std_K=0.0)


def test_a_prior_on_one_record_in_the_csv_schema_is_not_ignored(tmp_path):
    """One rig record of a plant whose h_end_air is 13 (the model's 15.5): a heavy prior keeps the
    start value, none lets the record move it (the prior takes the several-record fit)."""
    data = tmp_path / "rig.csv"
    assert main(["synth", "thesis_fig_3_2", "--out", str(data), "--seed", "4", "--param", "h_end_air=13"]) == 0

    def fitted(*prior):
        out = tmp_path / f"fit_{prior[-1]}.json"
        assert main(["calibrate", str(data), "--params", "h_end_air", "--json", str(out), *prior]) == 0
        report = json.loads(out.read_text())
        return report["parameters"][0]["value"]

    free = fitted("--prior-weight", "0")
    assert abs(free / 13.0 - 1) < 0.03
    # 1e8 K² per ln² outweighs the record's misfit of some 1e4 K² at a 10 % error
    held = fitted("--prior-weight", "1e8")
    assert abs(math.log(held / 15.5)) < 0.05 * abs(math.log(free / 15.5))
