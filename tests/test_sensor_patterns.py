"""In-flight sensor-fault signatures: frozen readings, opposite heat flows, and the fault test of a
unit whose sensor is masked."""

import numpy as np

from genthermal.schedule.monitoring.detector import DetectorSettings, DisturbanceDetector
from genthermal.schedule.monitoring.sensor_patterns import frozen_since, opposite_flows


def _noisy(n, seed=0):
    return 60.0 + 0.09 * np.random.default_rng(seed).standard_normal(n)


def test_a_reading_frozen_after_a_noisy_one_is_found_with_its_start():
    time_s = 10.0 * np.arange(1, 61)
    values = _noisy(60)
    values[40:] = values[40]
    assert frozen_since(time_s, values, 12) == time_s[40]


def test_no_frozen_reading_on_a_live_sensor_a_short_run_or_a_noise_free_record():
    time_s = 10.0 * np.arange(1, 61)
    assert frozen_since(time_s, _noisy(60), 12) is None
    short = _noisy(60)
    short[52:] = short[52]  # 8 equal samples: fewer than 12
    assert frozen_since(time_s, short, 12) is None
    assert frozen_since(time_s, np.full(60, 20.0), 12) is None  # logged without noise: not judged
    masked = _noisy(60)
    masked[40:] = masked[40]
    masked[-1] = np.nan  # a masked sensor is not looked at
    assert frozen_since(time_s, masked, 12) is None


def test_opposite_flows_are_the_smaller_magnitude_of_two_opposite_signs():
    r = np.array([[2.0, -0.7], [1.5, 0.4], [-0.3, 1.1], [np.nan, -2.0]])
    np.testing.assert_allclose(opposite_flows(r), [0.7, 0.0, 0.3, 0.0])


def test_a_masked_unit_is_neither_tested_nor_a_reference():
    detector = DisturbanceDetector(3, DetectorSettings(), ["winding", "iron"])
    heat = {0: np.array([5.0, 1.0]), 1: np.array([0.0, 0.0]), 2: np.array([1.0, 0.2])}

    def extra(g, load_factor):
        return heat[g], np.array([1.0, 1.0])

    loads, healthy = [1.0, 1.0, 1.0], [True, True, True]
    plain = detector.statistics(extra, loads, healthy)
    masked = detector.statistics(extra, loads, healthy, {(2, 0), (2, 1)})
    assert np.isnan(masked[2]).all()
    # unit 0 against unit 1 alone: (5 - 0) / sqrt(2), not against the median of 1 and 2
    np.testing.assert_allclose(masked[0], (heat[0] - heat[1]) / np.sqrt(2.0))
    np.testing.assert_allclose(plain[0], (heat[0] - np.median([heat[1], heat[2]], axis=0)) / np.sqrt(2.0))


def test_an_excess_above_the_healthy_range_is_held_until_an_alarm_or_the_longest_hold():
    from genthermal.schedule.monitoring.sensor_patterns import UnconfirmedExcess

    held = UnconfirmedExcess([0.56, 1.15], max_hold_s=3600.0, n_generators=3)
    r = np.array([[0.65, 0.3], [0.2, 1.3], [0.9, -0.2]])
    held.update(600.0, r, believed_healthy=[True, True, False], masked_units={1})
    assert held.holds(0) and not held.holds(1) and not held.holds(2)  # 1 masked, 2 believed faulty
    held.update(900.0, np.zeros((3, 2)), [True, True, True], set())
    assert held.holds(0)  # a statistic back in the healthy range does not end it
    held.release(0, 1200.0, "fault test alarmed")
    assert not held.holds(0) and held.events[0]["until_s"] == 1200.0
    held.update(1500.0, r, [True, True, True], set())
    assert held.holds(0) and held.holds(1) and held.holds(2)
    held.update(1500.0 + 3600.0, np.zeros((3, 2)), [True, True, True], set())
    assert not any(held.holds(g) for g in range(3))
    assert {e["ended"] for e in held.events[1:]} == {"held 60 min without an alarm"}
