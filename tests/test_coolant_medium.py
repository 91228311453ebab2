"""The coolant inlet and the ambient are each other's redundant reading only where both read the
room's air: on the water-cooled bench IPMSM (shipped slice, real thermocouples) a water-reading
offset is judged on the reading's own step, and a bad coolant medium is named."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from genthermal.column_map import ColumnMap, read_logged
from genthermal.diagnose.multi_record import decimated
from genthermal.diagnose.sensor_faults import SensorHypothesis
from genthermal.diagnose.sensor_plausibility import refusal
from genthermal.errors import InputError
from genthermal.machines import resolve_machine
from genthermal.machines.genco_rf201a import INTERFACE as GENERATOR_INTERFACE
from genthermal.resources import BENCH_MOTOR_DIR
from genthermal.sensor_faults import SensorFault

MACHINE_FILE = str(BENCH_MOTOR_DIR / "ipmsm_machine.py")
SLICE = BENCH_MOTOR_DIR / "id_9_first_3000s.csv"
OFFSET_K = 5.0


@pytest.fixture(scope="module")
def slice_inputs():
    """(machine, elapsed s, readings of the logged inputs by name) on a 60-s grid."""
    machine = resolve_machine(MACHINE_FILE)
    data = decimated(read_logged(SLICE, ColumnMap.from_dict(machine.column_map, machine.interface),
                                 machine.interface), 60.0)
    readings = {name: data.frame[name].to_numpy(float) for name in ("T_water", "T_ambient")}
    return machine, data.time_s - data.time_s[0], readings


def _water_claim(elapsed):
    """A 5-K bias of the water reading from 25 min, as the input screen fits it through the model."""
    onset = int(np.searchsorted(elapsed, 1500.0))
    signal = np.where(np.arange(elapsed.size) >= onset, OFFSET_K, 0.0)
    claim = SensorHypothesis(SensorFault("T_water", "bias", OFFSET_K, float(elapsed[onset])), onset, 1.0, 0.5,
                             -100.0, "input", signal, columns=("T_water",), output="")
    return claim, signal


def test_the_motors_declare_water_and_the_generator_room_air(slice_inputs):
    machine, _, _ = slice_inputs
    assert machine.interface.coolant_medium == "water"
    assert resolve_machine("examples/pmsm/pmsm_machine.py").interface.coolant_medium == "water"
    assert GENERATOR_INTERFACE.coolant_medium == "room_air"


def test_a_water_offset_is_judged_on_its_own_step(slice_inputs):
    """Offset reading: its step at 25 min stands out of the reading's own smooth course, so the
    claim passes. Untouched reading: no step, so the same fit through the model is refused as not
    distinguishable from model error, not by comparing water with room air."""
    machine, elapsed, readings = slice_inputs
    claim, signal = _water_claim(elapsed)
    faulty = {**readings, "T_water": readings["T_water"] + signal}
    assert refusal(claim, faulty, elapsed, {}, None, "T_water", "T_ambient", None, (), None, same_air=False) is None
    reason = refusal(claim, readings, elapsed, {}, None, "T_water", "T_ambient", None, (), None, same_air=False)
    assert reason is not None and "not distinguishable" in reason and "same air" not in reason, reason


def test_the_room_air_rule_reads_the_water_ambient_difference(slice_inputs):
    """Under the air rule the water reading's partner is the ambient: the refusal of a claim the
    readings do not show names the two readings 'of the same air', which is wrong for water; the
    water rule (above) does not use the ambient."""
    _, elapsed, readings = slice_inputs
    claim, _ = _water_claim(elapsed)
    reason = refusal(claim, readings, elapsed, {}, None, "T_water", "T_ambient", None, (), None, same_air=True)
    assert reason is not None and "same air" in reason, reason


def test_a_bad_coolant_medium_is_named():
    with pytest.raises(InputError) as raised:
        dataclasses.replace(GENERATOR_INTERFACE, coolant_medium="oil")
    assert "coolant_medium" in str(raised.value) and "oil" in str(raised.value)
