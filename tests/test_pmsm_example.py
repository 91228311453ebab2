"""The second machine, a liquid-cooled PMSM defined in examples/pmsm/ (outside the package), runs
through every consumer: simulate, codegen, estimate, calibrate, compare, diagnose; the generator
power system refuses it clearly."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from genthermal.ccompile import find_compiler
from genthermal.codegen import model_library
from genthermal.diagnose.calibrate import calibrate
from genthermal.diagnose.compare import compare
from genthermal.diagnose.discover import diagnose
from genthermal.effects import applicable_effects
from genthermal.errors import CompilerNotFoundError, InputError
from genthermal.estimation.arx_search import MEAN_SQUARED_CURRENT, input_signal, input_signals, select_input
from genthermal.estimation.ekf import ExtendedKalmanFilter
from genthermal.machines import build_model
from genthermal.measurements import dataframe_to_measurements
from genthermal.simulate import simulate
from genthermal.synth import synthesize

ROOT = Path(__file__).resolve().parents[1]
MACHINE_FILE = ROOT / "examples" / "pmsm" / "pmsm_machine.py"
DT_S = 10.0
#: A warm motor from an earlier drive: the magnet hotter than the stator (°C, state order).
WARM_START_C = {"stator_yoke": 70.0, "stator_tooth": 72.0, "stator_winding": 76.0, "permanent_magnet": 95.0}


@pytest.fixture(scope="module")
def motor():
    return build_model(str(MACHINE_FILE))


def drive_cycle(hours: float = 2.0, seed: int = 1) -> pd.DataFrame:
    """Speed and d/q currents held for 2-6 min at random points of the motor's operating range."""
    rng = np.random.default_rng(seed)
    time_s = np.arange(0.0, hours * 3600.0 + DT_S, DT_S)
    edges = np.cumsum(rng.uniform(120.0, 360.0, 200))
    segment = np.searchsorted(edges, time_s)
    speed = rng.uniform(1000.0, 8000.0, 200)[segment]
    i_q = rng.uniform(20.0, 150.0, 200)[segment]
    i_d = -np.clip(speed - 3000.0, 0.0, None) / 5000.0 * 90.0  # field weakening above 3000 rpm
    return pd.DataFrame({"time_s": time_s, "motor_speed": speed, "i_d": i_d, "i_q": i_q,
                         "T_coolant": np.full(time_s.size, 65.0), "T_ambient": np.full(time_s.size, 25.0)})


def record(model, inputs, seed: int = 2, x0=None) -> pd.DataFrame:
    return synthesize(model, inputs, dt_s=DT_S, seed=seed, x0=x0)


def test_no_file_under_genthermal_names_the_example():
    for path in (ROOT / "genthermal").rglob("*"):
        if "bench_motor" in path.parts:  # another machine's example (the bench IPMSM), shipped as data
            continue
        if path.is_file() and path.suffix in (".py", ".yaml", ".c", ".h", ".md"):
            text = path.read_text(encoding="utf-8", errors="replace").lower()
            assert "pmsm" not in text and "permanent_magnet" not in text, path


def test_the_interface_is_the_motor_s(motor):
    assert motor.input_names == ("motor_speed", "i_d", "i_q", "T_coolant", "T_ambient")
    assert motor.output_names == ["T_stator_yoke", "T_stator_tooth", "T_stator_winding"]
    assert motor.state_names == ["stator_yoke", "stator_tooth", "stator_winding", "permanent_magnet"]
    assert "permanent_magnet" not in motor.spec.sensors.values()  # the magnet is not measured


def test_steady_state_balances_the_losses_and_iron_loss_grows_with_speed(motor):
    values = motor.parameters.values()
    u = motor.input_vector(**motor.spec.interface.rated_inputs)
    x = motor.steady_state(u)
    T = dict(zip(motor.state_names, x))
    heat_in = float(motor.functions["heat"](x, u, motor.p0))
    to_coolant = values["G_yoke_coolant"] * (T["stator_yoke"] - 65.0)
    to_ambient = (values["G_housing_ambient"] * (T["stator_yoke"] - 25.0)
                  + values["G_rotor_ambient"] * (T["permanent_magnet"] - 25.0))
    assert heat_in == pytest.approx(to_coolant + to_ambient, rel=1e-9)
    assert T["stator_winding"] > T["stator_tooth"] > T["stator_yoke"] > 65.0
    simulated = simulate(motor, pd.DataFrame({"time_s": np.arange(0.0, 4 * 3600.0 + DT_S, DT_S),
                                              **{k: v for k, v in zip(motor.input_names, u)}}), x0=65.0)
    final = simulated[[f"T_{n}" for n in motor.state_names]].to_numpy()[-1]
    np.testing.assert_allclose(final, x, atol=0.05)  # 4 h is > 10 rotor time constants
    for speed in (1000.0, 6000.0, 8000.0):  # no current: iron (hysteresis + eddy) and magnet losses only
        ratio = speed / values["n_ref"]
        expected = (values["P_fe_ref"] * (values["a_hyst"] * ratio + (1 - values["a_hyst"]) * ratio**2)
                    + values["P_pm_ref"] * ratio**2)
        no_load = motor.input_vector(motor_speed=speed, i_d=0.0, i_q=0.0)
        assert float(motor.functions["heat"](x, no_load, motor.p0)) == pytest.approx(expected, rel=1e-12)


def test_generated_c_equals_python(motor, tmp_path):
    try:
        find_compiler()
    except CompilerNotFoundError as exc:
        pytest.skip(f"no C compiler: {exc}")
    inputs = drive_cycle(0.5)
    library = model_library(motor, dt_s=DT_S, prefix="pmsm")
    U = inputs[list(motor.input_names)].to_numpy()
    x0 = np.full(motor.n_states, 65.0)
    X_c = library.simulate(x0, U[:-1])
    X_py = simulate(motor, inputs, x0=x0)[[f"T_{n}" for n in motor.state_names]].to_numpy()[1:]
    assert np.max(np.abs(X_c - X_py)) < 1e-9
    assert X_py.max() > 80.0  # the cycle heats the motor: the comparison is not trivial


def test_the_filter_estimates_the_unmeasured_magnet(motor):
    inputs = drive_cycle(2.0)
    x0 = np.array([WARM_START_C[n] for n in motor.state_names])
    truth = simulate(motor, inputs, x0=x0)["T_permanent_magnet"].to_numpy()
    data = dataframe_to_measurements(record(motor, inputs, x0=x0), interface=motor.spec.interface)
    result = ExtendedKalmanFilter(motor, DT_S).run(data.frame[["time_s", *motor.input_names]], data.sensors)
    magnet = result.states[:, motor.state_names.index("permanent_magnet")]
    error = magnet - truth
    open_loop = simulate(motor, inputs, x0=result.states[0])["T_permanent_magnet"].to_numpy() - truth
    last_hour = result.time_s >= result.time_s[-1] - 3600.0
    rmse, rmse_open_loop = (float(np.sqrt(np.mean(e[last_hour] ** 2))) for e in (error, open_loop))
    print(f"magnet estimate: start error {error[0]:+.1f} K; last hour RMSE {rmse:.2f} K "
          f"(open loop from the same start {rmse_open_loop:.2f} K)")
    assert abs(error[0]) > 10.0  # the filter starts with the magnet at the stator's level
    assert rmse < 2.0 and rmse < 0.5 * rmse_open_loop


def test_calibration_recovers_the_coolant_conductance_and_resistance(motor):
    plant = motor.with_parameters("assumed", "test plant", G_yoke_coolant=78.0, R_s0=0.0138)
    data = record(plant, drive_cycle(2.0), x0=65.0)
    result = calibrate(motor, data, ["G_yoke_coolant", "R_s0"])
    fitted = result.model.parameters.values()
    assert fitted["G_yoke_coolant"] == pytest.approx(78.0, rel=0.03)
    assert fitted["R_s0"] == pytest.approx(0.0138, rel=0.03)


def test_compare_reports_every_sensor_of_the_motor(motor):
    comparison = compare(motor, record(motor, drive_cycle(1.0), x0=65.0))
    assert comparison.output_names == motor.output_names
    for name in motor.output_names:
        assert comparison.metrics["overall"][name]["rmse"] < 0.3  # the true model: noise only (0.1 K)


def test_diagnosis_finds_the_applicable_effect(motor):
    names = {effect.name for effect in applicable_effects(motor)}
    assert names == {"winding_insulation_degradation", "frame_cooling_change"}  # roles the motor has
    plant = motor.with_effect("winding_insulation_degradation", k_ins=0.6)
    data = record(plant, drive_cycle(2.0), x0=65.0)
    diagnosis = diagnose(motor, data, baseline_parameters=(), design_experiment=False)
    assert diagnosis.verdict == "winding_insulation_degradation"
    assert diagnosis.found[0].values["k_ins"] == pytest.approx(0.6, rel=0.1)


def test_the_generator_power_system_refuses_the_motor(motor):
    from genthermal.mission import load_mission
    from genthermal.schedule.planning.linearise import planning_design_model
    from genthermal.schedule.power_system import PowerSystem

    with pytest.raises(InputError, match="machine has no generator role"):
        PowerSystem(load_mission("thesis_fig_7_7"), model=motor)
    with pytest.raises(InputError, match="machine has no generator role"):
        planning_design_model(motor)


def test_the_command_line_runs_on_the_motor(motor, tmp_path, capsys):
    """compare, calibrate, estimate and diagnose read the motor's CSV schema through --model FILE."""
    from genthermal.cli import main

    data = tmp_path / "motor.csv"
    record(motor, drive_cycle(2.0), x0=65.0).to_csv(data, index=False)
    model = str(MACHINE_FILE)
    assert main(["compare", str(data), "--model", model, "--report", str(tmp_path / "cmp")]) == 0
    assert (tmp_path / "cmp" / "report.md").is_file()
    assert main(["calibrate", str(data), "--model", model, "--params", "G_yoke_coolant",
                 "--out", str(tmp_path / "fitted.yaml")]) == 0
    assert main(["estimate", str(data), "--model", str(tmp_path / "fitted.yaml"), "--predict-from", "20",
                 "--trust-machine", model]) == 0  # a model file of a machine file: trusted explicitly
    assert main(["diagnose", str(data), "--model", model]) == 0
    out = capsys.readouterr().out
    assert "T_stator_winding: RMSE" in out and "estimated unmeasured temperatures at the end" in out
    assert "permanent_magnet" in out and "verdict: none" in out  # the true model: nothing is missing


def test_the_motor_exports_as_an_fmu_with_its_units(motor, tmp_path):
    pytest.importorskip("fmpy")
    from fmpy.model_description import read_model_description

    from genthermal.fmu import export_fmu

    try:
        find_compiler()
    except CompilerNotFoundError as exc:
        pytest.skip(f"no C compiler: {exc}")
    export = export_fmu(motor, tmp_path / "pmsm.fmu")
    description = read_model_description(str(export.path))
    units = {unit.name: unit for unit in description.unitDefinitions}
    assert {"rpm", "W/K", "J/K", "degC"} <= set(units)
    inputs = [v.name for v in description.modelVariables if v.causality == "input"]
    assert inputs == list(motor.input_names)


def test_arx_input_selection_reads_the_motor_s_inputs(motor):
    signals = input_signals(motor.spec.interface)
    assert "motor_speed" in signals and "i_q" in signals and "I_exc" not in signals
    data = dataframe_to_measurements(record(motor, drive_cycle(hours=1.0)), interface=motor.spec.interface)
    selection = select_input(data, "winding", na_range=range(1, 3), nb_range=range(1, 3), nk_range=range(0, 2))
    assert set(selection.per_input["input"]) == set(signals)
    # the copper loss goes with the squared currents: the derived input explains the winding best
    assert selection.input_name == MEAN_SQUARED_CURRENT
    with pytest.raises(InputError, match="I_exc"):
        input_signal(data, "I_exc")
