"""The managed large blockage as a proxy of the chapter-7 calibration (thesis 7.3.3, Figs 7.13-7.15):
the timeline with the 10-min rest before landing, displacement moving heat from gen1 to gen2, and the
lowest reachable peak of two healthy generators (no displacement needed, the healthy peak)."""

import casadi as ca
import numpy as np
import pytest

from studies.chapter7 import ONSET_S, blockable
from studies.chapter7_managed import (CONDITIONS, LIMIT_C, REST_BEFORE_LANDING_S, REST_PERCENT,
                                                  ManagedBlockageProxy, best_displacement, managed_timeline,
                                                  smooth_excess)
from genthermal.mission import load_mission
from genthermal.model_file import load_model
from genthermal.simulate import simulate


@pytest.fixture(scope="module")
def chapter7():
    return load_model("genco_rf201a:chapter7")


def test_timeline_inserts_the_thesis_rest_before_landing():
    line = managed_timeline(30.0)
    mission = load_mission("thesis_fig_7_7")
    assert line["time_s"][-1] == pytest.approx(mission.duration_s + REST_BEFORE_LANDING_S)
    rest_start = CONDITIONS[-1][1]
    resting = line["rest"]
    assert np.all(line["current_A"][resting] == pytest.approx(REST_PERCENT / 100 * mission.rated_current_A))
    assert line["time_s"][resting][0] == pytest.approx(rest_start)
    assert np.sum(resting) * 30.0 == pytest.approx(REST_BEFORE_LANDING_S)
    # landing flies after the rest at the mission's own currents: 5 min at 100 %, then its continuous level
    landing = line["masks"][-1] > 0
    assert line["time_s"][landing][0] == pytest.approx(rest_start + REST_BEFORE_LANDING_S)
    assert line["current_A"][landing][0] == pytest.approx(mission.rated_current_A)
    # the four conditions do not overlap and never include the rest
    assert np.all(line["masks"].sum(axis=0) <= 1) and not np.any(line["masks"][:, resting])


def test_displacing_current_cools_gen1_and_heats_gen2(chapter7):
    proxy = ManagedBlockageProxy(blockable(chapter7), ["k_flow", "n_flow"], 60.0, None, 31.0, 41.5 * 60, ONSET_S)
    peaks = proxy.peaks(ca.DM([0.53, 0.5]), 0.1)
    evaluate = ca.Function("peaks", [proxy.displaced], [peaks["gen1"], peaks["gen2"]])
    none = [np.asarray(v).ravel() for v in evaluate(np.zeros(4))]
    some = [np.asarray(v).ravel() for v in evaluate(np.full(4, 1.0))]
    assert np.all(some[0][1:] < none[0][1:] - 1.0) and np.all(some[1] > none[1] + 1.0)
    # with nothing moved, gen2 flies the healthy mission (plus the rest): as the plain simulation
    healthy = simulate(chapter7, load_mission("thesis_fig_7_7").to_inputs(60.0))
    time_s = healthy["time_s"].to_numpy()
    cruise = (time_s >= CONDITIONS[0][1]) & (time_s < CONDITIONS[0][2])
    assert none[1][0] == pytest.approx(healthy["T_winding"].to_numpy()[cruise].max(), abs=0.2)


def test_two_healthy_generators_need_no_displacement(chapter7):
    """No fault: the two generators are alike, so the lowest worst peak moves nothing and stays below θmax."""
    result = best_displacement(chapter7, 1.0, 0.5, 0.0, 0.0, ONSET_S, dt_s=60.0)
    assert result["converged"]
    assert all(abs(c["displaced_A"]) < 0.05 for c in result["conditions"])
    assert result["worst_peak_C"] < LIMIT_C


def test_smooth_excess_is_near_the_hinge():
    values = [float(smooth_excess(ca.DM(v), LIMIT_C)) for v in (100.0, 110.0, 112.0, 150.0)]
    assert values[0] < 1e-6 and values[1] == pytest.approx(0.1 * np.log(2)) and values[2] == pytest.approx(2.0, abs=1e-6)
    assert values[3] == pytest.approx(40.0)


def test_the_excess_has_exact_derivatives_in_the_fitted_values_and_the_displacement(chapter7):
    """The fit (fit_chapter7 managed=True) differentiates the proxy exactly: its Jacobian in the
    blockage's flow fraction and in the displaced currents is finite, and a smaller flow or less
    displacement never lowers gen1's excess."""
    proxy = ManagedBlockageProxy(blockable(chapter7), ["k_flow", "n_flow"], 60.0, None, 31.0, 41.5 * 60, ONSET_S)
    theta = ca.MX.sym("theta", 2)
    excess = proxy.residuals(theta, 0.1)
    jacobian = ca.Function("jacobian", [theta, proxy.displaced],
                           [ca.jacobian(excess, theta), ca.jacobian(excess, proxy.displaced)])
    by_theta, by_displaced = (np.asarray(m) for m in jacobian([0.53, 0.5], np.full(4, 0.5)))
    assert np.all(np.isfinite(by_theta)) and np.all(np.isfinite(by_displaced))
    gen1 = slice(0, len(CONDITIONS))
    assert np.all(by_theta[gen1, 0] <= 1e-9)  # more flow, less excess
    assert np.all(np.diag(by_displaced[gen1]) <= 1e-9) and np.any(np.diag(by_displaced[gen1]) < -0.1)


def test_bad_inputs_name_their_field(chapter7):
    from genthermal.errors import InputError

    for bad in (0.0, -30.0, 7.0, float("nan")):
        with pytest.raises(InputError, match="dt_s"):
            managed_timeline(bad)
    with pytest.raises(InputError, match="k_flow"):
        best_displacement(chapter7, 1.5, 0.5, 31.0, 0.0, ONSET_S)
    with pytest.raises(InputError, match="n_flow"):
        best_displacement(chapter7, 0.5, float("nan"), 31.0, 0.0, ONSET_S)


def test_level_masks_split_each_condition_into_its_start_up_and_continuous_levels():
    """Each K-condition's 5-min start-up level and its continuous level (Table 7.1) partition its
    mask; landing's start-up level runs at 100 %, its continuous level at 76.7 %."""
    from studies.chapter7_managed import START_UP_S, level_masks

    line = managed_timeline(60.0)
    masks, names = level_masks(line)
    assert names[-2:] == ("landing_5min", "landing_continuous") and masks.shape == (2 * len(CONDITIONS), line["time_s"].size)
    assert np.array_equal(masks[0::2] + masks[1::2], line["masks"])
    assert np.all(masks[0::2].sum(axis=1) * 60.0 == START_UP_S)
    rated = load_mission("thesis_fig_7_7").rated_current_A
    assert np.all(line["current_A"][masks[-2] > 0] == pytest.approx(rated))
    assert np.all(line["current_A"][masks[-1] > 0] == pytest.approx(0.767 * rated))


def test_per_level_displacement_moves_current_only_in_its_level(chapter7):
    """With ``per_level`` a current displaced in landing's continuous level cools gen1's landing
    and leaves every earlier condition as it was."""
    proxy = ManagedBlockageProxy(blockable(chapter7), ["k_flow", "n_flow"], 60.0, None, 31.0, 41.5 * 60, ONSET_S,
                                 per_level=True)
    assert proxy.displaced.numel() == 2 * len(CONDITIONS)
    peaks = proxy.peaks(ca.DM([0.53, 0.5]), 0.1)
    evaluate = ca.Function("peaks", [proxy.displaced], [peaks["gen1"]])
    none = np.asarray(evaluate(np.zeros(8))).ravel()
    landing_continuous = np.asarray(evaluate(np.eye(8)[-1] * 1.5)).ravel()
    assert np.allclose(landing_continuous[:-1], none[:-1]) and landing_continuous[-1] < none[-1]


@pytest.mark.slow
def test_best_displacement_held_to_rated_current_never_exceeds_it(chapter7):
    """Held to 7 A per level, the receiver's current stays within it at every sample and nothing
    moves in landing's 5 min at 100 %; without the limit the same blockage sends gen2 past 7 A."""
    kwargs = dict(k_flow=0.6, n_flow=0.5, inlet_rise_C=26.0, inlet_rise_tau_s=36 * 60.0, onset_s=ONSET_S, dt_s=60.0,
                  inlet_load_share=1.0)
    held = best_displacement(chapter7, per_level=True, receiver_limit_A=7.0, **kwargs)
    assert held["receiver_max_current_A"] <= 7.0 + 1e-6
    assert held["displaced_A"]["landing_5min"] <= 1e-6 and held["displaced_A"]["landing_continuous"] > 0.1
    free = best_displacement(chapter7, **kwargs)
    assert free["receiver_max_current_A"] > 7.0 and set(free["displaced_A"]) == {c[0] for c in CONDITIONS}
