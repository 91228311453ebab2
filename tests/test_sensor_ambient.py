"""The ambient sensor against the inlet sensor of the same air: a wrong ambient reading is named, a
real change of the air is not, and what the outputs alone could tell is reported."""

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from genthermal.diagnose.calibrated_screen import CalibratedFrame
from genthermal.diagnose.discovery import Discovery
from genthermal.diagnose.fitter import OnsetFitter
from genthermal.diagnose.hidden import inject, make_hidden_effect_case
from genthermal.diagnose.shared_air import (MIN_CHANGE_K, fit_difference, machine_follows, minimal_detectable_error,
                                            screen_ambient_against_inlet)
from genthermal.mission import load_mission
from genthermal.model_file import load_model
from genthermal.sensor_faults import SensorFault, inject_sensor_faults

HOUR = 3600.0
DT_S = 10.0
N = 1440
NOISE_K = 0.1
RIG_PLANT = Path(__file__).resolve().parent.parent / "scenarios" / "data" / "rig_plant.yaml"


def _ambient_response(n=N):
    """(2, n) response of two outputs to a 1-K ambient step: 0.05 K/K through a 40-min frame."""
    elapsed = np.arange(n) * DT_S
    rise = 1.0 - np.exp(-elapsed / 2400.0)
    return np.vstack([0.05 * rise, 0.06 * rise])


def _frame(residual, n=N):
    """The residual with a slow calibration-like term and per-sensor offsets projected off."""
    slow = np.vstack([np.linspace(0, 1, n) ** 2, 0.5 * np.linspace(0, 1, n) ** 2])
    return CalibratedFrame(residual, slow[None])


def _readings(ambient_step=0.0, inlet_step=0.0, onset=700, offset=0.0, drift_K_per_h=0.0):
    elapsed = np.arange(N) * DT_S
    after = np.arange(N) >= onset
    ambient = 20.0 + offset + ambient_step * after + drift_K_per_h * after * (elapsed - elapsed[onset]) / HOUR
    inlet = 20.0 + inlet_step * after
    return pd.DataFrame({"T_ambient": ambient, "T_inlet": inlet}), elapsed


def _residual(error_K, onset, rng_seed=2):
    """What the outputs show when the ambient reading is wrong by ``error_K`` from ``onset``: the
    model follows the reading, the machine does not."""
    response = _ambient_response()
    residual = np.zeros_like(response)
    residual[:, onset:] = -error_K * response[:, :N - onset]
    return residual + NOISE_K * np.random.default_rng(rng_seed).standard_normal(residual.shape)


def _screen(inputs, elapsed, residual):
    return screen_ambient_against_inlet(inputs, "T_ambient", "T_inlet", elapsed, DT_S, lambda: _frame(residual),
                                        _ambient_response(), NOISE_K)


def test_an_ambient_reading_that_left_the_inlet_reading_is_the_sensors():
    inputs, elapsed = _readings(ambient_step=2.4, onset=700)
    found = _screen(inputs, elapsed, _residual(2.4, 700))
    assert (found.fault.sensor, found.fault.kind, found.evidence) == ("T_ambient", "bias", "input")
    assert found.fault.value == pytest.approx(2.4, abs=1e-6) and found.onset_index == 700
    np.testing.assert_allclose(found.signal, 2.4 * (np.arange(N) >= 700))


def test_an_ambient_drift_is_named_with_its_rate():
    inputs, elapsed = _readings(drift_K_per_h=1.2, onset=800)
    error = 1.2 * np.clip(elapsed - elapsed[800], 0, None) / HOUR
    residual = -np.array([np.convolve(np.diff(error, prepend=0.0), r)[:N] for r in _ambient_response()])
    found = _screen(inputs, elapsed, residual + NOISE_K * np.random.default_rng(3).standard_normal(residual.shape))
    assert (found.fault.kind, found.fault.value) == ("drift", pytest.approx(1.2, rel=1e-6))
    assert abs(found.onset_index - 800) <= 1


@pytest.mark.parametrize("case", ["the room warmed", "the inlet moved", "two airs", "too small"])
def test_no_ambient_claim_without_a_reading_that_left_the_same_air(case):
    readings = {"the room warmed": dict(ambient_step=3.0, inlet_step=3.0),  # both read the change
                "the inlet moved": dict(inlet_step=-3.0),  # a blockage or the inlet's own sensor
                "two airs": dict(ambient_step=3.0, offset=4.0),  # they never read the same air
                "too small": dict(ambient_step=0.8 * MIN_CHANGE_K)}[case]
    inputs, elapsed = _readings(onset=700, **readings)
    assert _screen(inputs, elapsed, _residual(0.0, 700)) is None


def test_the_machine_vetoes_a_real_ambient_change_it_followed():
    """A 20-K change of the ambient alone that the outputs followed (they show no shape) is not
    the sensor's, although the inlet did not move; a 20-K reading error they did not follow is."""
    inputs, elapsed = _readings(ambient_step=20.0, onset=500)
    assert _screen(inputs, elapsed, _residual(0.0, 500)) is None
    assert _screen(inputs, elapsed, _residual(20.0, 500)) is not None
    frame = _frame(_residual(0.0, 500))
    assert machine_follows(frame, _ambient_response(), 20.0, 500, NOISE_K) > 100.0
    assert machine_follows(_frame(_residual(20.0, 500)), _ambient_response(), 20.0, 500, NOISE_K) < -100.0


def test_the_difference_fit_finds_the_kind_and_the_sample():
    elapsed = np.arange(N) * DT_S
    kind, onset, value, offset, left = fit_difference(0.2 + 1.5 * (np.arange(N) >= 613), elapsed)
    assert (kind, onset) == ("bias", 613) and value == pytest.approx(1.5) and offset == pytest.approx(0.2)
    assert np.max(np.abs(left)) < 1e-9


def test_the_smallest_detectable_ambient_error_scales_with_the_noise_and_is_infinite_for_a_look_alike():
    response = _ambient_response()
    residual = NOISE_K * np.random.default_rng(5).standard_normal(response.shape)

    def factory(extra):
        return CalibratedFrame(residual, [np.zeros_like(residual), *extra])  # per-sensor offsets and ``extra``

    limit = minimal_detectable_error(factory, response, None, N // 2, NOISE_K, residual.size)
    assert 0.0 < limit < math.inf
    assert minimal_detectable_error(factory, response, None, N // 2, 2 * NOISE_K, residual.size) == \
        pytest.approx(2 * limit)
    same = np.zeros_like(response)
    same[:, N // 2:] = response[:, :N - N // 2]  # a frame cooling change that moves the outputs alike
    assert minimal_detectable_error(factory, response, same, N // 2, NOISE_K, residual.size) == math.inf


@pytest.fixture(scope="module")
def rig_record():
    """A healthy 4-h record of the rig plant (parameters 20-30 % off, an iron loss the model lacks)."""
    return make_hidden_effect_case(None, seed=100, plant=load_model(RIG_PLANT)).data


@pytest.mark.slow
@pytest.mark.parametrize("fault", [SensorFault("T_ambient", "bias", 2.4, 1.5 * HOUR),
                                   SensorFault("T_ambient", "drift", -1.0, 2.0 * HOUR)])
def test_a_wrong_ambient_reading_is_named_on_a_plant_that_differs_from_the_model(rig_record, plant_model, fault):
    """Before the inlet comparison no ambient fault of the rig plant was named: a 1-K error moves
    the outputs 0.05 K, and a better-cooled frame fitted as well."""
    data = inject_sensor_faults(rig_record, [fault])
    result = Discovery(fitter=OnsetFitter(pairs=False), design_experiment=False).fit(plant_model, data)
    [claim] = result.sensor_faults
    assert (claim.fault.sensor, claim.fault.kind) == ("T_ambient", fault.kind)
    assert claim.fault.value == pytest.approx(fault.value, abs=0.05)
    assert claim.fault.onset_s == pytest.approx(fault.onset_s, abs=2 * DT_S)


@pytest.mark.slow
def test_a_real_change_of_the_room_air_is_not_claimed_and_the_limit_is_reported(plant_model):
    """The room warms by 3 K at 1.8 h (inlet and ambient both read it, the machine follows):
    no sensor fault, and the verdict says how large an ambient error the outputs alone could tell."""
    inputs = load_mission("thesis_fig_7_7").to_inputs(DT_S)
    elapsed = inputs["time_s"].to_numpy(float) - inputs["time_s"].iloc[0]
    for column in ("T_ambient", "T_inlet"):
        inputs[column] = inputs[column] + 3.0 * (elapsed >= 1.8 * HOUR)
    record = inject(plant_model, [], inputs, seed=110)
    result = Discovery(fitter=OnsetFitter(pairs=False), design_experiment=False).fit(plant_model, record)
    assert result.sensor_faults == []
    limit = result.sensor_screen.limits["T_ambient"]
    assert 1.0 < limit < math.inf
    assert f"below {limit:.1f} K cannot be told from a frame cooling change" in result.iterations[0].explanation
    assert result.to_dict()["sensor_error_limits_K"] == {"T_ambient": limit}


@pytest.mark.slow
def test_a_real_ambient_change_the_machine_followed_is_not_claimed(plant_model):
    """The ambient alone rises 5 K (the inlet steady: the shared-air test alone would blame the
    sensor); on the model's own plant the outputs follow it, and the veto keeps the claim back."""
    inputs = load_mission("thesis_fig_7_7").to_inputs(DT_S)
    elapsed = inputs["time_s"].to_numpy(float) - inputs["time_s"].iloc[0]
    inputs["T_ambient"] = inputs["T_ambient"] + 5.0 * (elapsed >= 1.8 * HOUR)
    record = inject(plant_model, [], inputs, seed=110)
    result = Discovery(fitter=OnsetFitter(pairs=False), design_experiment=False).fit(plant_model, record)
    assert result.sensor_faults == []


@pytest.mark.parametrize("input_noise_K", [0.05, 0.3])
def test_noisy_inlet_and_ambient_readings_still_tell_the_ambient_step(input_noise_K):
    """Input PT100s as noisy as the others (0.05-0.3 K): the excursions of their difference are
    noise, not two airs; before, any excursion above 0.6 K refused the claim."""
    inputs, elapsed = _readings(ambient_step=2.4, onset=700)
    rng = np.random.default_rng(5)
    noisy = inputs + input_noise_K * rng.standard_normal(inputs.shape)
    found = _screen(noisy, elapsed, _residual(2.4, 700))
    assert found is not None and (found.fault.sensor, found.fault.kind) == ("T_ambient", "bias")
    assert found.fault.value == pytest.approx(2.4, abs=0.1)


@pytest.mark.parametrize("case", ["the room warmed", "two airs"])
def test_noisy_readings_do_not_make_a_same_air_claim_out_of_a_real_change(case):
    readings = {"the room warmed": dict(ambient_step=3.0, inlet_step=3.0),
                "two airs": dict(ambient_step=3.0, offset=4.0)}
    inputs, elapsed = _readings(onset=700, **readings[case])
    noisy = inputs + 0.3 * np.random.default_rng(6).standard_normal(inputs.shape)
    assert _screen(noisy, elapsed, _residual(0.0, 700)) is None
