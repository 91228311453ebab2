"""The machine owns its interface: consumers read inputs, sensors, ratings and limits from the model."""

import ast
import dataclasses
import io
import tokenize
from pathlib import Path

import numpy as np
import pytest

from genthermal.effects import CATALOGUE, applicable_effects
from genthermal.errors import InputError
from genthermal.machines import InputKind, MachineInterface, ModelInput, Role, Sensor, build_model
from genthermal.machines.genco_rf201a import INTERFACE, RATED_CURRENT_A, WINDING_LIMIT_C

PACKAGE = Path(__file__).resolve().parents[1] / "genthermal"
#: Genco RF201A facts no consumer may write down: its sensor names, rated current (as a float: the
#: integer 7 is a font size or a window length) and winding limit.
GENCO_STRINGS = {"T_winding", "T_iron"}


def _is_genco(value) -> bool:
    if isinstance(value, str):
        return value in GENCO_STRINGS
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    return value == WINDING_LIMIT_C or (isinstance(value, float) and value == RATED_CURRENT_A)
#: (file, literal) pairs that are not the Genco's facts, each with the reason.
ALLOWED = {
    ("exciter.py", 7.0): "the AVR law's default per-unit base: the Genco's exciter model itself (its parameters "
                         "are assumed for that machine); machines pass their rated current through "
                         "GeneratorRole.exciter_law",
    ("plots.py", 110): "figure resolution in dots per inch, not a temperature",
    ("schedule/power_system.py", 7.0): "smallest outlet plate diameter accepted for a blockage fault, mm",
}


def _literals(path: Path):
    """(line, value) of every string and number literal of the code, docstrings and comments left out."""
    source = path.read_text(encoding="utf-8")
    docstrings = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                docstrings.add(first.lineno)
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type == tokenize.STRING and token.start[0] not in docstrings:
            try:
                yield token.start[0], ast.literal_eval(token.string)
            except (ValueError, SyntaxError):  # f-strings
                continue
        elif token.type == tokenize.NUMBER:
            yield token.start[0], ast.literal_eval(token.string)


def test_no_consumer_hard_codes_the_genco():
    found, used_allowances = [], set()
    for path in sorted(PACKAGE.rglob("*.py")):
        relative = path.relative_to(PACKAGE).as_posix()
        if relative.startswith(("machines/", "data/")):  # machines, and machine files shipped as data
            continue
        for line, value in _literals(path):
            if not _is_genco(value):
                continue
            if (relative, value) in ALLOWED:
                used_allowances.add((relative, value))
                continue
            found.append(f"{relative}:{line}: {value!r}")
    assert not found, "consumers naming the Genco's sensors, rating or limit:\n" + "\n".join(found)
    assert used_allowances == set(ALLOWED), f"stale allowances: {set(ALLOWED) - used_allowances}"


def test_the_literal_scan_finds_a_hard_coded_sensor(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text('"""Docstring naming "T_winding" is fine."""\nLIMIT = 110.0\nCOLUMN = "T_iron"  # T_winding\n'
                     'FONT = 7\nRATED = 7.0\n')
    assert [v for _, v in _literals(probe) if _is_genco(v)] == [110.0, "T_iron", 7.0]


def test_the_model_reads_inputs_and_outputs_from_its_interface(plant_model):
    assert plant_model.input_names == INTERFACE.input_names
    assert plant_model.output_names == list(INTERFACE.output_names)
    assert plant_model.spec.rated_current_A == RATED_CURRENT_A
    assert plant_model.spec.interface.limits_C == {"T_winding": WINDING_LIMIT_C}
    u = plant_model.input_vector(I_u=3.0, T_inlet=30.0)
    expected = dict(INTERFACE.default_input_values(), I_u=3.0, T_inlet=30.0)
    np.testing.assert_array_equal(u, [expected[name] for name in INTERFACE.input_names])


@pytest.mark.parametrize("call, field", [
    (lambda m: m.input_vector(speed=3.0), "input speed"),
    (lambda m: m.input_vector(1, 2, 3, 4, 5, 6, 7), "input_vector"),
    (lambda m: m.input_vector(1.0, I_u=2.0), "input I_u"),
])
def test_bad_input_vectors_name_the_input(plant_model, call, field):
    with pytest.raises(InputError) as error:
        call(plant_model)
    assert error.value.field == field


def _interface(**changes):
    base = dict(inputs=(ModelInput("I", "A", InputKind.CURRENT, "current"),
                        ModelInput("T_c", "degC", InputKind.TEMPERATURE, "coolant", 20.0)),
                sensors=(Sensor("T_a", "a", ("T_a",), 0.01),), boundary_inputs={"c": "T_c"},
                rated_current_A=10.0, ambient_input="T_c", coolant_input="T_c")
    return MachineInterface(**{**base, **changes})


@pytest.mark.parametrize("changes, field", [
    ({"ambient_input": "T_x"}, "interface.ambient_input"),
    ({"rated_current_A": 0.0}, "interface.rated_current_A"),
    ({"roles": {"iron": ("a",)}}, "interface.roles"),
    ({"roles": {Role.LOAD_CURRENTS: ("J",)}}, "interface.roles[LOAD_CURRENTS]"),
    ({"rated_inputs": {"J": 1.0}}, "interface.rated_inputs"),
    ({"sensors": (Sensor("T_a", "a", ("T_a",), 0.0),)}, "sensor T_a.noise_variance_K2"),
])
def test_a_bad_interface_names_the_field(changes, field):
    with pytest.raises(InputError) as error:
        _interface(**changes)
    assert error.value.field == field


def test_a_missing_role_names_the_role_and_who_needs_it():
    with pytest.raises(InputError, match="no generator role.*power system"):
        _interface().generator


def test_effects_declare_typed_roles_and_apply_where_the_machine_has_them(plant_model, design_model):
    for effect in CATALOGUE.values():
        assert all(isinstance(role, Role) for role in effect.needs), effect.name
    names = {effect.name for effect in applicable_effects(plant_model)}
    assert {"coolant_flow_reduction", "phase_short_circuit", "end_winding_stray_loss"} <= names
    assert "quadratic_copper_loss" not in names  # needs the design model's linearised copper loss
    assert "quadratic_copper_loss" in {effect.name for effect in applicable_effects(design_model)}
    no_ends = dataclasses.replace(plant_model.spec.interface, roles={
        role: value for role, value in plant_model.spec.interface.roles.items() if role is not Role.END_WINDINGS})
    model = plant_model.with_network(plant_model.network, interface=no_ends)
    assert "end_winding_stray_loss" not in {effect.name for effect in applicable_effects(model)}
    with pytest.raises(InputError, match="no end_windings role"):
        model.with_effect("end_winding_stray_loss")


def test_an_effect_with_a_free_string_role_is_refused():
    from genthermal.effects import Effect

    with pytest.raises(InputError, match="Role members"):
        Effect("x", "x", "x", (), lambda network, roles: network, needs=("iron",))


def test_the_genco_figures_are_unchanged(plant_model):
    """Steady state at the rating point: the value the thesis-calibrated network gave before the interface."""
    u = plant_model.input_vector(**INTERFACE.rated_inputs)
    winding, iron = plant_model.outputs(plant_model.steady_state(u), u)
    assert winding == pytest.approx(101.8976, abs=1e-3) and iron == pytest.approx(71.3009, abs=1e-3)


def test_build_model_accepts_a_machine_object():
    from genthermal.machines.genco_rf201a import MACHINE

    assert build_model(MACHINE).output_names == list(INTERFACE.output_names)
