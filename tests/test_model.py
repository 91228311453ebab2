"""Physical invariants of the assembled thesis generator model."""

import numpy as np
import pytest
import sympy
from scipy.integrate import solve_ivp

from genthermal import elements as el
from genthermal.losses import input_symbol
from genthermal.machines.genco_rf201a import INTERFACE

INPUT_NAMES = INTERFACE.input_names

RATED = dict(I_u=7.0, I_v=7.0, I_w=7.0, I_exc=1.0, T_inlet=20.0, T_ambient=20.0)


def test_thesis_node_counts(plant_model):
    """Thesis 4.2.4: 19 nodes -> 12 without intermediate nodes -> 8 states."""
    assert plant_model.network.reduction_stages() == {"all_nodes": 19, "without_intermediate": 12, "states": 8}
    assert plant_model.n_states == 8


def test_zero_load_with_boundaries_at_T0_stays_at_T0(plant_model):
    u = plant_model.input_vector(0, 0, 0, 0, 35.0, 35.0)
    model = plant_model.with_parameters(P_iron=0.0, provenance="assumed", source="no losses")
    x = np.full(8, 35.0)
    assert np.max(np.abs(model.rhs(x, u))) < 1e-12
    X = np.asarray(model.discretise(10.0).simulator(100)(x, np.tile(u[:, None], (1, 100))))
    assert np.max(np.abs(X - 35.0)) < 1e-10


def _outflow(model, x, u):
    """Heat leaving through the air stream and the frame (W), written out independently."""
    v = model.parameters.values()
    theta = model.node_temperatures(x, u)
    air = v["c_air"] * v["m_dot_fan"] * (theta["end_air_out"] - u[INPUT_NAMES.index("T_inlet")])
    R_famb = float(el.frame_to_ambient(v["r_f2"], v["L_s"], v["L_fei"], v["L_feo"], v["h_ambient"]))
    frame = (theta["frame"] - u[INPUT_NAMES.index("T_ambient")]) / R_famb
    return air + frame


@pytest.mark.parametrize("current", [2.0, 5.0, 7.0])
def test_steady_state_energy_balance(plant_model, current):
    u = plant_model.input_vector(**{**RATED, "I_u": current, "I_v": current, "I_w": current, "T_inlet": 25.0})
    x = plant_model.steady_state(u)
    losses = float(plant_model.functions["heat"](x, u, plant_model.p0))
    assert losses > 0
    assert abs(_outflow(plant_model, x, u) - losses) / losses <= 1e-9


def test_more_load_is_hotter_everywhere(plant_model):
    previous = None
    for current in np.linspace(0.0, 7.0, 8):
        u = plant_model.input_vector(**{**RATED, "I_u": current, "I_v": current, "I_w": current})
        theta = np.array(list(plant_model.node_temperatures(plant_model.steady_state(u), u).values()))
        if previous is not None:
            assert np.all(theta > previous)
        previous = theta


def test_hotter_inlet_is_hotter_everywhere(plant_model):
    cool = plant_model.input_vector(**RATED)
    warm = plant_model.input_vector(**{**RATED, "T_inlet": 30.0})
    assert np.all(plant_model.steady_state(warm) > plant_model.steady_state(cool))


def _full_network_steady_state(model, u):
    """Solve all 19 node equations directly (no elimination), from the sympy network."""
    net = model.network
    internal = model.state_names + model.massless_names
    idx = {n: i for i, n in enumerate(internal)}
    values = model.parameters.values()
    subs = {model.parameters[n].symbol: v for n, v in values.items()}
    boundary = {b: u[INPUT_NAMES.index(model.spec.boundary_inputs[b])] for b in model.boundary_names}
    G = np.zeros((len(internal), len(internal)))
    rhs = np.zeros(len(internal))
    for link in net.links:
        g = 1.0 / float(link.resistance.subs(subs))
        for me, other in ((link.a, link.b), (link.b, link.a)):
            if me in idx:
                G[idx[me], idx[me]] -= g
                if other in idx:
                    G[idx[me], idx[other]] += g
                else:
                    rhs[idx[me]] -= g * boundary[other]
    for stream in net.air_streams:
        g = 1.0 / float(stream.resistance.subs(subs))
        G[idx[stream.downstream], idx[stream.downstream]] -= g
        if stream.upstream in idx:
            G[idx[stream.downstream], idx[stream.upstream]] += g
        else:
            rhs[idx[stream.downstream]] -= g * boundary[stream.upstream]
    # heat sources are affine in the node temperatures: q = q0 + D theta
    inputs = {input_symbol(n): u[i] for i, n in enumerate(INPUT_NAMES)}
    for source in net.heat_sources:
        power = sympy.expand(source.power.subs(subs).subs(inputs))
        theta = net.temperature_symbol(source.node)
        G[idx[source.node], idx[source.node]] += float(power.coeff(theta, 1))
        rhs[idx[source.node]] -= float(power.coeff(theta, 0))
    return dict(zip(internal, np.linalg.solve(G, rhs)))


def test_elimination_preserves_steady_state(plant_model):
    u = plant_model.input_vector(**{**RATED, "I_u": 6.0, "I_v": 5.5, "I_w": 6.5, "T_inlet": 28.0})
    reduced = plant_model.node_temperatures(plant_model.steady_state(u), u)
    full = _full_network_steady_state(plant_model, u)
    for node, value in full.items():
        assert reduced[node] == pytest.approx(value, abs=1e-9)


def test_conductance_matrix_not_symmetric_because_of_air_streams(plant_model):
    u = plant_model.input_vector(**RATED)
    A = plant_model.jacobian_x(np.full(8, 50.0), u)
    C = np.diag([float(plant_model.network.node(n).capacitance.subs(
        {plant_model.parameters[k].symbol: v for k, v in plant_model.parameters.values().items()}))
        for n in plant_model.state_names])
    G = C @ A
    assert np.max(np.abs(G - G.T)) > 1e-3


def test_reduced_network_is_an_m_matrix(plant_model):
    """Every effective coupling between states is non-negative (thesis sign of R_r3)."""
    A = plant_model.jacobian_x(np.zeros(8), np.zeros(6))
    off = A - np.diag(np.diag(A))
    assert off.min() >= -1e-15


def test_calibration_targets_at_rated_load(plant_model):
    """Issue target: rated load, 20 °C inlet/ambient -> winding ~95-105 °C, iron clearly cooler,
    winding time constant of tens of minutes."""
    u = plant_model.input_vector(**RATED)
    x = plant_model.steady_state(u)
    winding, iron = plant_model.outputs(x, u)
    assert 95.0 <= winding <= 105.0
    assert iron < winding - 10.0
    # time to 63 % of the winding rise from cold
    dm = plant_model.discretise(10.0)
    X = np.asarray(dm.simulator(720)(np.full(8, 20.0), np.tile(u[:, None], (1, 720))))
    rise = X[plant_model.state_names.index("stator_winding")] - 20.0
    tau_min = (np.argmax(rise >= 0.632 * (winding - 20.0)) + 1) * 10.0 / 60.0
    assert 10.0 <= tau_min <= 90.0


def test_jacobians_match_finite_differences(plant_model):
    rng = np.random.default_rng(1)
    x = 40 + 40 * rng.random(8)
    u = plant_model.input_vector(5.0, 6.0, 7.0, 1.0, 22.0, 18.0)
    p = plant_model.p0
    f = lambda xx, uu, pp: np.asarray(plant_model.functions["rhs"](xx, uu, pp)).ravel()
    for name, arg, perturb in (("jac_x", 0, x), ("jac_u", 1, u), ("jac_p", 2, p)):
        J = np.asarray(plant_model.functions[name](x, u, p))
        for j in range(perturb.size):
            h = 1e-5 * (abs(perturb[j]) or 1.0)
            args_plus = [x.copy(), u.copy(), p.copy()]
            args_minus = [x.copy(), u.copy(), p.copy()]
            args_plus[arg][j] += h
            args_minus[arg][j] -= h
            column = (f(*args_plus) - f(*args_minus)) / (2 * h)
            assert np.allclose(J[:, j], column, rtol=1e-4, atol=1e-6 * max(1e-9, np.abs(column).max())), (name, j)


@pytest.mark.parametrize("dt", [1.0, 10.0, 60.0])
def test_discrete_steps_match_a_stiff_integrator(plant_model, design_model, dt):
    u = plant_model.input_vector(**RATED)
    n = int(3600 / dt)
    # exact ZOH for the linear model; ETD2RK is second order: error ~ dt^2 (2.7e-4 K at 10 s)
    for model, tolerance in ((design_model, 1e-6), (plant_model, 5e-4 * (dt / 10.0) ** 2 + 1e-5)):
        X = np.asarray(model.discretise(dt).simulator(n)(np.full(8, 20.0), np.tile(u[:, None], (1, n))))
        sol = solve_ivp(lambda t, x: model.rhs(x, u), (0, n * dt), np.full(8, 20.0), method="Radau",
                        rtol=1e-11, atol=1e-11, t_eval=np.arange(1, n + 1) * dt,
                        jac=lambda t, x: model.jacobian_x(x, u))
        assert np.max(np.abs(sol.y - X)) < tolerance


def test_linear_step_is_exact_zoh(design_model):
    dm = design_model.discretise(10.0)
    assert dm.exact
    assert design_model.discretise(10.0) is dm  # cached per step length
    assert dm.A.shape == (8, 8) and dm.B.shape == (8, 6)


def test_equal_networks_built_again_share_compiled_functions_not_values(plant_model):
    """Two models of one effect with different values: one compilation (StructureCache), their
    own parameter values (a blockage of 0.3 heats more than one of 0.8)."""
    from genthermal.model import StructureCache

    mild = plant_model.with_effect("coolant_flow_reduction", k_flow=0.8)
    severe = plant_model.with_effect("coolant_flow_reduction", k_flow=0.3)
    assert severe.network is not mild.network and severe.network == mild.network
    assert severe._shared is mild._shared
    u = plant_model.input_vector(**RATED)
    x = np.full(plant_model.n_states, 80.0)
    assert np.all(severe.rhs(x, u) >= mild.rhs(x, u)) and np.any(severe.rhs(x, u) > mild.rhs(x, u) + 1e-6)
    cache = StructureCache(size=1)
    first = cache.shared(StructureCache.key(mild.network, mild.spec, mild.parameters))
    assert cache.shared(StructureCache.key(severe.network, severe.spec, severe.parameters)) is first
    cache.shared(StructureCache.key(plant_model.network, plant_model.spec, plant_model.parameters))
    assert cache.shared(StructureCache.key(mild.network, mild.spec, mild.parameters)) is not first  # evicted
    assert (cache.hits, cache.misses) == (1, 3)
    with pytest.raises(Exception, match="structure cache size"):
        StructureCache(size=0)


def test_one_more_sensor_on_the_same_network_reuses_its_equations(plant_model, monkeypatch):
    """The outlet sensor a diagnosis fits: a new model on the same network, its equations shared
    (EQUATIONS), its own sensor outputs compiled, the other sensors reading the same."""
    import genthermal.model as model_module
    from genthermal.diagnose.sensor_view import with_outlet_sensor
    from genthermal.model import StructureCache, ThermalModel

    # fresh caches: in a whole session the least recently used of the 128 structures kept may be
    # the plant's equations (a miss here) or the view's functions (no equation lookup at all)
    monkeypatch.setattr(model_module, "STRUCTURES", StructureCache())
    monkeypatch.setattr(model_module, "EQUATIONS", StructureCache())
    plant_model = ThermalModel(plant_model.network, plant_model.parameters, plant_model.spec)
    EQUATIONS = model_module.EQUATIONS
    assert EQUATIONS.misses == 1
    hits = EQUATIONS.hits
    viewed = with_outlet_sensor(plant_model)
    assert EQUATIONS.hits == hits + 1
    assert viewed.output_names == [*plant_model.output_names, "T_outlet"]
    x = np.linspace(40.0, 90.0, plant_model.n_states)
    u = plant_model.input_vector(**{name: 100.0 for name in plant_model.input_names if name.startswith("I_")})
    y, y_viewed = (np.asarray(m.functions["outputs"](x, u, m.p0)).ravel() for m in (plant_model, viewed))
    assert np.array_equal(y_viewed[:-1], y)
    nodes = np.asarray(viewed.functions["nodes"](x, u, viewed.p0)).ravel()
    assert y_viewed[-1] == nodes[viewed.node_order.index(viewed.spec.sensors["T_outlet"])]


def test_heat_capacities_are_the_capacitance_expressions_evaluated(plant_model):
    values = {plant_model.parameters[n].symbol: plant_model.parameters.value(n) for n in plant_model.parameter_names}
    expected = [float(plant_model.network.node(n).capacitance.subs(values)) for n in plant_model.state_names]
    np.testing.assert_allclose(plant_model.heat_capacities(), expected, rtol=1e-12)


def test_to_casadi_reuses_evaluators_and_names_an_unknown_symbol():
    """Evaluators are cached per expression across models: the same expression evaluates with
    each call's own values; an expression reading a symbol given no value is refused by name."""
    import casadi as ca

    from genthermal.errors import InputError
    from genthermal.model import to_casadi

    a, b = sympy.symbols("a_test b_test")
    expression = a ** 2 / (1 + b)
    first = to_casadi([expression], [a, b], [ca.SX(3.0), ca.SX(1.0)])[0]
    second = to_casadi([expression], [b, a], [ca.SX(0.0), ca.SX(2.0)])[0]
    assert float(ca.evalf(first)) == pytest.approx(4.5) and float(ca.evalf(second)) == pytest.approx(4.0)
    with pytest.raises(InputError, match="b_test"):
        to_casadi([expression], [a], [ca.SX(1.0)])
