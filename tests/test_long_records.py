"""Long records: block averages for fitting keep the mean loss and the timing, and bound the size."""

import numpy as np
import pandas as pd
import pytest

from genthermal.errors import InputError
from genthermal.long_records import (FITTING_STEPS_S, MAX_FITTING_SAMPLES, block_average, decimate_for_fitting,
                                      fitting_step)
from genthermal.measurements import REQUIRED_COLUMNS, dataframe_to_measurements


def record(hours: float, step_s: float, seed: int = 0):
    rng = np.random.default_rng(seed)
    time_s = np.arange(0.0, hours * 3600.0 + step_s / 2, step_s)
    current = 4.0 + 3.0 * (np.sin(time_s / 300.0) > 0) + rng.normal(0, 0.3, time_s.size)  # 5-min steps, noisy
    ramp = 40.0 + 10.0 * np.sin(2 * np.pi * time_s / 7200.0)  # sensors: a 2-hour cycle
    columns = {"time_s": time_s, "I_u": np.abs(current), "I_v": np.abs(current), "I_w": np.abs(current),
               "I_exc": np.full(time_s.size, 0.8), "T_inlet": np.full(time_s.size, 20.0),
               "T_ambient": np.full(time_s.size, 20.0)}
    columns.update({name: ramp for name in REQUIRED_COLUMNS if name.startswith("T_w") or name == "T_iron"})
    return dataframe_to_measurements(pd.DataFrame(columns), "synthetic")


def test_short_records_are_kept_as_they_are():
    data = record(2.0, 10.0)
    assert fitting_step(data) is None and decimate_for_fitting(data) == (data, None)


def test_a_week_at_1s_is_bounded_and_keeps_mean_loss_and_timing():
    data = record(7 * 24.0, 1.0)
    averaged, note = decimate_for_fitting(data)
    assert len(averaged.frame) <= MAX_FITTING_SAMPLES and "averaged" in note
    step = float(np.diff(averaged.time_s)[0])
    # the mean of I^2 (the copper loss) over the record is kept, which a plain mean of I would not
    np.testing.assert_allclose(np.mean(averaged.frame["I_u"] ** 2), np.mean(data.frame["I_u"] ** 2), rtol=1e-3)
    assert np.mean(averaged.frame["I_u"]) ** 2 < np.mean(averaged.frame["I_u"] ** 2)
    # a sensor is the centred average: it is the value at the grid time, not half a block later
    interior = averaged.frame.iloc[1:-1]
    exact = 40.0 + 10.0 * np.sin(2 * np.pi * interior["time_s"] / 7200.0)
    # (a 300-s window flattens the 2-hour cycle by 0.03 K; half a block late would be 1.3 K off)
    assert np.max(np.abs(interior["T_iron"] - exact)) < 0.05
    assert step in FITTING_STEPS_S


def test_a_gap_holds_the_inputs_and_leaves_the_sensors_missing():
    data = record(1.0, 1.0)
    frame = data.frame[(data.time_s < 1200) | (data.time_s >= 2400)].reset_index(drop=True)
    with pytest.warns(UserWarning, match="gap"):
        gappy = dataframe_to_measurements(frame, "gappy")
    averaged = block_average(gappy, 60.0)
    inside = (averaged.time_s > 1260) & (averaged.time_s < 2340)
    assert np.isfinite(averaged.frame[["I_u", "T_inlet"]].to_numpy()).all()
    assert averaged.frame.loc[inside, "T_iron"].isna().all()


def test_a_record_too_long_for_any_block_is_refused():
    data = record(24.0 * 45, 60.0)  # 45 days at 60 s: more than MAX_FITTING_SAMPLES even at the longest block
    with pytest.raises(InputError, match="split the record"):
        fitting_step(data)


def test_the_true_model_fits_its_own_long_record_on_the_longest_block():
    """12 h at 1 s with a load change every 10-40 min: on the longest fitting block the true model
    stays within the sensor noise (0.06 K RMSE; 300-s blocks gave 0.36 K, as a week at 1 s gave
    0.29 K: the block shifts the response of the 6.5-min mode to a load change inside it)."""
    from genthermal.diagnose.compare import compare
    from genthermal.machines import build_model
    from genthermal.synth import synthesize

    model = build_model()
    rng = np.random.default_rng(5)
    time_s = np.arange(0.0, 12 * 3600.0 + 1.0, 1.0)
    segment = np.searchsorted(np.cumsum(rng.uniform(600.0, 2400.0, 200)), time_s)
    load = rng.uniform(0.2, 1.1, 200)[segment] * 7.0
    inputs = pd.DataFrame({"time_s": time_s, "I_u": load, "I_v": load, "I_w": load, "I_exc": 0.5 + 0.05 * load,
                           "T_inlet": 20.0, "T_ambient": 22.0})
    data = dataframe_to_measurements(synthesize(model, inputs, dt_s=1.0, seed=2), "12 h at 1 s")
    longest = compare(model, block_average(data, FITTING_STEPS_S[-1])).metrics["rmse_all_sensors"]
    assert longest < 0.1
    assert compare(model, block_average(data, 300.0)).metrics["rmse_all_sensors"] > 3 * longest
