"""An inlet rise that follows the blocked generator's load (coolant.inlet_load_factor, fault key
``inlet_load_share``): the formula, the unchanged behaviour at share 0, bad input, and the rise
falling when load is displaced off the blocked generator."""

import casadi as ca
import numpy as np
import pytest

from genthermal.coolant import inlet_load_factor, inlet_rise
from genthermal.errors import InputError
from genthermal.mission import Mission
from genthermal.schedule.flight.closed_loop import true_inputs
from genthermal.schedule.power_system import PowerSystem


def _system(share=None, kind="coolant_blockage"):
    fault = {"generator": 1, "kind": kind, "onset_min": 10, "inlet_rise_C": 20, "inlet_rise_tau_min": 15}
    if kind == "coolant_blockage":
        fault["k_flow"] = 0.6
    if share is not None:
        fault["inlet_load_share"] = share
    document = {"name": "x", "generators": {"count": 2}, "actions": [{"condition": 5, "duration_min": 60}],
                "faults": [fault]}
    return PowerSystem.from_mission(Mission.from_dict(document))


def test_factor_is_one_minus_share_plus_share_times_the_squared_current_ratio():
    assert inlet_load_factor(2.0, 4.0, 1.0) == pytest.approx(0.25)
    assert inlet_load_factor(2.0, 4.0, 0.5) == pytest.approx(0.5 + 0.5 * 0.25)
    assert inlet_load_factor(6.0, 4.0, 0.4) == pytest.approx(0.6 + 0.4 * 2.25)
    assert inlet_load_factor(4.0, 4.0, 0.7) == 1.0  # at the undisplaced share the stated rise exactly
    # nobody carries anything (every generator off): no recirculated loss, only the load-free part
    assert inlet_load_factor(np.array([0.0]), np.array([0.0]), 0.3).tolist() == [pytest.approx(0.7)]
    # the same equation on CasADi expressions (the feasibility study differentiates through it)
    current, share = ca.SX.sym("I"), ca.SX.sym("a")
    function = ca.Function("f", [current, share], [inlet_load_factor(current, 4.0, share)])
    assert float(function(3.0, 0.6)) == pytest.approx(inlet_load_factor(3.0, 4.0, 0.6))
    # the rise: the time course of the fault times the factor
    t = np.array([0.0, 600.0, 1500.0, 3000.0])
    rise = inlet_rise(t, 600.0, 20.0, 900.0, 1.0, np.full(4, 3.0), np.full(4, 4.0))
    np.testing.assert_allclose(rise, inlet_rise(t, 600.0, 20.0, 900.0) * 9.0 / 16.0)


def test_share_zero_is_the_old_rise_bit_for_bit_whatever_the_currents():
    t = np.linspace(0.0, 3600.0, 121)
    displaced = np.vstack([np.linspace(0.5, 7.0, t.size), np.linspace(7.0, 0.0, t.size)])
    for kind in ("coolant_blockage", "inlet_rise"):
        old, zero = _system(None, kind), _system(0.0, kind)
        assert np.array_equal(zero.inlet_C(0, t, displaced), old.inlet_C(0, t))
        assert np.array_equal(zero.inlet_C(0, t), old.inlet_C(0, t))
    assert np.array_equal(inlet_rise(t, 600.0, 20.0, 900.0, 0.0, displaced[0], displaced.mean(axis=0)),
                          inlet_rise(t, 600.0, 20.0, 900.0))
    # with a share but no currents the generators carry their equal shares: the stated rise
    assert np.array_equal(_system(1.0).inlet_C(0, t), old.inlet_C(0, t))


@pytest.mark.parametrize("share", [-0.1, 1.5, float("nan"), True])
def test_bad_share_names_the_field_and_value(share):
    with pytest.raises(InputError, match="inlet_load_share"):
        inlet_load_factor(3.0, 4.0, share)
    if not isinstance(share, bool):
        with pytest.raises(InputError, match=r"faults\[0\]\.inlet_load_share"):
            _system(share)


def test_bad_currents_name_the_field():
    with pytest.raises(InputError, match="current_A"):
        inlet_load_factor(np.array([-1.0]), np.array([4.0]), 0.5)
    with pytest.raises(InputError, match="share_current_A"):
        inlet_load_factor(np.array([1.0]), np.array([np.nan]), 0.5)
    with pytest.raises(InputError, match="current_A"):  # the rise needs the load it follows
        inlet_rise([700.0], 600.0, 20.0, 0.0, 0.5)
    with pytest.raises(InputError, match="currents_A"):  # one row per generator, one column per time
        _system(1.0).inlet_C(0, [700.0, 800.0], [[4.0, 4.0]])


def test_the_rise_falls_when_load_is_displaced_off_the_blocked_generator():
    system = _system(1.0)
    t = np.array([3000.0])
    shared, displaced = np.array([[4.0], [4.0]]), np.array([[3.0], [5.0]])
    full = system.inlet_C(0, t, shared)[0]
    assert full == pytest.approx(system.inlet_C(0, t)[0])
    assert system.inlet_C(0, t, displaced)[0] - 20.0 == pytest.approx((full - 20.0) * 9.0 / 16.0)
    assert system.inlet_C(1, t, displaced)[0] == 20.0  # the healthy generator's inlet does not rise
    # the inlet the manager reads in the closed loop is that one
    read = true_inputs(system.frame(), ("T_inlet",), t, displaced)["T_inlet"]
    assert read[0, 0] == pytest.approx(system.inlet_C(0, t, displaced)[0])
    assert "0.5 of it following the load" in _system(0.5).describe()


def test_the_closed_loops_plant_flies_the_load_following_inlet():
    """The plant step of the closed loop (``closed_loop.plant_inputs`` into the model plant) reads
    the currents it flies: with load moved off the blocked generator a load-following rise leaves it
    cooler than a fixed one does; undisplaced the two are the same plant run."""
    from genthermal.plants.model_plant import ModelPlant
    from genthermal.schedule.flight.closed_loop import plant_inputs, plant_setup
    from genthermal.schedule.planning.plan import Schedule, build_timeline, mission_segments

    def end_winding(share, displaced_A):
        system = _system(share)
        segments = mission_segments(system.mission)
        schedule = Schedule(np.array([[displaced_A], [-displaced_A]]), np.zeros(1))
        timeline = build_timeline(segments, schedule, system.rest_current_A, 30.0)
        plant = ModelPlant(system.true_plants())
        plant.reset(plant_setup(system, 30.0))
        readings = plant.step(0.0, 30.0, plant_inputs(system.frame(), timeline, 0.0))
        return readings.values[0, 0, -1]

    assert end_winding(1.0, 0.0) == end_winding(0.0, 0.0)
    fixed, following = end_winding(0.0, 1.5), end_winding(1.0, 1.5)
    assert following < fixed - 1.0
