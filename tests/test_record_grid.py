"""The in-flight record on the identification grid: inputs averaged over the interval each grid
row is held for, not sampled at the grid times (genthermal/schedule/monitoring/record_grid.py)."""

import numpy as np
import pandas as pd
import pytest

from genthermal.diagnose.compare import compare, measured_series
from genthermal.errors import InputError
from genthermal.schedule.monitoring.monitor import record_frame
from genthermal.schedule.monitoring.record_grid import on_fit_grid
from genthermal.simulate import simulate

STEP_S, FIT_DT_S, CYCLE_S = 10.0, 60.0, 300.0


def _flight_record(model, duration_s=4 * 3600.0):
    """A noise-free record in the flight's convention (inputs of the step ending at each row): 7 A
    with a 10-s rest at 1.9 A at the start of every 5-min cycle, on the 60-s grid's own times."""
    n = int(duration_s / STEP_S)
    start = STEP_S * np.arange(n)
    current = np.where(start % CYCLE_S < STEP_S, 1.9, 7.0)
    interface = model.spec.interface
    excitation = interface.generator.exciter_law(current, 0.85, 7.0)
    inputs = pd.DataFrame({"time_s": start, "I_u": current, "I_v": current, "I_w": current, "I_exc": excitation,
                           "T_inlet": 20.0, "T_ambient": 20.0})
    states = simulate(model, pd.concat([inputs, inputs.iloc[[-1]].assign(time_s=duration_s)], ignore_index=True))
    sensors = states[list(model.output_names)].to_numpy().T[:, 1:]  # read at the end of each step
    return record_frame(interface, start + STEP_S, current, excitation, np.full(n, 20.0), 20.0, sensors)


def _rmse_on(model, frame) -> float:
    return compare(model, measured_series(frame, FIT_DT_S, model.output_names, model.spec.interface)) \
        .metrics["rmse_all_sensors"]


def test_a_short_rest_on_the_grid_times_is_averaged_not_taken_for_the_whole_minute(plant_model):
    record = _flight_record(plant_model)
    sensors = [c for s in plant_model.spec.interface.sensors for c in s.columns]
    grid = on_fit_grid(record, FIT_DT_S, ["I_u", "I_v", "I_w", "I_exc"], sensors)
    assert np.allclose(np.diff(grid["time_s"]), FIT_DT_S) and grid["time_s"].iloc[0] == record["time_s"].iloc[0]
    # each row holds the steps ending in (T, T + 60]: the rest ends the row before a cycle start
    rested = grid["time_s"].to_numpy() % CYCLE_S == CYCLE_S - FIT_DT_S + STEP_S
    expected = np.sqrt((5 * 7.0 ** 2 + 1.9 ** 2) / 6)
    assert np.allclose(grid["I_u"].to_numpy()[rested][:-1], expected)
    assert np.allclose(grid["I_u"].to_numpy()[~rested][:-1], 7.0)
    # the model that made the record fits it on the grid; sampled at the grid times it does not
    assert _rmse_on(plant_model, grid) < 0.3
    assert _rmse_on(plant_model, record) > 1.0


def test_a_grid_that_is_not_a_whole_multiple_of_the_step_is_refused(plant_model):
    record = _flight_record(plant_model, duration_s=600.0)
    with pytest.raises(InputError, match="fit_dt_s"):
        on_fit_grid(record, 45.0, ["I_u"], ["T_iron"])
    with pytest.raises(InputError, match="record columns"):
        on_fit_grid(record, 60.0, ["I_x"], ["T_iron"])


def test_a_flight_whose_fit_grid_is_not_a_whole_number_of_steps_is_refused_before_it_flies():
    import dataclasses

    from genthermal.mission import load_mission
    from genthermal.schedule.flight.closed_loop import fly
    from genthermal.schedule.flight.manager_settings import ManagerSettings
    from genthermal.schedule.power_system import PowerSystem
    from genthermal.schedule.monitoring.sensor_watch import SensorWatchSettings

    system = PowerSystem.from_mission(load_mission("blockage_large"))
    settings = dataclasses.replace(ManagerSettings(), sensor_watch=SensorWatchSettings(identify_dt_s=45.0))
    with pytest.raises(InputError, match="sensor_watch.identify_dt_s"):
        fly(system, "heuristic", settings)
