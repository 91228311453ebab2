"""A sensor fault fitted against the model is a finding only where the record shows it without the
model: a bias of a lone sensor needs a step in its reading, a noise increase a roughness the
other sensors do not share (the bench IPMSM's shipped slice, real thermocouples)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from genthermal.column_map import ColumnMap, read_logged
from genthermal.diagnose.multi_record import decimated, record_from_measurements, simulate_record
from genthermal.diagnose.sensor_faults import (SensorHypothesis, fit_noise_increase, fit_shape, sensor_columns,
                                               sensor_groups)
from genthermal.diagnose.sensor_plausibility import noise_refusal, refusal, robust_scale, roughness_change
from genthermal.machines import build_model, resolve_machine
from genthermal.resources import BENCH_MOTOR_DIR
from genthermal.sensor_faults import SensorFault

MACHINE_FILE = str(BENCH_MOTOR_DIR / "ipmsm_machine.py")
SLICE = BENCH_MOTOR_DIR / "id_9_first_3000s.csv"
STEP_S = 60.0


@pytest.fixture(scope="module")
def plain_on_slice():
    """The plain model (copper loss, constant convection, not calibrated) against the slice on a
    60-s grid: (model, elapsed s, measured outputs, predicted outputs, readings by column)."""
    machine = resolve_machine(MACHINE_FILE)
    data = decimated(read_logged(SLICE, ColumnMap.from_dict(machine.column_map, machine.interface),
                                 machine.interface), STEP_S)
    model = build_model(f"{MACHINE_FILE}:MACHINE_PLAIN")
    record = record_from_measurements(model, data)
    readings = {c: data.frame[c].to_numpy(float) for cols in sensor_columns(model.spec.interface).values()
                for c in cols}
    return model, data.time_s - data.time_s[0], record.outputs, simulate_record(model, record), readings


def _roughness(values):
    """Robust scale of the second differences of ``values``, K (white noise: sqrt(6) its std)."""
    return robust_scale(np.diff(values, 2))


def _phases(readings, columns):
    return tuple(c for group in sensor_groups(readings, columns).values() if len(group) > 1 for c in group)


def test_the_plain_models_misfit_on_a_lone_sensor_is_no_sensor_offset(plain_on_slice):
    """Fitted against the model, an offset of the lone rotor sensor removes much of the plain
    model's rotor misfit on the slice (the model's own error); the reading makes no step there that
    it does not make elsewhere, so it is no finding. From the record's start no reading can show
    an offset at all."""
    model, elapsed, measured, predicted, readings = plain_on_slice
    columns = sensor_columns(model.spec.interface)
    rotor = model.output_names.index("T_rotor")
    value, onset, before, after, signal = fit_shape("bias", measured[rotor] - predicted[rotor], predicted[rotor],
                                                    elapsed)
    assert abs(value) > 1.0 and after < 0.7 * before, (value, before, after)
    claim = SensorHypothesis(SensorFault("rotor", "bias", value, float(elapsed[onset])), onset, 1.0, 0.5, -100.0,
                             "model", signal, output="T_rotor")
    phases = _phases(readings, columns)
    reason = refusal(claim, readings, elapsed, {}, None, "T_water", "T_ambient", None, phases)
    assert reason is not None and "not distinguishable" in reason, reason
    start = SensorHypothesis(SensorFault("rotor", "bias", value, 0.0), 0, 1.0, 0.5, -100.0, "model",
                             np.full(elapsed.size, value), output="T_rotor")
    reason = refusal(start, readings, elapsed, {}, None, "T_water", "T_ambient", None, phases)
    assert reason is not None and "not distinguishable" in reason


@pytest.mark.parametrize("sensor, output", [("endcap", "T_endcap"), ("activewind_2", "T_winding")])
def test_a_true_offset_is_still_named(plain_on_slice, sensor, output):
    """A 3-K offset from 25 min on a lone sensor (its reading steps) or on one with a partner (the
    partner does not move) passes; the same claim on the untouched reading does not."""
    model, elapsed, measured, predicted, readings = plain_on_slice
    columns = sensor_columns(model.spec.interface)
    onset = int(np.searchsorted(elapsed, 1500.0))
    signal = np.where(np.arange(elapsed.size) >= onset, 3.0, 0.0)
    claim = SensorHypothesis(SensorFault(sensor, "bias", 3.0, float(elapsed[onset])), onset, 1.0, 0.5, -100.0,
                             "model", signal, output=output)
    faulty = {**readings, sensor: readings[sensor] + signal}
    phases = _phases(readings, columns)
    assert refusal(claim, faulty, elapsed, {}, None, "T_water", "T_ambient", None, phases) is None
    assert refusal(claim, readings, elapsed, {}, None, "T_water", "T_ambient", None, phases) is not None


def test_a_noise_claim_needs_a_roughness_the_other_sensors_do_not_share(plain_on_slice):
    model, elapsed, _, _, readings = plain_on_slice
    groups = sensor_groups(readings, sensor_columns(model.spec.interface))
    rng = np.random.default_rng(3)
    onset = int(np.searchsorted(elapsed, 1500.0))
    after = np.arange(elapsed.size) >= onset
    scale = 0.3  # K: well above the 60-s block means' own roughness
    noisy = {**readings, "endcap": readings["endcap"] + after * scale * rng.standard_normal(elapsed.size)}
    factor, found_onset, _ = fit_noise_increase(noisy["endcap"], elapsed)
    claim = SensorHypothesis(SensorFault("endcap", "noise", max(factor, 2.0), float(elapsed[found_onset])),
                             found_onset, float("nan"), float("nan"), -20.0, "noise", np.zeros(elapsed.size),
                             output="T_endcap")
    assert noise_refusal(claim, noisy, groups) is None
    # every reading roughened alike (each by the endcap's factor on its own roughness before, as
    # a faster load pattern does) is the temperatures', not the endcap sensor's noise
    factor = roughness_change(noisy["endcap"], onset)
    everywhere = {c: v + after * math.sqrt(factor ** 2 - 1) * _roughness(v[:onset])
                  * rng.standard_normal(elapsed.size) / 2.0 for c, v in readings.items()}
    everywhere["endcap"] = noisy["endcap"]
    reason = noise_refusal(claim, everywhere, groups)
    assert reason is not None and "other sensors" in reason


def test_a_lone_winding_offset_is_read_against_the_models_own_load_steps():
    """A winding sampled once a minute steps at every load step (its fast mode, about a minute):
    the reading alone makes larger steps there than a 4-K offset, so the offset is not shown by the
    reading alone; against a model that knows the load (10 % off in its gains) the load steps
    cancel and the offset is the one step left. The untouched reading with the same claim stays
    refused, and so does a misfit the load change starts and that grows with the node's inertia."""
    elapsed = np.arange(0.0, 4 * 3600.0 + 1, 60.0)
    load_steps = (1800.0, 5400.0, 9000.0, 12600.0)
    rises = (6.0, -5.0, 7.0, -6.0)  # K: the fast winding mode's share of each load step

    def node(gain, fast_s=60.0, slow_s=1800.0):
        curve = np.full(elapsed.size, 40.0)
        for t0, rise in zip(load_steps, rises):
            after = np.clip(elapsed - t0, 0.0, None)
            curve += gain * (elapsed >= t0) * (rise * (1 - np.exp(-after / fast_s))
                                               + 0.5 * rise * (1 - np.exp(-after / slow_s)))
        return curve

    truth, predicted = node(1.0), node(0.9)
    onset = int(np.searchsorted(elapsed, 3600.0))
    signal = np.where(np.arange(elapsed.size) >= onset, 4.0, 0.0)
    claim = SensorHypothesis(SensorFault("T_winding", "bias", 4.0, 3600.0), onset, 1.0, 0.5, -100.0, "model",
                             signal, output="T_winding")
    faulty = {"T_winding": truth + signal}
    healthy = {"T_winding": truth}
    model = {"T_winding": predicted}
    alone = refusal(claim, faulty, elapsed, {}, None)
    assert alone is not None and "its reading steps" in alone, alone
    assert refusal(claim, faulty, elapsed, {}, None, predicted=model) is None
    refused = refusal(claim, healthy, elapsed, {}, None, predicted=model)
    assert refused is not None and "reading minus the model" in refused, refused
    # a misfit from the onset that grows with the node's slow mode (a heat the model lacks)
    misfit = {"T_winding": truth + (elapsed >= 3600.0) * 4.0 * (1 - np.exp(-np.clip(elapsed - 3600.0, 0, None) / 900.0))}
    assert refusal(claim, misfit, elapsed, {}, None, predicted=model) is not None
