"""Rig data: schema validation, missing and out-of-range sensor samples, resampling, round trip."""

import io

import numpy as np
import pandas as pd
import pytest

from genthermal.errors import InputError
from genthermal.measurements import (
    REQUIRED_COLUMNS,
    dataframe_to_measurements,
    load_measurements,
    resample,
)

HEADER = ",".join(REQUIRED_COLUMNS)
GOOD_ROWS = [
    "0,1.0,1.1,1.2,0.50,20.0,19.0,25.0,25.2,25.4,24.0",
    "10,2.0,2.1,2.2,0.60,20.5,19.0,26.0,26.2,26.4,24.5",
    "20,3.0,3.1,3.2,0.70,21.0,19.5,27.0,27.2,27.4,25.0",
]


def csv_text(rows, header=HEADER):
    return "\n".join([header, *rows]) + "\n"


def load_text(text):
    return load_measurements(io.StringIO(text))


def replace_cell(row_index, column, value, rows=GOOD_ROWS):
    """GOOD_ROWS with one cell replaced (row_index 0-based, column by name)."""
    rows = [row.split(",") for row in rows]
    rows[row_index][REQUIRED_COLUMNS.index(column)] = value
    return [",".join(row) for row in rows]


def test_good_file_loads(tmp_path):
    path = tmp_path / "rig.csv"
    extra = [",30.0,start", ",31.0,", ",32.0,end"]
    path.write_text(csv_text([row + tail for row, tail in zip(GOOD_ROWS, extra)], HEADER + ",T_outlet,comment"))
    data = load_measurements(path)
    assert data.source == str(path)
    assert list(data.frame.index) == [0, 1, 2]
    assert all(dtype == float for dtype in data.frame.dtypes)
    assert list(data.frame.columns) == [*REQUIRED_COLUMNS, "T_outlet"]
    assert data.ignored_columns == ["comment"]
    assert data.flags == [] and set(data.missing_counts.values()) == {0}
    np.testing.assert_allclose(data.time_s, [0, 10, 20])
    assert list(data.inputs.columns) == ["I_u", "I_v", "I_w", "I_exc", "T_inlet", "T_ambient"]
    np.testing.assert_allclose(data.winding, [25.2, 26.2, 27.2])
    np.testing.assert_allclose(data.iron, [24.0, 24.5, 25.0])
    assert list(data.sensors.columns) == ["T_winding", "T_iron"]


BAD_FILES = [
    ("missing column", csv_text(GOOD_ROWS, HEADER.replace(",T_iron", "")), "T_iron", "T_iron"),
    ("misspelt column", csv_text(GOOD_ROWS, HEADER.replace("T_winding_v", "T_windng_v")), "T_winding_v",
     "did you mean 'T_windng_v'"),
    ("non-numeric", csv_text(replace_cell(1, "I_exc", "abc")), "column I_exc, data row 2", "'abc'"),
    ("infinite", csv_text(replace_cell(2, "T_iron", "inf")), "column T_iron, data row 3", "inf"),
    ("time not increasing", csv_text(replace_cell(2, "time_s", "10")), "column time_s, data row 3",
     "previous row has 10 s"),
    ("empty file", "", "file", "empty"),
    ("header only", HEADER + "\n", "file", "no data rows"),
    ("empty current", csv_text(replace_cell(0, "I_v", "")), "column I_v, data row 1", "empty cell"),
    ("empty time", csv_text(replace_cell(1, "time_s", "")), "column time_s, data row 2", "empty cell"),
    ("negative current", csv_text(replace_cell(1, "I_w", "-0.5")), "column I_w, data row 2", "-0.5"),
    ("inlet above PT100 range", csv_text(replace_cell(0, "T_inlet", "350")), "column T_inlet, data row 1",
     "350"),
    ("ambient below PT100 range", csv_text(replace_cell(2, "T_ambient", "-60")),
     "column T_ambient, data row 3", "-60"),
]


@pytest.mark.parametrize("text, field, value", [case[1:] for case in BAD_FILES], ids=[c[0] for c in BAD_FILES])
def test_bad_file_gives_input_error_naming_field_and_value(text, field, value):
    with pytest.raises(InputError) as caught:
        load_text(text)
    message = str(caught.value)
    assert field in message and value in message


def test_row_numbers_state_their_convention():
    with pytest.raises(InputError, match=r"data row 2 \(line 3 of the file\)"):
        load_text(csv_text(replace_cell(1, "I_u", "x")))
    frame = pd.read_csv(io.StringIO(csv_text(replace_cell(1, "I_u", "x"))))
    with pytest.raises(InputError, match=r"column I_u, data row 2 = 'x'"):
        dataframe_to_measurements(frame)


def test_empty_sensor_cells_are_missing_samples_and_counted():
    rows = replace_cell(0, "T_winding_u", "")
    rows = replace_cell(1, "T_winding_u", "", rows)
    rows = replace_cell(1, "T_winding_v", "", rows)
    rows = replace_cell(2, "T_iron", "", rows)
    data = load_text(csv_text(rows))
    assert data.missing_counts == {"T_winding_u": 2, "T_winding_v": 1, "T_winding_w": 0, "T_iron": 1}
    np.testing.assert_allclose(data.winding, [25.3, 26.4, 27.2])  # mean of the sensors that measured
    assert np.isnan(data.iron[2])


def test_winding_is_missing_only_when_all_three_sensors_are():
    rows = GOOD_ROWS
    for column in ("T_winding_u", "T_winding_v", "T_winding_w"):
        rows = replace_cell(1, column, "", rows)
    data = load_text(csv_text(rows))
    assert np.isnan(data.winding[1]) and np.isfinite(data.winding[[0, 2]]).all()


def test_out_of_range_sensor_values_are_flagged_and_discarded():
    rows = replace_cell(0, "T_iron", "-80")
    rows = replace_cell(2, "T_winding_w", "999", rows)
    data = load_text(csv_text(rows))
    assert np.isnan(data.frame.loc[0, "T_iron"]) and np.isnan(data.frame.loc[2, "T_winding_w"])
    assert data.missing_counts["T_iron"] == 1 and data.missing_counts["T_winding_w"] == 1
    assert len(data.flags) == 2
    assert any("T_iron" in flag and "-80" in flag and "PT100" in flag for flag in data.flags)
    assert any("T_winding_w" in flag and "999" in flag and "data row 3" in flag for flag in data.flags)


def test_dataframe_input_is_validated_the_same_way():
    frame = pd.read_csv(io.StringIO(csv_text(GOOD_ROWS)))
    frame.index = [5, 6, 7]
    data = dataframe_to_measurements(frame, "synthetic")
    assert data.source == "synthetic" and list(data.frame.index) == [0, 1, 2]
    frame.loc[6, "I_u"] = -1.0
    with pytest.raises(InputError, match="column I_u, data row 2 = -1.0"):
        dataframe_to_measurements(frame)


def rig_frame(time_s, **overrides):
    """A valid frame at the given times: inputs and sensors as functions of time unless overridden."""
    time_s = np.asarray(time_s, dtype=float)
    columns = {"time_s": time_s, "I_u": 1.0 + time_s / 100, "I_v": 2.0 + 0 * time_s, "I_w": 3.0 + 0 * time_s,
               "I_exc": 0.5 + time_s / 1000, "T_inlet": 20.0 + 0 * time_s, "T_ambient": 19.0 + 0 * time_s,
               "T_winding_u": 30.0 + time_s / 10, "T_winding_v": 30.0 + time_s / 10,
               "T_winding_w": 30.0 + time_s / 10, "T_iron": 25.0 + time_s / 20}
    columns.update(overrides)
    return pd.DataFrame(columns)


def test_resample_from_1_s_to_10_s():
    data = dataframe_to_measurements(rig_frame(np.arange(0.0, 61.0)))
    out = resample(data, 10.0)
    np.testing.assert_allclose(out.time_s, np.arange(0.0, 61.0, 10.0))
    np.testing.assert_allclose(out.frame["I_u"], 1.0 + out.time_s / 100)
    np.testing.assert_allclose(out.iron, 25.0 + out.time_s / 20)
    assert list(out.frame.index) == list(range(7))


def test_resample_irregular_sampling_holds_inputs_and_interpolates_sensors():
    time_s = np.array([0.0, 3.0, 12.0, 14.0, 27.0, 30.0])
    data = dataframe_to_measurements(rig_frame(time_s))
    out = resample(data, 10.0)
    np.testing.assert_allclose(out.time_s, [0.0, 10.0, 20.0, 30.0])
    # zero-order hold: the latest sample at or before t (t = 10 s → the 3 s sample; 20 s → 14 s)
    np.testing.assert_allclose(out.frame["I_u"], 1.0 + np.array([0.0, 3.0, 14.0, 30.0]) / 100)
    # linear sensors are reproduced exactly by linear interpolation
    np.testing.assert_allclose(out.iron, 25.0 + out.time_s / 20)


def test_resample_leaves_gaps_longer_than_dt_unmeasured():
    time_s = np.arange(0.0, 101.0, 5.0)
    iron = 25.0 + time_s / 20
    iron[(time_s > 20) & (time_s < 80)] = np.nan  # valid at 20 s and 80 s only around the gap
    out = resample(dataframe_to_measurements(rig_frame(time_s, T_iron=iron)), 10.0)
    expected_missing = [40.0, 50.0, 60.0]  # nearest valid sample 20 s away or more
    np.testing.assert_array_equal(out.time_s[np.isnan(out.iron)], expected_missing)
    np.testing.assert_allclose(out.iron[out.time_s == 30.0], 25.0 + 30.0 / 20)  # 10 s from 20 s: kept
    assert out.missing_counts["T_iron"] == 3


@pytest.mark.parametrize("dt_s", [0.0, -10.0, 1000.0, "ten"])
def test_resample_rejects_bad_steps(dt_s):
    data = dataframe_to_measurements(rig_frame(np.arange(0.0, 61.0)))
    with pytest.raises(InputError, match="dt_s"):
        resample(data, dt_s)


def test_round_trip_through_csv(tmp_path):
    time_s = np.array([0.0, 1.5, 4.0, 9.25])
    data = dataframe_to_measurements(rig_frame(time_s, T_winding_v=[31.0, np.nan, 33.3, 1e3],
                                                T_outlet=[22.0, 22.5, 23.0, 23.5]))
    path = tmp_path / "out.csv"
    data.to_csv(path)
    again = load_measurements(path)
    pd.testing.assert_frame_equal(again.frame, data.frame)
    assert again.missing_counts == data.missing_counts == {"T_winding_u": 0, "T_winding_v": 2,
                                                            "T_winding_w": 0, "T_iron": 0, "T_outlet": 0}
