"""The matrix exponential of :mod:`genthermal.discretise`, numeric and symbolic, and the parametric step."""

import casadi as ca
import mpmath
import numpy as np
import pytest

from genthermal.discretise import (PHI_NORM_HEADROOM, ModalDecay, discretise, parametric_step, phi_matrices,
                                   symbolic_phi_function)
from genthermal.errors import InputError


def _state_matrix(model, p=None):
    p = model.p0 if p is None else p
    return np.asarray(model.functions["jac_x"](np.zeros(model.n_states), np.zeros(len(model.input_names)), p))


def _reference_phis(L, h):
    """:math:`(e^{hL}, \\Gamma_1, \\Gamma_2)` with 40 digits: :math:`\\Gamma_1 = L^{-1}(E - I)`,
    :math:`\\Gamma_2 = L^{-1}(\\Gamma_1 - hI)`."""
    with mpmath.workdps(40):
        A, identity = mpmath.matrix(L.tolist()), mpmath.eye(L.shape[0])
        E = mpmath.expm(A * h)
        inverse = mpmath.inverse(A)
        G1 = inverse * (E - identity)
        G2 = inverse * (G1 - h * identity)
        return tuple(np.array(M.tolist(), dtype=float) for M in (E, G1, G2))


@pytest.mark.parametrize("h", [0.5, 7.0, 60.0, 3600.0])
def test_numeric_exponential_matches_40_digits(plant_model, h):
    L = _state_matrix(plant_model)
    for got, expected in zip(phi_matrices(L, h), _reference_phis(L, h)):
        assert np.max(np.abs(got - expected)) <= 1e-13 * np.max(np.abs(expected))


def test_zero_step_is_the_identity(plant_model):
    E, G1, G2 = phi_matrices(_state_matrix(plant_model), 0.0)
    assert np.array_equal(E, np.eye(8)) and not G1.any() and not G2.any()


@pytest.mark.parametrize("factor", [1.0, 0.05, 30.0])
def test_symbolic_exponential_holds_far_from_the_nominal_parameters(plant_model, factor):
    """Built for the nominal ``L``, evaluated at ``L`` scaled by ``factor`` (a fit moving every rate)."""
    nominal = _state_matrix(plant_model)
    symbol = ca.SX.sym("k")
    exponential = symbolic_phi_function(8, 60.0, nominal)
    phis = ca.Function("phis", [symbol], exponential.call([symbol * ca.DM(nominal)]))
    assert factor < PHI_NORM_HEADROOM
    for got, expected in zip(phis(factor), _reference_phis(factor * nominal, 60.0)):
        assert np.max(np.abs(np.asarray(got) - expected)) <= 1e-12 * np.max(np.abs(expected))


@pytest.mark.parametrize("dt_s", [7.0, 60.0])
def test_parametric_step_is_the_discrete_step(plant_model, design_model, dt_s):
    x, u = ca.SX.sym("x", 8), ca.SX.sym("u", 6)
    x0 = np.linspace(25.0, 110.0, 8)
    u0 = plant_model.input_vector(5.0, 6.0, 7.0, 1.0, 40.0, 30.0)
    for model in (plant_model, design_model):
        p = ca.SX.sym("p", len(model.p0))
        parametric = parametric_step(model, x, u, p, dt_s)
        step = ca.Function("step", [x, u, p, *parametric.phis], [parametric.x_next])
        L = ca.Function("L", [p], [parametric.state_matrix])(model.p0)
        got = step(x0, u0, model.p0, *parametric.exponential.call([L]))
        expected = np.asarray(model.discretise(dt_s).step(x0, u0))
        assert np.max(np.abs(np.asarray(got) - expected)) < 1e-10


def test_modal_decay_is_the_exponential(design_model):
    L = _state_matrix(design_model)
    decay, v = ModalDecay.of(L, design_model.name), np.linspace(-5.0, 40.0, 8)
    E = phi_matrices(L, 450.0)[0]
    assert np.max(np.abs(decay.apply(v, 450.0) - E @ v)) < 1e-10
    h = ca.SX.sym("h")
    symbolic = ca.Function("decay", [h], [decay.apply(v, h)])
    assert np.max(np.abs(np.asarray(symbolic(450.0)).ravel() - E @ v)) < 1e-10


@pytest.mark.parametrize("h", [-1.0, np.nan, np.inf])
def test_bad_step_length_is_named(plant_model, h):
    with pytest.raises(InputError, match="h_s"):
        phi_matrices(_state_matrix(plant_model), h)
    with pytest.raises(InputError, match="dt_s"):
        parametric_step(plant_model, ca.SX.sym("x", 8), ca.SX.sym("u", 6), ca.SX(plant_model.p0), h)


def test_oscillating_matrix_has_no_modal_decay():
    with pytest.raises(InputError, match="real, negative eigenvalues"):
        ModalDecay.of(np.array([[-0.1, 1.0], [-1.0, -0.1]]), "oscillator")


def test_linearisation_inputs_keep_a_steep_speed_dependent_convection_stable():
    """A conductance rising with speed is the explicit part of the step; taken from zero speed it
    makes the step unstable at top speed (|eigenvalue| > 1), taken from mid-range it does not, and
    is closer to the finely resolved solution at a short step (the same model)."""
    from genthermal.machines.interface import InputKind, MachineInterface, ModelInput, Sensor
    from genthermal.model import ModelSpec, ThermalModel
    from genthermal.network import HeatSource, Link, Network, Node
    from genthermal.losses import input_symbol
    from genthermal.parameters import Parameter, ParameterSet

    parameters = ParameterSet([Parameter("C_air", 100.0, "J/K", "assumed", "test"),
                               Parameter("C_part", 5000.0, "J/K", "assumed", "test"),
                               Parameter("G_rest", 10.0, "W/K", "assumed", "test"),
                               Parameter("G_rise", 30.0, "W/K", "assumed", "test")])
    S = parameters.symbols()
    network = Network((Node("air", "capacitive", S["C_air"], "air"), Node("part", "capacitive", S["C_part"], "solid"),
                       Node("water", "boundary", role="T_water")),
                      (Link("air", "water", 1 / S["G_rest"], "rest"), Link("part", "air", 1 / S["G_rest"], "rest")), ())
    theta = network.temperature_symbol
    flow = S["G_rise"] * input_symbol("speed") / 4000.0 * (theta("air") - theta("part"))
    network = network.with_heat_sources((HeatSource("air", -flow, "rise"), HeatSource("part", flow, "rise")))
    inputs = (ModelInput("speed", "rpm", InputKind.SPEED, "speed"),
              ModelInput("T_water", "degC", InputKind.TEMPERATURE, "water", 25.0))
    sensors = (Sensor("T_part", "part", ("part",), 0.01, None, "part"),)

    def model(linearisation):
        interface = MachineInterface(inputs, sensors, {"water": "T_water"}, 1.0, ambient_input="T_water",
                                     coolant_input="T_water", linearisation_inputs=linearisation)
        return ThermalModel(network, parameters, ModelSpec(name="rise", interface=interface))

    top = np.array([4000.0, 25.0])
    x = np.array([60.0, 40.0])
    radii = {}
    for label, linearisation in (("zero", {}), ("mid", {"speed": 2000.0})):
        step = discretise(model(linearisation), 20.0).step
        xs = ca.SX.sym("x", 2)
        A = np.asarray(ca.Function("A", [xs], [ca.jacobian(step(xs, top), xs)])(x))
        radii[label] = float(np.max(np.abs(np.linalg.eigvals(A))))
    assert radii["zero"] > 1.0 > radii["mid"]
    fine, state = discretise(model({}), 0.01).step, x  # the same model, resolved finely
    for _ in range(100):
        state = np.asarray(fine(state, top)).ravel()
    error = {label: np.max(np.abs(np.asarray(discretise(model(lin), 1.0).step(x, top)).ravel() - state))
             for label, lin in (("zero", {}), ("mid", {"speed": 2000.0}))}
    assert error["mid"] < min(error["zero"], 0.05)
    with pytest.raises(InputError, match="linearisation_inputs"):
        MachineInterface(inputs, sensors, {"water": "T_water"}, 1.0, ambient_input="T_water",
                         coolant_input="T_water", linearisation_inputs={"rpm": 2000.0})
