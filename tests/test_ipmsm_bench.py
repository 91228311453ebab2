"""The real bench IPMSM: its logger's column map, bad logger input, multi-record fit and the EKF,
on the profile slice shipped in the package (no ../shared needed)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd
import pytest

from genthermal.cli import main
from genthermal.column_map import ColumnMap, read_logged, read_logged_set
from genthermal.diagnose.multi_record import (fit_records, record_from_measurements, records_fisher,
                                              simulate_record)
from genthermal.errors import InputError
from genthermal.estimation.node_observer import NodeObserver
from genthermal.machines import build_model, resolve_machine
from genthermal.resources import BENCH_MOTOR_DIR

MACHINE_FILE = BENCH_MOTOR_DIR / "ipmsm_machine.py"
SLICE = BENCH_MOTOR_DIR / "id_9_first_3000s.csv"


@pytest.fixture(scope="module")
def machine():
    return resolve_machine(str(MACHINE_FILE))


@pytest.fixture(scope="module")
def column_map(machine):
    return ColumnMap.from_dict(machine.column_map, machine.interface)


@pytest.fixture(scope="module")
def model():
    return build_model(str(MACHINE_FILE))


@pytest.fixture(scope="module")
def slice_data(machine, column_map):
    return read_logged(SLICE, column_map, machine.interface)


def _variant(tmp_path, name, change):
    frame = pd.read_csv(SLICE, nrows=600)
    change(frame)
    path = tmp_path / name
    frame.to_csv(path, index=False)
    return path


def test_slice_read_through_the_column_map(slice_data, machine):
    frame = slice_data.frame
    assert list(frame["time_s"][:3]) == [0.0, 1.0, 2.0]  # made from dt_s = 1: the file has no time column
    raw = pd.read_csv(SLICE)
    assert np.allclose(frame["motor_speed"], raw["speed"])
    assert np.allclose(frame["T_water"], raw["water_outlet"])
    winding = slice_data.output("T_winding")
    assert np.allclose(winding, 0.5 * (raw["activewind_1"] + raw["activewind_2"]))
    assert set(machine.interface.sensor_columns) <= set(frame.columns)


def test_units_are_converted(tmp_path, machine):
    mapping = {"dt_s": 2.0, "columns": {**ColumnMapDict.base(machine)}}
    mapping["columns"]["speed"] = {"input": "motor_speed", "unit": "rad/s"}
    mapping["columns"]["water_outlet"] = {"input": "T_water", "unit": "K"}
    mapping["columns"].pop("Torque")
    mapping["columns"].pop("Pele_PI")
    path = _variant(tmp_path, "si.csv", lambda f: (f.__setitem__("speed", f["speed"] * 2 * math.pi / 60),
                                                   f.__setitem__("water_outlet", f["water_outlet"] + 273.15)))
    data = read_logged(path, ColumnMap.from_dict(mapping, machine.interface), machine.interface)
    raw = pd.read_csv(SLICE, nrows=600)
    assert np.allclose(data.frame["motor_speed"], raw["speed"])
    assert np.allclose(data.frame["T_water"], raw["water_outlet"])
    assert data.frame["time_s"].iloc[-1] == 2.0 * 599


class ColumnMapDict:
    @staticmethod
    def base(machine):
        return {k: dict(v) for k, v in machine.column_map["columns"].items()}


def test_map_naming_a_column_not_in_the_file(tmp_path, machine, column_map):
    path = _variant(tmp_path, "no_rotor.csv", lambda f: f.pop("rotor"))
    with pytest.raises(InputError, match=r"no_rotor.csv: column = 'rotor'.*not in the file"):
        read_logged(path, column_map, machine.interface)


def test_kelvin_in_a_celsius_column(tmp_path, machine, column_map):
    path = _variant(tmp_path, "kelvin.csv", lambda f: f.__setitem__("endcap", f["endcap"] + 273.15))
    with pytest.raises(InputError, match=r"kelvin.csv: column endcap.*median 29[0-9].*look like kelvin"):
        read_logged(path, column_map, machine.interface)


def test_rad_per_s_where_rpm_is_declared(tmp_path, machine, column_map):
    path = _variant(tmp_path, "rads.csv", lambda f: f.__setitem__("speed", f["speed"] * 2 * math.pi / 60))
    with pytest.raises(InputError, match=r"rads.csv: column speed.*unit rpm.*rad/s declared as rpm"):
        read_logged(path, column_map, machine.interface)


def test_the_true_unit_passes_the_speed_check(slice_data):
    assert slice_data.frame["motor_speed"].max() > 3000.0


def test_negative_speed(tmp_path, machine, column_map):
    path = _variant(tmp_path, "backwards.csv", lambda f: f.loc[100, "speed"].__class__ and f.__setitem__(
        "speed", np.where(f.index == 100, -250.0, f["speed"])))
    with pytest.raises(InputError, match=r"backwards.csv: column speed, data row 101 = -250.0: a negative speed"):
        read_logged(path, column_map, machine.interface)


def test_run_of_nan_in_a_sensor(tmp_path, machine, column_map):
    def lose(frame):
        frame["bearing"] = frame["bearing"].astype(float)
        frame.loc[200:259, "bearing"] = np.nan

    path = _variant(tmp_path, "lost.csv", lose)
    with pytest.raises(InputError, match=r"lost.csv: column bearing, data rows 201-260 = 'NaN': 60 missing"):
        read_logged(path, column_map, machine.interface)


def test_a_short_gap_in_a_sensor_is_kept_as_missing(tmp_path, machine, column_map):
    def lose(frame):
        frame["bearing"] = frame["bearing"].astype(float)
        frame.loc[200:204, "bearing"] = np.nan

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = read_logged(_variant(tmp_path, "gap.csv", lose), column_map, machine.interface)
    assert data.missing_counts["bearing"] == 5


def test_records_with_different_columns_in_one_call(tmp_path, machine, column_map):
    same = _variant(tmp_path, "a.csv", lambda f: None)
    other = _variant(tmp_path, "b.csv", lambda f: f.__setitem__("extra_probe", 1.0))
    with pytest.raises(InputError, match=r"b.csv: columns = 'extra_probe'.*same columns"):
        read_logged_set([same, other], column_map, machine.interface)


def test_map_with_unknown_unit_or_target(machine):
    columns = ColumnMapDict.base(machine)
    columns["speed"] = {"input": "motor_speed", "unit": "furlongs"}
    with pytest.raises(InputError, match=r"columns.speed.unit = 'furlongs': not a speed unit"):
        ColumnMap.from_dict({"columns": columns}, machine.interface)
    columns["speed"] = {"input": "speed_rpm", "unit": "rpm"}
    with pytest.raises(InputError, match=r"'speed_rpm': not an input"):
        ColumnMap.from_dict({"columns": columns}, machine.interface)


def test_initial_state_from_each_records_first_readings(model, slice_data):
    record = record_from_measurements(model, slice_data, 60.0)
    first = {s.node: s for s in model.spec.interface.sensors}
    states = dict(zip(model.state_names, record.x0))
    rotor = slice_data.output("T_rotor")[:30].mean()  # the first 60-s window, centred on t = 0
    assert abs(states["rotor"] - rotor) < 0.5
    assert "end_space_air" not in first  # unmeasured: from its measured neighbours
    neighbours = [states[n] for n in ("end_winding", "rotor", "endcap")]
    assert min(neighbours) <= states["end_space_air"] <= max(neighbours)


def test_fit_over_two_records_lowers_the_error_and_reports_intervals(model, slice_data):
    from genthermal.measurements import MeasurementData

    frame = slice_data.frame
    halves = [MeasurementData(part.reset_index(drop=True).assign(time_s=lambda f: f["time_s"] - f["time_s"].iloc[0]),
                              f"half {i}", {}, [], [], slice_data.interface)
              for i, part in enumerate((frame.iloc[:1500], frame.iloc[1500:]))]
    records = [record_from_measurements(model, half, 60.0) for half in halves]
    before = np.sqrt(np.nanmean(np.concatenate([(simulate_record(model, r) - r.outputs).ravel() for r in records]) ** 2))
    names = ["G_jacket", "G_slot_tooth", "G_slot_end", "G_end_winding_frame", "G_gap", "G_rotor_shaft"]
    fit = fit_records(model, records, names, max_iter=30)
    after = np.sqrt(np.nanmean(np.concatenate([(simulate_record(fit.model, r) - r.outputs).ravel() for r in records]) ** 2))
    assert after < 0.6 * before
    assert math.isclose(fit.rmse, after, rel_tol=0.05)
    fisher = records_fisher(fit)
    for value, (low, high) in zip(fit.values, fisher["ci95"]):
        assert low < value < high
    assert fit.model.parameters["G_jacket"].provenance == "fitted"


def test_ekf_from_stator_sensors_tracks_the_winding_better_than_open_loop(model, slice_data):
    record = record_from_measurements(model, slice_data, 30.0)
    winding = model.output_names.index("T_winding")
    open_loop = simulate_record(model, record)[winding] - record.outputs[winding]
    observer = NodeObserver(model, record.dt_s, ("T_end_winding", "T_slot_bottom", "T_outer_yoke"))
    _, outputs = observer.run(record)
    filtered = outputs[winding] - record.outputs[winding]
    assert np.sqrt(np.mean(filtered ** 2)) < 0.6 * np.sqrt(np.mean(open_loop ** 2))  # the uncalibrated model
    with pytest.raises(InputError, match="'T_magnet': not a sensor"):
        NodeObserver(model, record.dt_s, ("T_magnet",))


def test_ekf_offset_step_per_sensor(model, slice_data):
    record = record_from_measurements(model, slice_data, 30.0)
    winding = model.output_names.index("T_winding")
    sensors = ("T_end_winding", "T_slot_bottom", "T_outer_yoke")

    def winding_rmse(bias, default=0.02):
        _, outputs = NodeObserver(model, record.dt_s, sensors, bias_std_K=bias, default_bias_std_K=default).run(record)
        return float(np.sqrt(np.mean((outputs[winding] - record.outputs[winding]) ** 2)))

    loose = winding_rmse(0.3)
    assert winding_rmse({}, default=0.3) == loose  # a mapping naming no sensor: every sensor takes the default
    # the end winding's offset held: its reading, next to the slot winding, corrects the winding estimate
    assert winding_rmse({"T_end_winding": 0.0}, default=0.3) < 0.7 * loose
    with pytest.raises(InputError, match=r"bias_std_K = 'T_rotor': not a sensor the filter reads"):
        NodeObserver(model, record.dt_s, sensors, bias_std_K={"T_rotor": 0.1})
    with pytest.raises(InputError, match=r"bias_std_K\[T_end_winding\] = -0.1: give a finite step"):
        NodeObserver(model, record.dt_s, sensors, bias_std_K={"T_end_winding": -0.1})


def test_compare_command_on_the_shipped_slice(capsys):
    code = main(["compare", "--model", f"{MACHINE_FILE}:MACHINE_PLAIN", str(SLICE), "--fit-step", "60"])
    out = capsys.readouterr().out
    assert code == 0
    assert "each from its own measured initial state" in out
    assert "by speed band" in out and "3000-inf rpm" in out


def test_compare_command_names_a_bad_column_map(tmp_path, capsys):
    bad = tmp_path / "map.yaml"
    bad.write_text("dt_s: 1\ncolumns:\n  speed: {input: motor_speed, unit: rpm}\n", encoding="utf-8")
    code = main(["compare", "--model", str(MACHINE_FILE), str(SLICE), "--columns", str(bad)])
    assert code == 2
    assert "'i_d': this input or sensor column of the machine is not mapped" in capsys.readouterr().err


def test_calibrate_names_a_weight_on_an_unknown_sensor(capsys):
    code = main(["calibrate", "--model", str(MACHINE_FILE), str(SLICE), "--params", "G_jacket",
                 "--weight", "T_magnet=4"])
    assert code == 2
    assert "--weight T_magnet = 'T_magnet': not a sensor of ipmsm_bench" in capsys.readouterr().err


def test_effects_can_be_left_out_one_by_one(machine):
    import importlib.util

    spec = importlib.util.spec_from_file_location("ipmsm_machine_module", MACHINE_FILE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    full = build_model(str(MACHINE_FILE))
    square_law = module.parameters_without("magnet_loss_exponent")
    assert "pm_speed_exponent" not in square_law and "P_pm_ref" in square_law
    at_half_speed = {"motor_speed": 2000.0, "i_d": -100.0, "i_q": 150.0, "T_water": 25.0, "T_ambient": 23.0}
    x = np.linspace(30.0, 60.0, full.n_states)
    square = build_model(str(MACHINE_FILE), parameters=square_law)
    # with the exponent at its start value 2, the power law is the square law it replaces
    assert np.allclose(full.rhs(x, full.input_vector(**at_half_speed)),
                       square.rhs(x, square.input_vector(**at_half_speed)), rtol=1e-3, atol=1e-5)
    plain = build_model(f"{MACHINE_FILE}:MACHINE_PLAIN")
    assert "pm_speed_exponent" not in plain.parameters and "P_pm_ref" not in plain.parameters
    with pytest.raises(ValueError, match="unknown effect 'windage'"):
        module.parameters_without("windage")
    capacity = full.parameters["C_shaft_bearing"]  # a fit may end on either bound of a capacity
    for value in (capacity.lower, capacity.upper):
        assert full.with_parameters(provenance="fitted", source="test", C_shaft_bearing=value)


def test_speed_power_laws_vanish_at_rest_with_finite_derivatives(model):
    """The magnet loss is an (n/n_ref)^c law: zero heat at standstill, and the fit's derivative
    with respect to the exponent finite there (no log(0))."""
    import casadi as ca

    x, u, p = ca.SX.sym("x", model.n_states), ca.SX.sym("u", len(model.input_names)), ca.SX.sym("p", len(model.p0))
    rhs = model.functions["rhs"](x, u, p)
    exponents = [model.parameter_names.index("pm_speed_exponent")]
    derivative = ca.Function("d", [x, u, p], [ca.jacobian(rhs, p[exponents])])
    at_rest = model.input_vector(motor_speed=0.0, i_d=-100.0, i_q=150.0, T_water=25.0, T_ambient=23.0)
    x0 = np.linspace(30.0, 60.0, model.n_states)
    rotor = model.state_names.index("rotor")
    rest = np.asarray(derivative(x0, at_rest, model.p0))
    assert np.all(np.isfinite(rest)) and np.allclose(rest[rotor], 0.0, atol=1e-6)
    half = np.asarray(derivative(x0, model.input_vector(motor_speed=2000.0, i_q=150.0, T_water=25.0,
                                                        T_ambient=23.0), model.p0))
    assert np.all(np.isfinite(half)) and abs(half[rotor, 0]) > 0


def test_the_full_model_steps_stably_at_top_speed_with_a_steep_end_space_convection(model):
    """Extreme fitted values (a light end-space air node, end-space convection rising 10-fold by
    4000 rpm) once made 10-s steps diverge; the step's linear part at 2000 rpm keeps them stable."""
    import casadi as ca

    from genthermal.discretise import discretise

    steep = model.with_parameters(provenance="fitted", source="test", C_end_space_air=170.0,
                                  G_end_winding_air=90.0, k_end_space_speed=10.0)
    step = discretise(steep, 10.0).step
    xs = ca.SX.sym("x", steep.n_states)
    top = steep.input_vector(motor_speed=4000.0, i_d=-150.0, i_q=250.0, T_water=25.0, T_ambient=23.0)
    A = np.asarray(ca.Function("A", [xs], [ca.jacobian(step(xs, top), xs)])(np.full(steep.n_states, 40.0)))
    assert np.max(np.abs(np.linalg.eigvals(A))) < 1.0


def test_calibrate_names_a_negative_prior_weight(capsys):
    code = main(["calibrate", "--model", str(MACHINE_FILE), str(SLICE), "--params", "G_jacket",
                 "--prior-weight", "-1"])
    assert code == 2
    assert "--prior-weight = -1.0: a weight must be a number >= 0" in capsys.readouterr().err


def test_a_prior_keeps_a_parameter_the_record_hardly_sees_near_its_estimate(model, slice_data):
    record = record_from_measurements(model, slice_data, 60.0)
    names = ["G_jacket", "G_rotor_air", "G_bearing_endcap"]
    free = fit_records(model, [record], names, max_iter=30)
    held = fit_records(model, [record], names, max_iter=30, prior_weight=1e4)
    start = np.array([model.parameters[n].value for n in names])
    assert np.all(np.abs(np.log(held.values / start)) <= np.abs(np.log(free.values / start)) + 1e-9)
    assert held.rss >= free.rss * (1 - 1e-6)


def test_a_prior_by_parameter_holds_only_the_parameters_it_names(model, slice_data):
    record = record_from_measurements(model, slice_data, 60.0)
    names = ["G_jacket", "G_rotor_air", "G_bearing_endcap"]
    free = fit_records(model, [record], names, max_iter=30)
    held = fit_records(model, [record], names, max_iter=30, prior_weight={"G_rotor_air": 1e6})
    start = {n: model.parameters[n].value for n in names}
    moved_free = abs(math.log(free.values[1] / start["G_rotor_air"]))
    assert moved_free > 1e-3  # the record moves it when nothing holds it
    assert abs(math.log(held.values[1] / start["G_rotor_air"])) < 0.1 * moved_free
    assert held.rss >= free.rss * (1 - 1e-6)
    everything = fit_records(model, [record], names, max_iter=30, prior_weight=1e6)
    assert abs(math.log(everything.values[0] / start["G_jacket"])) < abs(math.log(held.values[0] / start["G_jacket"]))


@pytest.mark.parametrize("prior, field", [({"G_not_a_path": 1.0}, "prior_weight = 'G_not_a_path'"),
                                          ({"G_jacket": -2.0}, "prior_weight[G_jacket] = -2.0"),
                                          ({"G_jacket": "heavy"}, "prior_weight[G_jacket] = 'heavy'")])
def test_a_prior_by_parameter_names_a_bad_entry(model, slice_data, prior, field):
    record = record_from_measurements(model, slice_data, 60.0)
    with pytest.raises(InputError, match=field.replace("[", r"\[").replace("]", r"\]")):
        fit_records(model, [record], ["G_jacket", "G_rotor_air"], max_iter=5, prior_weight=prior)
