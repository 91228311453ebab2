"""Input sensors (coolant inlet, ambient) that froze or got noisier, told from the reading alone."""

import numpy as np
import pandas as pd
import pytest

from genthermal.diagnose.input_readings import screen_input_readings
from genthermal.sensor_faults import SensorFault

HOUR = 3600.0
ELAPSED = np.arange(0.0, 3 * HOUR + 1, 60.0)
AIR = 20.0 + 2.0 * np.sin(2 * np.pi * ELAPSED / (2.5 * HOUR))  # room air wandering by 2 K


def _inputs(noise_K: float, seed: int = 7) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    return pd.DataFrame({"T_inlet": AIR + noise_K * rng.standard_normal(AIR.size),
                         "T_ambient": AIR + noise_K * rng.standard_normal(AIR.size)})


def _with(inputs, fault: SensorFault, noise_K: float) -> pd.DataFrame:
    changed = inputs.copy()
    changed[fault.sensor] = fault.reading(ELAPSED, changed[fault.sensor].to_numpy(), noise_K,
                                          np.random.default_rng(1))
    return changed


def _claims(inputs):
    return [(h.fault.sensor, h.fault.kind, round(h.fault.onset_s / HOUR, 1))
            for h in screen_input_readings(inputs, ["T_inlet", "T_ambient"], ELAPSED)]


@pytest.mark.parametrize("noise_K", [0.0, 0.05, 0.3])
def test_a_healthy_input_reading_is_not_claimed(noise_K):
    assert _claims(_inputs(noise_K)) == []


@pytest.mark.parametrize("sensor", ["T_inlet", "T_ambient"])
@pytest.mark.parametrize("kind, value", [("stuck", 0.0), ("noise", 3.0)])
def test_a_noisy_input_that_froze_or_got_noisier_is_named_with_its_onset(sensor, kind, value):
    assert _claims(_with(_inputs(0.1), SensorFault(sensor, kind, value, 1.5 * HOUR), 0.1)) == [(sensor, kind, 1.5)]


def test_a_noise_free_logged_input_that_stops_changing_is_not_called_stuck():
    # a logged set point: no sensor noise, so a constant stretch is what a healthy one looks like
    held = _with(_inputs(0.0), SensorFault("T_inlet", "stuck", 0.0, 1.5 * HOUR), 0.0)
    assert _claims(held) == []


def test_white_noise_rarely_passes_for_a_noise_increase():
    # 200 healthy 4-h readings at 60 s: the correlated second differences made 9 of them pass
    # before the likelihood ratio was divided by their variance inflation
    from genthermal.diagnose.sensor_faults import MIN_NOISE_FACTOR, PREFERENCE_BIC, fit_noise_increase

    elapsed = np.arange(240) * 60.0
    passed = 0
    for seed in range(200):
        factor, _, delta = fit_noise_increase(0.1 * np.random.default_rng(seed).standard_normal(240), elapsed)
        passed += factor >= MIN_NOISE_FACTOR and delta < -PREFERENCE_BIC
    assert passed <= 2
