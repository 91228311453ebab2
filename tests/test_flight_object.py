"""``Flight(plant, manager, mission).run()``: the composed flight and its result's record and plot."""

import numpy as np
import pytest

from genthermal.errors import InputError
from genthermal.schedule.flight.closed_loop import fly
from genthermal.schedule.flight.flight import Flight, Manager
from genthermal.schedule.flight.manager_settings import ManagerSettings

from test_plants import SHORT_MISSION, FailsAt, LumpedPlant, _system


def test_a_flight_composed_of_plant_manager_and_mission_is_fly(tmp_path):
    system, path = _system(tmp_path, SHORT_MISSION)
    result = Flight(LumpedPlant(), Manager("engineer"), path).run()
    direct = fly(system, "engineer", ManagerSettings(), LumpedPlant())
    np.testing.assert_array_equal(result.temperatures_C, direct.temperatures_C)
    frame = result.to_pandas()
    assert len(frame) == result.time_s.size and frame["time_s"].iloc[-1] == 1800.0
    np.testing.assert_array_equal(frame["gen2_T_winding"].to_numpy(), result.temperatures_C[1, 0])
    np.testing.assert_array_equal(frame["gen1_current_A"].to_numpy()[:-1], result.currents_A[0])
    assert frame["action"].iloc[0] == 1 and frame["action"].iloc[-2] == 2 and frame["action"].isna().iloc[-1]
    assert result.summary()["max_T_winding"]["gen1"] == pytest.approx(frame["gen1_T_winding"].max())
    figure = tmp_path / "flight.png"
    result.plot(figure)
    assert figure.stat().st_size > 10_000


def test_a_failed_plant_gives_the_record_so_far(tmp_path):
    _, path = _system(tmp_path, SHORT_MISSION)
    result = Flight(FailsAt(600.0, "nan"), Manager("engineer"), path).run()
    frame = result.to_pandas()
    assert frame["time_s"].iloc[-1] == 600.0 and result.summary()["plant_fault"]["kind"] == "not_finite"


def test_a_manager_with_an_unknown_scheduler_is_refused():
    with pytest.raises(InputError, match="scheduler"):
        Manager("magic")
    with pytest.raises(InputError, match="planner_model"):
        Manager("milp", ManagerSettings(planner_model="nonlinear"))
