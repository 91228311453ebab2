"""The rewrites behind the generated C (genthermal.codegen_simplify) keep every value.

The design model's step with its copper-loss floors becomes ``A x + B u + c + D max(R u + r, 0)``:
equal to the model's step to rounding with the floors active and not, one floor per phase. The
select that replaces ``fmax``/``fmin`` against a constant gives C's results, NaN included, and no
call of libm's ``fmax`` is left in the generated step.
"""

import casadi as ca
import numpy as np
import pytest

from genthermal.codegen import generate_c
from genthermal.codegen_simplify import affine_with_floors, inline_floors


def _samples(seed: int, n: int = 100):
    """States (°C) and inputs: currents 0-9 A (the floors act below 1.6 A), inlet and ambient."""
    rng = np.random.default_rng(seed)
    for _ in range(n):
        yield rng.uniform(-20.0, 160.0, 8), np.concatenate([rng.uniform(0.0, 9.0, 4), rng.uniform(-40.0, 50.0, 2)])


@pytest.mark.parametrize("dt_s", [1.0, 10.0, 60.0])
def test_affine_form_of_the_design_step_equals_the_step(design_model, dt_s):
    step = design_model.discretise(dt_s).step
    affine = affine_with_floors(step)
    assert affine is not None and affine.name_in() == step.name_in()
    floors_active = 0
    for x, u in _samples(1):
        expected = np.asarray(step(x, u)).ravel()
        assert np.max(np.abs(np.asarray(affine(x, u)).ravel() - expected)) < 1e-12 * np.max(np.abs(expected))
        floors_active += bool(np.any(u[:3] < 1.6))
    assert floors_active > 10  # the samples exercise the floors


def test_affine_form_has_one_select_per_phase_floor(design_model):
    affine = affine_with_floors(design_model.discretise(10.0).step)
    selects = [k for k in range(affine.n_instructions()) if affine.instruction_id(k) == ca.OP_IF_ELSE_ZERO]
    assert 3 <= len(selects) <= 3 * design_model.n_states  # one floor per phase current, scaled per state
    assert not any(affine.instruction_id(k) in (ca.OP_FMAX, ca.OP_DIV) for k in range(affine.n_instructions()))


def test_affine_form_refuses_what_it_cannot_write(plant_model):
    assert affine_with_floors(plant_model.discretise(10.0).step) is None  # copper resistance of the state
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u", 2)
    of_state = ca.Function("step", [x, u], [x + ca.fmax(x[0], 0.0)])
    assert affine_with_floors(of_state) is None
    nested = ca.Function("step", [x, u], [x + ca.fmax(ca.fmax(u[0], 1.0) - u[1], 0.0)])
    assert affine_with_floors(nested) is None
    assert affine_with_floors(ca.Function("mx", [ca.MX.sym("x", 2)], [ca.MX.sym("x", 2) * 0])) is None


def test_affine_form_of_fmin_and_floors_against_inputs():
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u", 2)
    step = ca.Function("step", [x, u], [ca.vertcat(0.5 * x[0] + ca.fmin(u[0], 2.0), x[1] - 3 * ca.fmax(u[0], u[1]))])
    affine = affine_with_floors(step)
    for values in ([1.0, 0.0], [3.0, 5.0], [2.0, 2.0], [-1.0, 4.0]):
        np.testing.assert_allclose(np.asarray(affine([1.0, 2.0], values)), np.asarray(step([1.0, 2.0], values)),
                                   rtol=0, atol=1e-14)


@pytest.mark.parametrize("value", [np.nan, -np.inf, np.inf, -1.0, 0.0, 2.5])
def test_inline_floors_gives_cs_fmax_and_fmin_for_every_input(value):
    v = ca.SX.sym("v")
    function = ca.Function("f", [v], [ca.vertcat(ca.fmax(v, 0.0), ca.fmin(1.0, v), ca.fmax(v, v * 2))])
    inlined = inline_floors(function)
    expected = [np.fmax(value, 0.0), np.fmin(1.0, value), np.fmax(value, 2 * value)]
    np.testing.assert_array_equal(np.asarray(inlined(value)).ravel(), expected)
    assert sum(inlined.instruction_id(k) == ca.OP_FMAX for k in range(inlined.n_instructions())) == 1  # v vs 2v stays


def test_inline_floors_keeps_the_design_models_functions(design_model):
    for name in ("rhs", "jac_x", "outputs"):
        function = design_model.functions[name]
        inlined = inline_floors(function)
        for x, u in _samples(2, 20):
            np.testing.assert_array_equal(np.asarray(inlined(x, u, design_model.p0)),
                                          np.asarray(function(x, u, design_model.p0)))


def test_generated_step_calls_no_fmax(design_model, tmp_path):
    generated = generate_c(design_model, tmp_path, 10.0, "gts")
    step_source = (tmp_path / "gts_casadi_step.c").read_text()
    start = step_source.index("static int casadi_f0")
    body = step_source[start:step_source.index("\n}\n", start)]
    assert "fmax(" not in body and "/" not in body.split("{", 1)[1]  # no libm call, no division
    assert generated.exact


def test_reciprocals_remove_divisions_by_constants_and_keep_the_nonlinear_step(plant_model):
    step = plant_model.discretise(10.0).step
    faster = inline_floors(step, reciprocals=True)
    divisions = [k for k in range(faster.n_instructions()) if faster.instruction_id(k) == ca.OP_DIV]
    assert divisions == [] and any(step.instruction_id(k) == ca.OP_DIV for k in range(step.n_instructions()))
    for x, u in _samples(3, 50):
        expected = np.asarray(step(x, u)).ravel()
        assert np.max(np.abs(np.asarray(faster(x, u)).ravel() - expected)) < 1e-13 * np.max(np.abs(expected))
    v = ca.SX.sym("v")
    by_zero = inline_floors(ca.Function("f", [v], [v / 0.0, v / 4.0]), reciprocals=True)
    assert np.isinf(float(by_zero(1.0)[0])) and float(by_zero(1.0)[1]) == 0.25  # 1/0 is not a reciprocal
