"""The flight's detection and identification under the model's error: the innovation CUSUM
learns each unit's own difference from its sisters, the identification scores on the AR(1) error
of the recalibrated model and refuses implausible effects. The plants are not the manager's model
(a sister unit's losses or cooling a few per cent off, plants 10-30 % off)."""

import types

import numpy as np
import pytest

from genthermal.diagnose.error_model import ErrorModel, SensorError
from genthermal.errors import InputError
from genthermal.estimation.kalman import KalmanFilter
from genthermal.mission import Mission
from genthermal.schedule.monitoring.innovation_detector import InnovationCusumSettings, innovation_cusum_alarms
from genthermal.schedule.power_system import PowerSystem

DT, CYCLE = 10.0, 30  # 10-s steps, 5-min management cycles, as in flight
WHITE = InnovationCusumSettings(inlet_tolerance_K=1.0)
LEARNT = InnovationCusumSettings(inlet_tolerance_K=1.0, learn_updates=8)
ONSET_MIN = 150.0
BLOCKAGE = (("coolant_flow_reduction", (("k_flow", 0.4),)),)


@pytest.fixture(scope="module")
def system():
    mission = Mission.from_dict({"name": "sisters", "generators": {"count": 2},
                                 "actions": [{"condition": 5, "duration_min": 60}]})
    return PowerSystem.from_mission(mission)


def _unit(system, factors=None, effects=()):
    """The design model of a unit whose parameters are the planning model's times ``factors``."""
    model = system.planning_model
    base = model.with_parameters(**{k: model.parameters[k].value * f for k, f in (factors or {}).items()})
    return system.design_generator_for(tuple(effects), base=base)


def _currents():
    """A 4-h load: four 15-min start-up steps (2-5 A), then 30-min legs of 4-6.5 A."""
    levels, minutes = [2, 3, 4, 5, 4.5, 6.0, 4.0, 6.5, 5.0, 6.0], [15] * 4 + [30] * 6
    return np.concatenate([np.full(int(m * 60 / DT), a) for a, m in zip(levels, minutes)])


def _record(units, changed=None, seed=1):
    """Both units carry the same load; unit 0 becomes ``changed`` at ``ONSET_MIN``; sensors with
    0.05-K noise."""
    current = _currents()
    n = current.size
    currents, inlet = np.tile(current, (len(units), 1)), np.full((len(units), n), 20.0)
    measured = np.empty((len(units), 2, n))
    for g, unit in enumerate(units):
        x, kalman = np.full(unit.model.n_states, 20.0), KalmanFilter(unit.model, DT)
        for i in range(n):
            if g == 0 and changed is not None and i == int(ONSET_MIN * 60 / DT):
                unit, kalman = changed, KalmanFilter(changed.model, DT)
            x, _ = kalman.predict(x, None, unit.input(currents[g, i], inlet[g, i], 20.0))
            measured[g, :, i] = kalman.C @ x + kalman.e
    return currents, inlet, measured + np.random.default_rng(seed).normal(0.0, 0.05, measured.shape)


@pytest.fixture(scope="module")
def sister_records(system):
    """Unit 0's resistance 5 % above its sister's (and the model's): healthy, and blocked at 150 min."""
    own = {"R0": 1.05}
    units = [_unit(system, own), _unit(system)]
    return {"healthy": _record(units), "blocked": _record(units, _unit(system, own, BLOCKAGE))}


def _alarms(system, record, settings):
    return innovation_cusum_alarms(system.design_generator_for(()), *record, 20.0, DT, CYCLE, settings)


def test_a_sister_unit_with_its_own_losses_rings_the_white_test_but_not_the_learnt_one(system, sister_records):
    white = _alarms(system, sister_records["healthy"], WHITE)
    assert len(white) > 20 and {a["generator"] for a in white} == {0}  # measured 43 over 4 h
    assert _alarms(system, sister_records["healthy"], LEARNT) == []


def test_a_blockage_on_that_unit_is_detected_as_soon_by_the_learnt_test(system, sister_records):
    """Margin: one 5-min cycle (measured: both alarm in the first cycle after the onset)."""
    first = {}
    for name, settings in (("white", WHITE), ("learnt", LEARNT)):
        alarms = _alarms(system, sister_records["blocked"], settings)
        first[name] = min(a["time_s"] for a in alarms if a["generator"] == 0 and a["time_s"] > ONSET_MIN * 60)
    assert first["learnt"] <= first["white"] + CYCLE * DT
    assert first["learnt"] - ONSET_MIN * 60 <= 2 * CYCLE * DT


def test_the_learnt_test_keeps_the_white_tests_verdict_on_identical_units(system):
    units = [_unit(system, {"h_end_air": 0.8, "R0": 1.2})] * 2  # both off alike, as on the robustness grid
    healthy = _record(units)
    assert _alarms(system, healthy, WHITE) == [] and _alarms(system, healthy, LEARNT) == []


@pytest.mark.parametrize("value", [3, 5, 8.5, -1])
def test_too_short_a_learning_window_is_refused_naming_it(value):
    with pytest.raises(InputError, match="learn_updates") as raised:
        InnovationCusumSettings(learn_updates=value)
    assert raised.value.value == value and "6" in raised.value.reason


def test_the_flight_refuses_implausible_effects_its_shape_variants_too():
    from genthermal.schedule.monitoring.fault_identification import implausible

    def candidate(effect, onset_s=3600.0, **values):
        return types.SimpleNamespace(effect=effect, values=values, onset_s=onset_s)
    assert implausible(candidate("coolant_flow_reduction+shape", k_flow=0.4, n_flow=0.3)) is None
    assert "k_flow" in implausible(candidate("coolant_flow_reduction+shape", k_flow=0.95, n_flow=0.3))
    assert "n_flow" in implausible(candidate("coolant_flow_reduction+shape", k_flow=0.4, n_flow=1.3))
    assert "R_short" in implausible(candidate("phase_short_circuit", R_short=3.0))
    assert implausible(candidate("phase_short_circuit", R_short=0.3)) is None


def _error_model(*names):
    return ErrorModel(tuple(SensorError(n, 0.3, 0.9, 0.05) for n in names), 60.0, "test")


def test_an_error_model_of_another_sensor_set_is_refused_naming_it(plant_model):
    from genthermal.diagnose.discovery import Discovery
    from genthermal.schedule.monitoring.fault_identification import identify_fault
    from genthermal.schedule.monitoring.monitor import DetectionSettings

    other = _error_model("T_winding", "T_outlet")
    with pytest.raises(InputError, match="error_model") as raised:
        identify_fault(plant_model, None, 0, 3600.0, DetectionSettings(), error_model=other)
    assert "T_outlet" in str(raised.value)
    with pytest.raises(InputError, match="error_model"):
        Discovery(error_model="white")
    _error_model(*plant_model.output_names).check_sensors(plant_model.output_names)  # its own: accepted


def _synthesized(model, hours, seed, onset_s=None, changed=None):
    from genthermal.resources import SCENARIO_DIR
    from genthermal.mission import load_mission
    from genthermal.synth import synthesize

    mission = load_mission(str(SCENARIO_DIR / "thesis_fig_7_7.yaml"))
    switches = [] if changed is None else [(onset_s, changed)]
    record = synthesize(model, mission, dt_s=10.0, seed=seed, switches=switches)
    return record[record["time_s"] <= hours * 3600.0]


def test_the_flight_error_model_needs_an_hour_of_record_and_says_so(plant_model):
    from genthermal.schedule.monitoring.flight_error import flight_error_model

    with pytest.raises(InputError, match="baseline") as raised:
        flight_error_model(plant_model, _synthesized(plant_model, 0.5, 2), 60.0)
    assert "1.0 h" in raised.value.reason


PLANT_OFF = {"R0": 1.2, "h_end_air": 0.8, "h_top_air": 1.15, "P_iron": 0.85, "m_dot_fan": 0.9}


@pytest.fixture(scope="module")
def recalibrated(plant_model):
    """The model recalibrated on the sister unit's 2-h healthy record of a plant 10-20 % off, and
    the error model of that record."""
    from genthermal.diagnose import calibrate
    from genthermal.schedule.monitoring.flight_error import flight_error_model
    from genthermal.schedule.monitoring.monitor import DetectionSettings

    plant = plant_model.with_parameters(**{k: plant_model.parameters[k].value * f for k, f in PLANT_OFF.items()})
    sister = _synthesized(plant, 2.0, seed=2)
    names = [n for n in DetectionSettings().calibrate_parameters if n in plant_model.parameters]
    model = calibrate(plant_model, sister, names, 60.0).model
    return plant, model, flight_error_model(model, sister, 60.0)


@pytest.mark.slow
def test_the_flight_error_model_of_a_mismatched_plant_lies_above_the_noise(recalibrated):
    _, model, error = recalibrated
    assert [s.sensor for s in error.sensors] == list(model.output_names)
    assert error.floor_K > error.noise_K and 0.0 <= max(s.phi for s in error.sensors) < 1.0
    assert error.effective_fraction() < 1.0


@pytest.mark.slow
def test_identification_on_the_error_model_still_names_a_real_blockage(recalibrated):
    from genthermal.schedule.monitoring.fault_identification import identify_fault
    from genthermal.schedule.monitoring.monitor import DetectionSettings

    plant, model, error = recalibrated
    record = _synthesized(plant, 2.0, seed=1, onset_s=3600.0,
                          changed=plant.with_effect("coolant_flow_reduction", k_flow=0.3))
    found = identify_fault(model, record, 0, 4200.0, DetectionSettings(), error_model=error)
    assert found.effect == "coolant_flow_reduction"
    assert found.onset_s == pytest.approx(3600.0, abs=600.0)
    assert 0.1 <= found.values["k_flow"] <= 0.5
