"""A new sensor is one entry in the machine's interface: the flight reads it from there.

The machine is the thesis generator with a stator-teeth PT100 added (an iron node, which the fault
detector watches like the back-iron sensor); nothing else is changed for it. A sensor on a node the
fault detector has no drift for (the cooling-air outlet) is refused before take-off, naming it.
"""

import dataclasses

import numpy as np
import pytest

from genthermal.errors import InputError
from genthermal.machines import Sensor
from genthermal.schedule.flight.closed_loop import fly
from genthermal.schedule.flight.manager_settings import ManagerSettings

from test_plants import HOT_MISSION, _system


def _with_sensor(model, sensor: Sensor):
    interface = model.spec.interface
    return model.with_network(model.network, interface=dataclasses.replace(
        interface, sensors=(*interface.sensors, sensor)))


def test_a_flight_reads_a_sensor_added_to_the_machine(tmp_path):
    system, _ = _system(tmp_path, HOT_MISSION)
    noise_K2 = system.planning_model.spec.interface.sensors[1].noise_variance_K2
    three = _with_sensor(system.planning_model, Sensor("T_teeth", "stator_teeth", ("T_teeth",), noise_K2))
    result = fly(dataclasses.replace(system, model=three), "engineer", ManagerSettings())
    assert result.temperatures_C.shape[:2] == (2, 3) and result.plant_fault is None
    loaded = (result.time_s > 0.0) & (result.time_s <= 80 * 60.0)  # 95 % and 104 % of rated; 50 % after
    winding, teeth = result.temperatures_C[:, 0, loaded], result.temperatures_C[:, 2, loaded]
    # the copper loss leaves the slot winding through the teeth: while loaded the teeth read below
    # the winding (after the drop to 50 % the winding cools below them), and above the ambient air
    assert np.all(teeth < winding) and np.all(teeth[:, -1] > system.mission.T_ambient_C + 20.0)
    assert np.all(np.isfinite(result.temperatures_C))


def test_a_sensor_the_fault_detector_cannot_watch_is_named(tmp_path):
    system, _ = _system(tmp_path, HOT_MISSION)
    outlet = system.planning_model.spec.interface.outlet_sensor
    with pytest.raises(InputError, match="end_air_out") as error:
        fly(dataclasses.replace(system, model=_with_sensor(system.planning_model, outlet)), "engineer")
    assert outlet.node == "end_air_out" and "capacitive" in str(error.value)
