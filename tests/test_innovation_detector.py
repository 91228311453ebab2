"""The baseline detector (differential-innovation CUSUM) on synthetic flight records."""

import numpy as np
import pytest

from genthermal.errors import InputError
from genthermal.estimation.kalman import KalmanFilter
from genthermal.mission import Mission
from genthermal.schedule.monitoring.innovation_detector import InnovationCusumSettings, innovation_cusum_alarms
from genthermal.schedule.power_system import PowerSystem

DT, CYCLE = 10.0, 30  # 10-s steps, 5-min cycles


@pytest.fixture(scope="module")
def generator():
    mission = Mission.from_dict({"name": "baseline_test", "generators": {"count": 3},
                                 "actions": [{"condition": 5, "duration_min": 60}]})
    return PowerSystem.from_mission(mission).design_generator_for(())


def _record(generator, currents, heat_from_step=None, extra_K=0.0, ambient=20.0):
    """Sensors of the design model itself for ``currents`` (n_gen, n); generator 0's winding reads
    ``extra_K`` more from step ``heat_from_step`` on."""
    kalman = KalmanFilter(generator.model, DT)
    n_gen, n = currents.shape
    inlet = np.full((n_gen, n), 20.0)
    measured = np.empty((n_gen, 2, n))
    for g in range(n_gen):
        x = np.full(generator.model.n_states, ambient)
        for i in range(n):
            x, _ = kalman.predict(x, None, generator.input(currents[g, i], inlet[g, i], ambient))
            measured[g, :, i] = kalman.C @ x + kalman.e
    if heat_from_step is not None:
        measured[0, 0, heat_from_step:] += extra_K
    return currents, inlet, measured


def test_a_generator_reading_hotter_than_the_others_alarms_and_only_it(generator):
    n = 20 * CYCLE
    currents = np.full((3, n), 5.0)
    record = _record(generator, currents, heat_from_step=8 * CYCLE, extra_K=3.0)
    alarms = innovation_cusum_alarms(generator, *record, 20.0, DT, CYCLE)
    assert alarms and {a["generator"] for a in alarms} == {0}
    assert alarms[0]["time_s"] == pytest.approx(9 * CYCLE * DT)  # the first update that sees it
    healthy = innovation_cusum_alarms(generator, *_record(generator, currents), 20.0, DT, CYCLE)
    assert healthy == []


def test_a_generator_carrying_more_than_the_others_is_not_tested(generator):
    n = 12 * CYCLE
    currents = np.full((3, n), 4.0)
    currents[0] = 6.0
    record = _record(generator, currents, heat_from_step=2 * CYCLE, extra_K=5.0)
    assert innovation_cusum_alarms(generator, *record, 20.0, DT, CYCLE) == []


def test_bad_records_and_settings_name_the_field(generator):
    currents = np.full((1, 60), 5.0)
    with pytest.raises(InputError, match="at least 2 generators"):
        innovation_cusum_alarms(generator, *_record(generator, currents), 20.0, DT, CYCLE)
    currents = np.full((2, 60), 5.0)
    with pytest.raises(InputError, match="cycle_steps"):
        innovation_cusum_alarms(generator, *_record(generator, currents), 20.0, DT, 0)
    with pytest.raises(InputError, match="drift_K"):
        InnovationCusumSettings(drift_K=-1.0)


def _stepped(generator, record, references=None, settings=InnovationCusumSettings()):
    """Run :class:`InnovationCusum` cycle by cycle over ``record``; the alarms ``(cycle, g)``."""
    from genthermal.schedule.monitoring.innovation_detector import InnovationCusum

    currents, inlet, measured = record
    test = InnovationCusum(currents.shape[0], DT, 20.0, generator, settings)
    alarms = []
    for cycle, start in enumerate(range(0, currents.shape[1] - CYCLE, CYCLE)):
        stop = start + CYCLE
        for g in range(currents.shape[0]):
            test.predict(g, currents[g, start:stop], inlet[g, start:stop])
        alarms += [(cycle, g) for g, _ in test.update(measured[:, :, stop - 1], currents[:, start:stop].mean(axis=1),
                                                      references)]
    return alarms


def test_stepping_the_test_gives_the_record_runs_alarms(generator):
    n = 20 * CYCLE
    record = _record(generator, np.full((3, n), 5.0), heat_from_step=8 * CYCLE, extra_K=3.0)
    alarms = innovation_cusum_alarms(generator, *record, 20.0, DT, CYCLE)
    assert _stepped(generator, record) == [(round(a["time_s"] / (CYCLE * DT)) - 1, a["generator"]) for a in alarms]


def test_a_generator_without_a_reference_is_not_tested(generator):
    n = 12 * CYCLE
    currents = np.full((2, n), 5.0)
    hot = _record(generator, currents, heat_from_step=4 * CYCLE, extra_K=3.0)
    assert {g for _, g in _stepped(generator, hot)} == {0}
    assert _stepped(generator, hot, references=[[], [0]]) == []  # generator 1 believed faulty: 0 has none


def test_switching_a_filter_to_another_model_carries_its_nodes_and_restarts_its_sum(generator):
    from genthermal.schedule.monitoring.innovation_detector import InnovationCusum

    test = InnovationCusum(2, DT, 20.0, generator)
    test.x[0] = test.x[0] + 5.0
    test.sums[0] = 0.1
    test.use(0, generator)  # the same model: nothing happens
    assert test.sums[0] == 0.1
    other = PowerSystem.from_mission(Mission.from_dict({"name": "other", "generators": {"count": 2},
                                                        "actions": [{"condition": 5, "duration_min": 60}]}
                                                       )).design_generator_for(
        (("phase_short_circuit", (("R_short", 0.3),)),))
    test.use(0, other)
    assert test.sums[0] == 0.0 and test.generators[0] is other
    assert test.x[0] == pytest.approx(np.full(len(test.x[0]), 25.0))
    with pytest.raises(InputError, match="generators.count"):
        InnovationCusum(1, DT, 20.0, generator)


def test_a_reference_with_a_hotter_inlet_is_no_reference(generator):
    """Generator 0's inlet is 10 K hotter and its winding reads 3 K cold (its filter's own error):
    the original test has generator 1 alarm on the mirrored difference; with the inlet tolerance
    generator 1 has no reference, and generator 0 is still tested."""
    n = 12 * CYCLE
    currents, inlet, measured = _record(generator, np.full((2, n), 5.0), heat_from_step=4 * CYCLE, extra_K=-3.0)
    inlet = inlet.copy()
    inlet[0, 4 * CYCLE:] += 10.0
    record = (currents, inlet, measured)
    assert {g for _, g in _stepped(generator, record)} == {1}
    assert _stepped(generator, record, settings=InnovationCusumSettings(inlet_tolerance_K=1.0)) == []
    # generator 0 reads 25 K hot instead (more than its 10 K hotter inlet can explain): it alarms
    hot = (currents, inlet, measured + np.where(np.arange(2)[:, None, None] == 0, 28.0, 0.0) *
           (np.arange(n) >= 4 * CYCLE))
    assert {g for _, g in _stepped(generator, hot, settings=InnovationCusumSettings(inlet_tolerance_K=1.0))} == {0}
    with pytest.raises(InputError, match="inlet_tolerance_K"):
        InnovationCusumSettings(inlet_tolerance_K=-1.0)
