"""Sensor faults told by their onset: a jump no heat flow makes, a frozen reading, an input jump the
machine did not follow; and the rig-plant records where the whole-record comparison cannot see them."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from genthermal.diagnose.discovery import Discovery
from genthermal.diagnose.fitter import OnsetFitter
from genthermal.diagnose.hidden import make_hidden_effect_case
from genthermal.diagnose.onset_signatures import (JUMP_MIN_SIGMA, frozen_tail, inertial_outputs, local_jump,
                                                  screen_frozen, screen_input_jumps)
from genthermal.model_file import load_model
from genthermal.sensor_faults import SensorFault, inject_sensor_faults

HOUR = 3600.0
DT_S = 10.0
RIG_PLANT = Path(__file__).resolve().parent.parent / "scenarios" / "data" / "rig_plant.yaml"


def _heating(n=1440, tau_s=1800.0, step_at=400, size=8.0):
    """A node heated by a load step: a first-order rise of ``size`` K from sample ``step_at``."""
    t = np.arange(n) * DT_S
    return np.where(t >= step_at * DT_S, size * (1 - np.exp(-(t - step_at * DT_S) / tau_s)), 0.0)


def test_a_step_is_found_with_its_size_and_sample_and_a_heating_is_not_a_step():
    rng = np.random.default_rng(1)
    predicted = 40.0 + _heating()
    misfit = 0.3 * _heating(tau_s=900.0)  # the model misses the plant's gain and time constant
    noise = 0.1 * rng.standard_normal(predicted.size)
    value, onset, z = local_jump(misfit + noise, predicted, DT_S, 0.1)
    assert z < JUMP_MIN_SIGMA  # the heating and its misfit are smooth
    biased = misfit + noise + np.where(np.arange(predicted.size) >= 900, -1.2, 0.0)
    value, onset, z = local_jump(biased, predicted, DT_S, 0.1)
    assert onset == 900 and value == pytest.approx(-1.2, abs=0.1) and z > JUMP_MIN_SIGMA


def test_a_frozen_reading_is_found_from_its_first_held_sample_and_a_noisy_one_is_not():
    rng = np.random.default_rng(2)
    reading = np.round(50.0 + _heating() + 0.1 * rng.standard_normal(1440), 2)  # logged to 0.01 K
    onset, held, noise = frozen_tail(reading)
    assert onset >= reading.size - 3  # a value repeated once or twice at the end, as rounding does
    assert screen_frozen({"T_iron": reading}, np.arange(1440) * DT_S, {"T_iron": ("T_iron",)}) == []
    reading[1000:] = reading[1000]
    onset, held, noise = frozen_tail(reading)
    assert onset == 1000 and held == reading[1000] and noise == pytest.approx(0.1, rel=0.2)
    [stuck] = screen_frozen({"T_iron": reading}, np.arange(1440) * DT_S, {"T_iron": ("T_iron",)})
    assert (stuck.fault.sensor, stuck.fault.kind, stuck.onset_index, stuck.evidence) == ("T_iron", "stuck", 1000,
                                                                                          "frozen")
    assert stuck.drops_reading


def test_a_short_run_of_equal_samples_is_not_a_stuck_sensor():
    reading = 50.0 + 0.1 * np.random.default_rng(3).standard_normal(1440)
    reading[-5:] = reading[-5]  # 50 s
    assert screen_frozen({"T_iron": reading}, np.arange(1440) * DT_S, {"T_iron": ("T_iron",)}) == []


def test_inertia_comes_from_the_response_after_one_sample():
    response = np.array([np.r_[0.0, 0.002, np.linspace(0.01, 1.0, 98)],   # a node with a heat capacity
                         np.r_[0.0, 0.7, np.full(98, 0.97)]])              # the cooling air
    assert inertial_outputs(response, ["T_iron", "T_outlet"]) == {"T_iron"}


def _input_case(followed: bool):
    n, onset, jump = 1440, 700, 1.8
    logged = np.full(n, 30.0)
    logged[onset:] += jump
    inputs = pd.DataFrame({"time_s": np.arange(n) * DT_S, "T_inlet": logged})
    response = np.vstack([1 - np.exp(-np.arange(n) * DT_S / tau) for tau in (2000.0, 4000.0, 20.0)])
    rng = np.random.default_rng(5)
    residual = 0.1 * rng.standard_normal((3, n)) + 0.5 * np.sin(np.arange(n) / 300.0)  # a smooth misfit
    if not followed:
        residual[:, onset:] -= jump * response[:, :n - onset]
    return inputs, residual, {"T_inlet": response}, onset, jump


@pytest.mark.parametrize("followed", [False, True])
def test_an_input_jump_the_machine_did_not_follow_is_the_sensors(followed):
    inputs, residual, responses, onset, jump = _input_case(followed)
    found = screen_input_jumps(inputs, residual, responses, DT_S, inputs["time_s"].to_numpy(), 0.1)
    if followed:
        assert found is None  # the machine saw the change: the inlet did change
    else:
        assert (found.fault.sensor, found.fault.kind, found.onset_index) == ("T_inlet", "bias", onset)
        assert found.fault.value == pytest.approx(jump, rel=0.1) and found.evidence == "input"


@pytest.fixture(scope="module")
def rig_record():
    """A healthy 4-h record of the rig plant (parameters 20-30 % off, an iron loss the model lacks)."""
    return make_hidden_effect_case(None, seed=100, plant=load_model(RIG_PLANT)).data


@pytest.mark.slow
@pytest.mark.parametrize("fault", [SensorFault("T_iron", "bias", -1.2, 1.3 * HOUR),
                                   SensorFault("T_iron", "stuck", 0.0, 2.1 * HOUR),
                                   SensorFault("T_iron", "drift", 1.0, 1.7 * HOUR),
                                   SensorFault("T_inlet", "bias", 1.5, 1.8 * HOUR),
                                   None])
def test_sensor_faults_are_named_on_a_plant_that_differs_from_the_model(rig_record, plant_model, fault):
    """Before the onset signatures the rig plant's 2-K misfit hid every iron and inlet fault."""
    data = rig_record if fault is None else inject_sensor_faults(rig_record, [fault])
    result = Discovery(fitter=OnsetFitter(pairs=False), design_experiment=False).fit(plant_model, data)
    claims = [(h.fault.sensor, h.fault.kind) for h in result.sensor_faults]
    assert claims == ([] if fault is None else [(fault.sensor, fault.kind)])
    if fault is not None and fault.kind != "stuck":
        [claim] = result.sensor_faults
        assert claim.fault.value == pytest.approx(fault.value, abs=0.3)
        assert claim.fault.onset_s == pytest.approx(fault.onset_s, abs=(2 if fault.kind == "bias" else 30) * DT_S)


def test_a_drift_is_found_on_top_of_a_calibration_misfit_and_a_misfit_alone_is_not_a_fault():
    from genthermal.diagnose.calibrated_screen import CalibratedFrame, sensor_hypotheses

    n, rng = 1440, np.random.default_rng(6)
    elapsed = np.arange(n) * DT_S
    sensitivity = np.vstack([_heating(n, 1800.0, 200, 5.0), _heating(n, 3600.0, 200, 3.0)])[None]
    misfit = 0.4 * sensitivity[0] + 0.1 * rng.standard_normal((2, n))  # a loss 40 % off the model's
    columns = {"T_winding": ("T_winding",), "T_iron": ("T_iron",)}
    readings = {"T_winding": misfit[0], "T_iron": misfit[1]}
    frame = CalibratedFrame(misfit, sensitivity)
    assert frame.rss / frame.n == pytest.approx(0.01, rel=0.15)  # what is left is the noise
    drifting = misfit.copy()
    drifting[1, 800:] += 1.2 * (elapsed[800:] - elapsed[800]) / HOUR
    frame = CalibratedFrame(drifting, sensitivity)
    best = min(sensor_hypotheses(frame, readings, elapsed, ["T_winding", "T_iron"], columns), key=lambda h: h.delta_bic)
    assert (best.fault.sensor, best.fault.kind) == ("T_iron", "drift")
    assert best.fault.value == pytest.approx(1.2, rel=0.1) and abs(best.onset_index - 800) <= 20


@pytest.mark.slow
@pytest.mark.parametrize("effect, seed", [("coolant_flow_reduction", 5), ("phase_short_circuit", 5),
                                          ("winding_insulation_degradation", 5), ("end_winding_stray_loss", 5),
                                          ("frame_cooling_change", 5), ("frame_cooling_change", 7)])
def test_no_physical_effect_of_the_rig_plant_is_taken_for_a_sensor_fault(plant_model, effect, seed):
    """The onset signatures and the calibrated comparison run on every rig record (the
    whole-record comparison claims nothing there): a machine effect must not pass them. Seed 7's
    better-cooled frame fitted like an ambient reading 11.9 K high until an input fault had to
    show in the logged input."""
    case = make_hidden_effect_case(effect, seed=seed, plant=load_model(RIG_PLANT))
    result = Discovery(fitter=OnsetFitter(pairs=False), design_experiment=False).fit(plant_model, case.data)
    assert result.sensor_faults == [], [h.fault.describe() for h in result.sensor_faults]


def test_an_input_fault_must_show_in_the_logged_reading():
    from genthermal.diagnose.calibrated_screen import logged_input_shows

    elapsed = np.arange(1440) * DT_S
    steady = np.full(1440, 25.0)
    assert not logged_input_shows(steady, elapsed, "bias", 2.0, 700)  # the reading never moved
    assert not logged_input_shows(steady, elapsed, "drift", 1.0, 700)
    jumped = steady + np.where(np.arange(1440) >= 703, 2.0, 0.0)
    assert logged_input_shows(jumped, elapsed, "bias", 1.8, 700)
    drifting = steady + np.where(elapsed >= elapsed[700], (elapsed - elapsed[700]) / HOUR, 0.0)
    assert logged_input_shows(drifting, elapsed, "drift", 1.1, 690)
