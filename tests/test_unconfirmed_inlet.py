"""The plan's hold on a warmer coolant-inlet reading under check: bounded in size and in time."""

import numpy as np

from genthermal.schedule.monitoring.unconfirmed_inlet import UnconfirmedInlet


def test_a_small_rise_is_held_whole_and_a_large_one_only_up_to_the_bound():
    hold = UnconfirmedInlet(held_K=4.0, max_hold_s=600.0, n_generators=2)
    np.testing.assert_allclose(hold.planned(0, 3600.0, np.array([23.0]), np.array([20.0])), [20.0])
    np.testing.assert_allclose(hold.planned(1, 3600.0, np.array([51.0]), np.array([20.0])), [47.0])
    assert hold.holds(0) and hold.holds(1)
    assert [e["rise_K"] for e in hold.events] == [3.0, 31.0]


def test_the_hold_ends_at_its_time_bound_and_starts_again_only_after_the_readings_agree():
    hold = UnconfirmedInlet(held_K=4.0, max_hold_s=600.0, n_generators=1)
    for t in (3600.0, 3900.0, 4200.0):  # the first held plan and two more cycles
        np.testing.assert_allclose(hold.planned(0, t, np.array([23.0]), np.array([20.0])), [20.0])
    np.testing.assert_allclose(hold.planned(0, 4500.0, np.array([23.0]), np.array([20.0])), [23.0])
    assert not hold.holds(0)
    [event] = hold.events
    assert event["until_s"] == 4500.0 and "without a decision" in event["ended"]
    np.testing.assert_allclose(hold.planned(0, 4800.0, np.array([23.0]), np.array([20.0])), [23.0])  # not again
    hold.agrees(0, 5100.0)
    np.testing.assert_allclose(hold.planned(0, 5400.0, np.array([23.0]), np.array([20.0])), [20.0])
    assert len(hold.events) == 2 and hold.holds(0)


def test_a_release_says_why_and_a_second_release_changes_nothing():
    hold = UnconfirmedInlet(held_K=4.0, max_hold_s=600.0, n_generators=1)
    hold.planned(0, 3600.0, np.array([25.0]), np.array([20.0]))
    hold.release(0, 3900.0, "confirmed by the record check")
    hold.release(0, 4200.0, "no check left")
    [event] = hold.events
    assert (event["until_s"], event["ended"]) == (3900.0, "confirmed by the record check")
    assert not hold.holds(0)


def test_nothing_is_held_or_reported_when_the_hold_is_zero():
    hold = UnconfirmedInlet(held_K=0.0, max_hold_s=600.0, n_generators=1)
    np.testing.assert_allclose(hold.planned(0, 3600.0, np.array([23.0]), np.array([20.0])), [23.0])
    assert not hold.holds(0) and hold.events == []
