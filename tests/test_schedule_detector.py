"""Fault detection on the EKF's disturbance states (genthermal.schedule.monitoring.detector) and in flight."""

import numpy as np
import pytest

from genthermal.errors import InputError
from genthermal.estimation.ekf import ExtendedKalmanFilter
from genthermal.estimation.kalman import KalmanFilter
from genthermal.mission import Mission
from genthermal.schedule.flight.closed_loop import fly
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.state_estimator import FLIGHT_EKF_SETTINGS
from genthermal.schedule.monitoring.detector import DetectorSettings, DisturbanceDetector, extra_heat_flow
from genthermal.schedule.power_system import PowerSystem
from genthermal.schedule.report import flight_summary

#: Every parameter the manager is unsure of off by 30 %, both directions (shared by both units).
MISMATCH = {"h_end_air": 0.7, "h_top_air": 1.3, "R0": 1.3, "P_iron": 0.7, "m_dot_fan": 1.3}


def _mission(faults):
    return Mission.from_dict({
        "name": "detector_test", "generators": {"count": 2, "plant_mismatch": MISMATCH}, "faults": faults,
        "actions": [{"condition": 3, "duration_min": 15}, {"condition": 4, "duration_min": 15},
                    {"condition": 6, "duration_min": 45}, {"condition": 7, "duration_min": 15}]})


def test_extra_heat_flow_combines_constant_and_load_scaled_disturbances(plant_model, design_model):
    ekf = ExtendedKalmanFilter(plant_model, 10.0, **FLIGHT_EKF_SETTINGS)
    nx = plant_model.n_states
    z = np.zeros(len(ekf.state_names))
    z[nx:] = [5.0, 1.0, 20.0, 4.0]  # q_winding, q_iron, q_load_winding, q_load_iron
    P = np.eye(len(z))
    P[nx, nx + 2] = P[nx + 2, nx] = 0.5
    q, variance = extra_heat_flow(ekf, z, P, 0.25)
    np.testing.assert_allclose(q, [5.0 + 0.25 * 20.0, 1.0 + 0.25 * 4.0])
    np.testing.assert_allclose(variance, [1.0 + 0.25**2 + 2 * 0.25 * 0.5, 1.0 + 0.25**2])
    with pytest.raises(InputError, match="extended Kalman"):
        extra_heat_flow(KalmanFilter(design_model, 10.0), z, P, 0.25)
    estimate_filter = ExtendedKalmanFilter(plant_model, 10.0)  # coolant-scaled states: not for the detector
    with pytest.raises(InputError, match="state-dependent"):
        extra_heat_flow(estimate_filter, np.zeros(len(estimate_filter.state_names)), None, 0.25)


def test_statistic_compares_with_the_healthy_median_and_the_cusum_is_one_sided():
    detector = DisturbanceDetector(3, DetectorSettings(winding_drift=1.0, winding_threshold=1.5, settle_s=0.0),
                                   ["winding"])
    flows = {0: 30.0, 1: 10.0, 2: 12.0}

    def extra(g, load):
        return np.array([flows[g]]), np.array([4.0])  # σ 2 W each: reference difference σ √8
    r = detector.statistics(extra, [1.0, 1.0, 1.0], [True, True, True])
    np.testing.assert_allclose(r[:, 0], [(30 - 11) / np.sqrt(8), (10 - 21) / np.sqrt(8), (12 - 20) / np.sqrt(8)])
    assert detector.update(600.0, r) == [(0, 0)]  # 6.7 − 1 > 1.5 at once; the cooler ones never alarm
    assert detector.sums[0, 0] == 0.0 and detector.sums[1, 0] == 0.0
    # a generator that took load on from the others is not tested
    r = detector.statistics(extra, [1.0, 0.6, 0.6], [True, True, True])
    assert np.isnan(r[0, 0]) and np.isfinite(r[1:, 0]).all()
    # a generator believed faulty is no reference; with no reference left a generator is not tested
    two = DisturbanceDetector(2, DetectorSettings(settle_s=0.0), ["winding"])
    r = two.statistics(extra, [1.0, 1.0], [False, True])
    assert np.isnan(r[1, 0]) and np.isfinite(r[0, 0])


def test_small_statistics_do_not_accumulate_and_nothing_is_tested_while_settling():
    settings = DetectorSettings(winding_drift=1.0, winding_threshold=1.5, iron_drift=2.5, settle_s=600.0)
    detector = DisturbanceDetector(2, settings, ["winding", "iron"])
    assert detector.update(300.0, np.array([[50.0, 50.0], [0.0, 0.0]])) == []  # settling
    assert all(detector.update(600.0 + k, np.array([[0.9, 2.4], [0.9, 2.4]])) == [] for k in range(50))
    assert detector.update(900.0, np.array([[2.0, 0.0], [0.0, 0.0]])) == []  # 1.0 <= 1.5
    assert detector.update(1200.0, np.array([[2.0, 0.0], [0.0, 0.0]])) == [(0, 0)]  # 2.0 > 1.5


def test_bad_detector_settings_name_the_field():
    with pytest.raises(InputError, match="detection.iron_threshold"):
        DetectorSettings(iron_threshold=-1.0)


def test_healthy_flight_with_30_percent_mismatch_raises_no_alarm():
    summary = flight_summary(fly(PowerSystem.from_mission(_mission([])), "engineer"))
    assert summary["false_alarms"] == 0 and summary["identified"] == [] and summary["detected_at_s"] is None


@pytest.mark.slow
def test_blockage_is_detected_within_ten_minutes_and_identified():
    onset_min = 40.0
    system = PowerSystem.from_mission(_mission([{"generator": 2, "kind": "coolant_blockage", "onset_min": onset_min,
                                                 "k_flow": 0.3, "inlet_rise_C": 10.0}]))
    summary = flight_summary(fly(system, "engineer", ManagerSettings(replan=False)))  # detection alone
    assert summary["false_alarms"] == 0
    assert summary["detect_delay_s"] is not None and summary["detect_delay_s"] <= 600.0, summary["detect_delay_s"]
    found = [i for i in summary["identified"] if i["effect"]]
    assert found, summary["identified"]
    first = found[0]  # an alarm a few minutes after the onset may not hold enough record yet
    assert first["generator"] == "gen2" and first["effect"] == "coolant_flow_reduction", first
    assert first["onset_s"] >= 60.0 * onset_min - 600.0 and first["detected_at_s"] <= 60.0 * onset_min + 1800.0
    assert abs(first["parameters"]["k_flow"] - 0.3) <= 0.1, first


def test_with_the_linear_filter_in_the_loop_the_detector_runs_on_its_own_extended_filters():
    onset_min = 40.0
    system = PowerSystem.from_mission(_mission([{"generator": 1, "kind": "effect", "effect": "excitation_iron_loss",
                                                 "onset_min": onset_min, "values": {"k_exc": 120.0}}]))
    result = fly(system, "engineer", ManagerSettings(replan=False, filter="kf"))
    assert np.all(np.isfinite(result.monitor.detector.peak_statistic))
    assert {a["generator"] for a in result.monitor.alarms} == {0}
    assert all(a["time_s"] > 60.0 * onset_min for a in result.monitor.alarms)
    alarms = [a for a in result.monitor.alarms if a["test"] == "disturbance"]  # on its own extended filters
    assert alarms and alarms[0]["node"] == "iron", alarms
    assert 60.0 * onset_min < alarms[0]["time_s"] <= 60.0 * onset_min + 900.0
