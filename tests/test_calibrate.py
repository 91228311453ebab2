"""Least-squares calibration with exact derivatives: simulator, fit, confidence, identifiability."""

import numpy as np
import pytest
import yaml

from genthermal.cli import main
from genthermal.diagnose.calibrate import calibrate
from genthermal.diagnose.trajectory import ParametricSimulator
from genthermal.diagnose.compare import initial_coefficients, initial_state, measured_series
from genthermal.diagnose.hidden import make_hidden_effect_case
from genthermal.mission import load_mission
from genthermal.simulate import simulate


@pytest.mark.parametrize("dt_s", [10.0, 60.0])
def test_parametric_simulator_matches_simulate_with_a_switch(plant_model, dt_s):
    model = plant_model.with_effect("coolant_flow_reduction")
    inputs = load_mission("thesis_fig_7_7").to_inputs(dt_s)
    onset = int(4000 // dt_s)
    reference = simulate(plant_model, inputs, switches=[(inputs["time_s"][onset],
                                                          plant_model.with_effect("coolant_flow_reduction", k_flow=0.5))])
    simulator = ParametricSimulator(model, dt_s, inputs[list(model.input_names)].to_numpy().T, ["k_flow"],
                                    [{}, {"k_flow": "k_flow"}])
    Y = simulator.outputs([0.5], [0.0, 20.0], simulator.indicator([onset]))
    assert np.max(np.abs(Y - reference[["T_winding", "T_iron"]].to_numpy().T)) < 0.01


def test_parametric_jacobian_is_exact(plant_model):
    inputs = load_mission("varying_load").to_inputs(60.0)
    simulator = ParametricSimulator(plant_model, 60.0, inputs[list(plant_model.input_names)].to_numpy().T,
                                    ["h_end_air", "R0"])
    theta, ac, S = np.array([15.5, 1.2]), [0.0, 20.0], simulator.indicator()
    _, jac = simulator.outputs_and_jacobian(theta, ac, S)
    step = 1e-6 * theta[1]
    difference = (simulator.outputs(theta + [0, step], ac, S) - simulator.outputs(theta, ac, S)) / step
    assert np.allclose(jac[:, 1], difference.T.ravel(), rtol=1e-4, atol=1e-5)


@pytest.fixture(scope="module")
def rig(plant_model):
    """A 'real' machine whose losses and cooling differ from the model's defaults."""
    machine = plant_model.with_parameters(provenance="assumed", R0=1.1, h_end_air=18.0, P_iron=45.0)
    return machine, make_hidden_effect_case(None, mission="varying_load", dt_s=60.0, seed=4, plant=machine)


def test_calibration_recovers_the_machine(plant_model, rig):
    machine, case = rig
    result = calibrate(plant_model, case.data, ["R0", "h_end_air", "P_iron"])
    truth = {"R0": 1.1, "h_end_air": 18.0, "P_iron": 45.0}
    for name, value, (low, high) in zip(result.names, result.values, result.fisher["ci95"]):
        assert value == pytest.approx(truth[name], rel=0.03) and low < value < high
    assert result.converged and result.after["rmse_all_sensors"] < 0.25 < result.before["rmse_all_sensors"]
    assert result.model.parameters["R0"].provenance == "fitted"
    assert "least squares on" in result.model.parameters["R0"].source


def test_unidentifiable_pair_is_named(plant_model, rig):
    _, case = rig
    # density and specific heat of copper enter only as their product (the heat capacity)
    result = calibrate(plant_model, case.data, ["rho_copper", "c_copper"])
    assert any("rho_copper" in w and "c_copper" in w for w in result.warnings)


def test_initial_state_matches_the_first_sample(plant_model, rig):
    _, case = rig
    series = measured_series(case.data)
    x0 = initial_state(plant_model, series, initial_coefficients(plant_model, series))
    assert plant_model.outputs(x0, series.input_matrix[:, 0]) == pytest.approx(series.outputs[:, 0], abs=1e-6)


def test_cli_calibrate_writes_a_model_file(rig, tmp_path, capsys):
    _, case = rig
    case.data.to_csv(tmp_path / "rig.csv", index=False)
    out = tmp_path / "calibrated.yaml"
    assert main(["calibrate", str(tmp_path / "rig.csv"), "--params", "R0,h_end_air",
                 "--out", str(out), "--json", str(tmp_path / "fit.json")]) == 0
    assert "95 % CI" in capsys.readouterr().out
    document = yaml.safe_load(out.read_text())
    assert document["parameters"]["R0"]["provenance"] == "fitted"
    assert main(["compare", "--model", str(out), str(tmp_path / "rig.csv")]) == 0


def test_scaled_bound_round_trip_stays_within_the_physical_bounds():
    """A linear scaling's bound maps back onto the bound, not an ulp outside it: 0.0135 + 0.075 ·
    ((0 − 0.0135)/0.075) is −1.7e-18 in floating point, and an effect refuses a negative exponent
    (a flight crashed on an ``n_flow`` fitted to its bound 0)."""
    from genthermal.diagnose.trajectory import Scaling

    scaling = Scaling("linear", 0.013524645605433084, 0.075, 0.0, 1.5)
    low, high = scaling.bounds()
    assert 0.013524645605433084 + 0.075 * low < 0.0  # the round-off the clip is for
    assert scaling.value(low) == 0.0
    assert scaling.value(high) == 1.5
    assert scaling.value(0.0) == 0.013524645605433084
