"""The speed-dependent catalogue effects: they apply to a machine declaring a speed (the bench
IPMSM's plain model), not to the generator, and reproduce the machine file's hand-written terms."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from genthermal.effects import CATALOGUE, apply_effect
from genthermal.errors import InputError
from genthermal.machines import InputKind, MachineInterface, ModelInput, Role, SpeedRole, build_model
from genthermal.resources import BENCH_MOTOR_DIR

MACHINE_FILE = str(BENCH_MOTOR_DIR / "ipmsm_machine.py")
SPEED_EFFECTS = ("speed_iron_loss", "iron_loss_hysteresis_eddy", "air_gap_convection_speed", "end_space_convection_speed", "ac_copper_loss",
                 "magnet_eddy_loss", "bearing_friction")
#: Sensors each effect at its typical size must warm (+1) or cool (-1) at speed under load.
DIRECTIONS = {"speed_iron_loss": {"T_slot_bottom": 1, "T_winding": 1},
              "iron_loss_hysteresis_eddy": {"T_slot_bottom": 1, "T_slot_open": 1},
              "air_gap_convection_speed": {"T_rotor": -1, "T_slot_open": 1},
              "end_space_convection_speed": {"T_end_winding": -1, "T_endcap": 1},
              "ac_copper_loss": {"T_winding": 1, "T_end_winding": 1},
              "magnet_eddy_loss": {"T_rotor": 1, "T_bearing": 1},
              "bearing_friction": {"T_bearing": 1, "T_rotor": 1}}
AT_SPEED = dict(motor_speed=3500.0, i_d=-100.0, i_q=200.0, T_water=25.0, T_ambient=23.0)


@pytest.fixture(scope="module")
def plain():
    return build_model(f"{MACHINE_FILE}:MACHINE_PLAIN")


def _steady(model, **inputs):
    u = model.input_vector(**inputs)
    return dict(zip(model.output_names, model.outputs(model.steady_state(u), u)))


def test_the_generator_takes_none_of_them(plant_model):
    for name in SPEED_EFFECTS:
        assert "speed" in CATALOGUE[name].unavailable_reason(plant_model)


def test_the_plain_ipmsm_takes_them_and_the_full_one_has_them(plain):
    full = build_model(MACHINE_FILE)
    for name in SPEED_EFFECTS:
        assert CATALOGUE[name].unavailable_reason(plain) is None, name
        assert "already" in CATALOGUE[name].unavailable_reason(full), name


@pytest.mark.parametrize("name", SPEED_EFFECTS)
def test_each_acts_at_speed_as_documented_and_not_at_rest(plain, name):
    effect = CATALOGUE[name]
    typical = {p.name: p.typical for p in effect.parameters}
    changed = apply_effect(plain, name, **typical)
    at_rest = dict(AT_SPEED, motor_speed=0.0)
    before, after = _steady(plain, **at_rest), _steady(changed, **at_rest)
    assert max(abs(after[k] - before[k]) for k in before) < 1e-6, name  # nothing at standstill
    before, after = _steady(plain, **AT_SPEED), _steady(changed, **AT_SPEED)
    for sensor, sign in DIRECTIONS[name].items():
        assert np.sign(after[sensor] - before[sensor]) == sign and abs(after[sensor] - before[sensor]) > 0.05, \
            (name, sensor, after[sensor] - before[sensor])


def test_the_catalogue_terms_are_the_machine_files_terms(plain):
    """Plain + five catalogue effects at the machine file's values = the full model without its
    iron loss (the file shares it by a fitted tooth share, the catalogue effect by mass)."""
    from genthermal.machines import resolve_machine

    machine = resolve_machine(MACHINE_FILE)
    without_iron = machine.build_network.__globals__["parameters_without"]("speed_iron_loss")
    full = build_model(dataclasses.replace(machine, default_parameters=lambda: without_iron))
    p = full.parameters
    model = plain
    for name, values in (("air_gap_convection_speed", {"k_gap_speed": p.value("G_gap_speed") / p.value("G_gap")}),
                         ("end_space_convection_speed", {"k_end_space": p.value("k_end_space_speed")}),
                         ("ac_copper_loss", {"k_ac_speed": p.value("k_ac")}),
                         ("magnet_eddy_loss", {"P_pm_speed": p.value("P_pm_ref"),
                                               "pm_loss_exponent": p.value("pm_speed_exponent"),
                                               "k_pm_load": p.value("k_pm_current")}),
                         ("bearing_friction", {"P_friction_speed": p.value("P_friction_ref")})):
        model = apply_effect(model, name, **values)
    for speed in (500.0, 2000.0, 4000.0):
        inputs = dict(AT_SPEED, motor_speed=speed)
        expected, got = _steady(full, **inputs), _steady(model, **inputs)
        assert max(abs(got[k] - expected[k]) for k in expected) < 1e-6, speed


def test_a_speed_role_is_checked():
    inputs = (ModelInput("n", "rpm", InputKind.SPEED, "speed"), ModelInput("I", "A", InputKind.CURRENT, "current"),
              ModelInput("T_c", "degC", InputKind.TEMPERATURE, "coolant", 20.0))
    with pytest.raises(InputError, match="reference_rpm.*-5"):
        SpeedRole("n", -5.0, 100.0)
    with pytest.raises(InputError, match=r"roles\[SPEED\].input.*'I'"):
        MachineInterface(inputs, (), {}, 100.0, "T_c", "T_c", roles={Role.SPEED: SpeedRole("I", 3000.0, 100.0)})
    with pytest.raises(InputError, match=r"roles\[SPEED\]"):
        MachineInterface(inputs, (), {}, 100.0, "T_c", "T_c", roles={Role.SPEED: "n"})
