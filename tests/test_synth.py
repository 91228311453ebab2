"""Synthetic rig data: schema, noise statistics, reproducibility, and the ``synth`` command."""

import numpy as np
import pandas as pd
import pytest

from genthermal.cli import main
from genthermal.errors import InputError
from genthermal.measurements import REQUIRED_COLUMNS, WINDING_SENSORS, load_measurements
from genthermal.mission import load_mission
from genthermal.simulate import simulate
from genthermal.synth import synthesize


@pytest.fixture(scope="module")
def mission():
    return load_mission("thesis_fig_7_7")


@pytest.fixture(scope="module")
def synthetic(plant_model, mission):
    return synthesize(plant_model, mission, seed=3)


@pytest.fixture(scope="module")
def truth(plant_model, mission):
    return simulate(plant_model, mission.to_inputs(10.0))


def test_schema_and_noise_statistics(synthetic, truth):
    assert list(synthetic.columns) == [*REQUIRED_COLUMNS, "T_outlet"]
    assert np.array_equal(synthetic["time_s"], truth["time_s"])
    for sensor in WINDING_SENSORS:  # three sensors on the winding node, independent noise
        assert np.var(synthetic[sensor] - truth["T_winding"]) == pytest.approx(0.0082, rel=0.1)
    assert np.var(synthetic["T_iron"] - truth["T_iron"]) == pytest.approx(0.013, rel=0.1)
    assert np.var(synthetic["T_outlet"] - truth["T_outlet"]) == pytest.approx(0.013, rel=0.1)
    assert abs(np.corrcoef(synthetic["T_winding_u"] - truth["T_winding"],
                           synthetic["T_winding_v"] - truth["T_winding"])[0, 1]) < 0.1
    loaded = truth["I_u"] > 0
    relative = synthetic["I_u"][loaded] / truth["I_u"][loaded] - 1
    assert np.std(relative) == pytest.approx(0.01, rel=0.1)
    assert synthetic[["T_inlet", "T_ambient"]].equals(truth[["T_inlet", "T_ambient"]])


def test_same_seed_same_data_and_the_plant_sees_true_currents(plant_model, mission, synthetic, truth):
    assert synthesize(plant_model, mission, seed=3).equals(synthetic)
    assert not synthesize(plant_model, mission, seed=4).equals(synthetic)
    quiet = synthesize(plant_model, mission, noise_var=(0, 0), current_noise=0.0)
    assert np.allclose(quiet["T_winding_u"], truth["T_winding"]) and np.allclose(quiet["I_u"], truth["I_u"])
    # noisy measured currents do not change what the plant did
    assert np.abs(synthetic["T_winding_u"] - truth["T_winding"]).max() < 0.5


def test_input_frames_and_initial_state(plant_model, mission):
    inputs = mission.to_inputs(30.0).iloc[:100]
    warm = synthesize(plant_model, inputs, dt_s=30.0, noise_var=(0, 0), current_noise=0.0, x0=60.0)
    assert warm["T_iron"].iloc[0] == pytest.approx(60.0)
    with pytest.raises(InputError, match="dt_s"):
        synthesize(plant_model, inputs, dt_s=10.0)
    with pytest.raises(InputError, match="noise_var"):
        synthesize(plant_model, inputs, dt_s=30.0, noise_var=(-1, 0.01))
    with pytest.raises(InputError, match="current_noise"):
        synthesize(plant_model, inputs, dt_s=30.0, current_noise=-0.1)


def test_synth_command_writes_loadable_mismatched_data(tmp_path, capsys):
    nominal, changed = tmp_path / "nominal.csv", tmp_path / "changed.csv"
    assert main(["synth", "step_rated", "--out", str(nominal), "--seed", "1", "--dt", "30"]) == 0
    assert main(["synth", "step_rated", "--out", str(changed), "--seed", "1", "--dt", "30",
                 "--param", "R0=1.4", "--noise-iron", "0.02"]) == 0
    assert "R0=1.4" in capsys.readouterr().out
    data, hotter = load_measurements(nominal), load_measurements(changed)
    assert data.flags == [] and data.missing_counts["T_iron"] == 0
    assert np.allclose(np.diff(data.time_s), 30.0)
    assert hotter.winding[-1] > data.winding[-1] + 2.0  # more copper loss in the mismatched plant
    assert list(pd.read_csv(changed).columns) == [*REQUIRED_COLUMNS, "T_outlet"]


BAD = [
    (["--param", "no_such=1"], "no_such"),
    (["--param", "h_end_air=-3"], "h_end_air"),
    (["--param", "h_end_air"], "NAME=VALUE"),
    (["--noise-iron", "-0.1"], "--noise-iron"),
    (["--noise-winding", "loud"], "--noise-winding"),
    (["--seed", "x"], "--seed"),
    (["--dt", "0"], "--dt"),
]


@pytest.mark.parametrize("extra, named", BAD, ids=[" ".join(e) for e, _ in BAD])
def test_bad_synth_arguments_exit_2_naming_the_option(extra, named, tmp_path, capsys):
    assert main(["synth", "step_rated", "--out", str(tmp_path / "x.csv"), *extra]) == 2
    err = capsys.readouterr().err
    assert named in err and "Traceback" not in err
    assert not (tmp_path / "x.csv").exists()


def test_synth_records_the_faults_of_a_scenario(tmp_path, capsys):
    """Faults come from the scenario: generator 1 of the large blockage overheats, generator 2 not."""
    peaks = {}
    for generator in (1, 2):
        out = tmp_path / f"gen{generator}.csv"
        assert main(["synth", "blockage_large", "--out", str(out), "--dt", "60",
                     "--generator", str(generator)]) == 0
        data = load_measurements(out).frame
        peaks[generator] = (data["T_winding_u"].max(), data["T_inlet"].max())
    assert peaks[1][0] > 110.0 and peaks[1][1] == pytest.approx(51.0)
    assert peaks[2][0] < 100.0 and peaks[2][1] == pytest.approx(20.0)
    assert "coolant_blockage at 66 min" in capsys.readouterr().out
    assert main(["synth", "blockage_large", "--out", str(tmp_path / "x.csv"), "--generator", "3"]) == 2
    assert "--generator" in capsys.readouterr().err
