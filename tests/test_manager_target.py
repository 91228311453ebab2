"""The onboard manager in C on the emulated Cortex-M4F against its Python reference, on the
thesis large-blockage flight: the plants differ from the manager's model (parameter mismatch, a
coolant blockage and inlet rise the model does not have)."""

import numpy as np
import pytest

from genthermal.codegen import forbidden_constructs
from genthermal.embedded import toolchain
from genthermal.embedded.manager import blockage_flight, build_flight_program, fly_on_target, fly_reference
from genthermal.errors import InputError
from genthermal.mission import load_mission
from genthermal.schedule.power_system import PowerSystem
from genthermal.simulate import simulate


@pytest.fixture(scope="module")
def system():
    return PowerSystem.from_mission(load_mission("blockage_large"))


@pytest.fixture(scope="module")
def flights(system, tmp_path_factory):
    """The blockage flight flown by the Python rule and by the C manager under QEMU."""
    try:
        toolchain.check_toolchain()
    except toolchain.TargetToolchainError as exc:
        pytest.skip(f"Cortex-M toolchain not installed: {exc}")
    design, settings, flight = blockage_flight(system)
    built = build_flight_program(design, settings, flight, tmp_path_factory.mktemp("flight"))
    return {"reference": fly_reference(design, settings, flight), "target": fly_on_target(built), "build": built}


def test_the_c_manager_on_the_target_takes_the_decisions_of_the_python_reference(flights):
    reference, target = flights["reference"], flights["target"]
    np.testing.assert_array_equal(target.flags, reference.flags)  # resting, decisions, plan, flags
    np.testing.assert_array_equal(target.currents_A, reference.currents_A)
    for name in ("plant_winding_C", "filtered_winding_C", "predicted_peak_C"):
        assert np.max(np.abs(getattr(target, name) - getattr(reference, name))) < 1e-6, name
    resting, displaced = reference.flags[:, 0], reference.flags[:, 3]
    assert displaced.any() and resting.any()  # the flight exercises displacement and rest


def test_the_manager_keeps_the_faulty_plant_below_the_limit_that_unmanaged_it_breaks(flights, system):
    assert flights["target"].plant_winding_C.max() < system.limit_C
    plant, switches = system.plant_switches(0)
    unmanaged = simulate(plant, system.mission.to_inputs(10.0).assign(
        T_inlet=lambda f: system.inlet_C(0, f["time_s"])), switches=switches)
    assert unmanaged["T_winding"].max() > system.limit_C + 5.0


def test_the_manager_allocates_nothing_and_has_no_mutable_static_data(flights):
    assert toolchain.heap_symbols(flights["build"]) == []
    assert forbidden_constructs(toolchain.support_file("manager.c").read_text()) == []
    assert 0 < flights["target"].stack_bytes < 4096


def test_a_flight_without_a_single_fault_on_the_first_generator_is_refused():
    healthy = PowerSystem.from_mission(load_mission("thesis_fig_7_7"))
    with pytest.raises(InputError, match="one fault with an effect on the first"):
        blockage_flight(healthy)
