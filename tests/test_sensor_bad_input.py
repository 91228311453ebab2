"""Bad records in diagnose's sensor path: gaps, irregular sampling and missing sensor columns are
either handled (the faulty sensor still named) or refused with an error naming the column."""

import warnings

import numpy as np
import pytest

from genthermal.diagnose.compare import measured_series
from genthermal.diagnose.discovery import Discovery
from genthermal.diagnose.fitter import OnsetFitter
from genthermal.diagnose.hidden import make_hidden_effect_case
from genthermal.diagnose.sensor_faults import mean_of_finite, screen_redundant, sensor_columns
from genthermal.diagnose.sensor_screen import record_readings
from genthermal.errors import InputError
from genthermal.sensor_faults import SensorFault, inject_sensor_faults

HOUR = 3600.0
IRON_BIAS = SensorFault("T_iron", "bias", 3.0, 1.5 * HOUR)


@pytest.fixture(scope="module")
def iron_biased():
    """A 4-h record of the model's own plant at 60 s with the iron PT100 3 K high from 1.5 h."""
    healthy = make_hidden_effect_case(None, seed=3, dt_s=60.0).data
    return inject_sensor_faults(healthy, [IRON_BIAS])


@pytest.fixture(scope="module")
def discovery():
    return Discovery(fitter=OnsetFitter(pairs=False), design_experiment=False)


def _claims(discovery, model, data):
    return [(h.fault.sensor, h.fault.kind) for h in discovery.fit(model, data).sensor_faults]


def test_mean_of_finite_skips_gaps_and_leaves_nan_where_all_are_missing():
    rows = [np.array([1.0, np.nan, np.nan]), np.array([3.0, 5.0, np.nan])]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mean = mean_of_finite(rows)
    assert mean[:2].tolist() == [2.0, 5.0] and np.isnan(mean[2])


def test_a_gap_in_every_phase_sensor_warns_nothing_and_the_stuck_phase_is_still_named(plant_model):
    healthy = make_hidden_effect_case(None, seed=3).data
    data = inject_sensor_faults(healthy, [SensorFault("T_winding_v", "stuck", 0.0, 2.0 * HOUR)])
    data.loc[300:360, ["T_winding_u", "T_winding_v", "T_winding_w"]] = np.nan  # logger down for 10 min
    interface = plant_model.spec.interface
    series = measured_series(data, None, plant_model.output_names, interface)
    readings = record_readings(data, series, interface)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        found = screen_redundant(readings, series.inputs, series.time_s - series.time_s[0], series.dt_s,
                                 sensor_columns(interface), interface.generator.phase_inputs)
    assert [(h.fault.sensor, h.fault.kind) for h in found] == [("T_winding_v", "stuck")]


def test_gaps_in_the_faulty_sensor_and_in_a_phase_are_handled(iron_biased, plant_model, discovery):
    data = iron_biased.copy()
    data.loc[40:55, "T_iron"] = np.nan
    data.loc[150:170, "T_winding_u"] = np.nan
    assert _claims(discovery, plant_model, data) == [("T_iron", "bias")]


def test_irregular_sampling_is_resampled_and_the_fault_still_named(iron_biased, plant_model, discovery):
    keep = np.random.default_rng(0).random(len(iron_biased)) > 0.15  # a logger that loses 15 % of its rows
    keep[[0, -1]] = True
    data = iron_biased[keep].reset_index(drop=True)
    assert np.ptp(np.diff(data["time_s"].to_numpy())) > 0  # irregular
    assert _claims(discovery, plant_model, data) == [("T_iron", "bias")]


def test_a_record_without_the_optional_outlet_sensor_is_diagnosed(iron_biased, plant_model, discovery):
    assert _claims(discovery, plant_model, iron_biased.drop(columns=["T_outlet"])) == [("T_iron", "bias")]


@pytest.mark.parametrize("column", ["T_winding_v", "T_iron", "T_inlet", "T_ambient"])
def test_a_missing_sensor_column_is_refused_naming_it(iron_biased, plant_model, discovery, column):
    with pytest.raises(InputError, match=column):
        discovery.fit(plant_model, iron_biased.drop(columns=[column]))


def test_a_gap_in_an_input_sensor_is_refused_naming_column_and_row(iron_biased, plant_model, discovery):
    data = iron_biased.copy()
    data.loc[41, "T_inlet"] = np.nan
    with pytest.raises(InputError, match=r"T_inlet, data row 42"):  # data rows are counted from 1
        discovery.fit(plant_model, data)


def test_a_sensor_with_no_reading_at_all_is_refused(iron_biased, plant_model, discovery):
    data = iron_biased.copy()
    data["T_iron"] = np.nan
    with pytest.raises(InputError, match="T_iron"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        discovery.fit(plant_model, data)
