"""The effect catalogue: each effect is a small transformation that every consumer can use."""

import numpy as np
import pytest

from genthermal.effects import CATALOGUE, Effect, EffectParameter, get_effect, register_effect
from genthermal.errors import InputError
from genthermal.losses import input_symbol
from genthermal.mission import load_mission
from genthermal.network import HeatSource
from genthermal.simulate import simulate

U_HOT = dict(I_u=6.0, I_v=6.0, I_w=6.0, I_exc=1.2, T_inlet=20.0, T_ambient=20.0)

# direction of (T_winding, T_iron) change at the effect's typical value: +1 hotter, -1 cooler
DIRECTIONS = {
    "coolant_flow_reduction": (1, 1), "phase_short_circuit": (1, 1), "excitation_iron_loss": (1, 1),
    "winding_insulation_degradation": (1, -1), "end_winding_stray_loss": (1, 1),
    "frame_cooling_change": (-1, -1), "copper_resistance_temperature": (-1, -1),
    "quadratic_copper_loss": (1, 1),  # at 6 A the line a I + b lies just below I^2
}


def _applicable(model):
    return [name for name, effect in CATALOGUE.items() if effect.unavailable_reason(model) is None]


def _sensors(model, u):
    return model.outputs(model.steady_state(u), u)


def test_catalogue_has_the_required_effects():
    assert set(DIRECTIONS) <= set(CATALOGUE)
    for effect in CATALOGUE.values():
        assert 1 <= len(effect.parameters) <= 2 and effect.latex and effect.signature


@pytest.mark.parametrize("variant", ["plant_model", "design_model"])
def test_neutral_effects_change_nothing_and_typical_ones_act_as_documented(variant, request):
    model = request.getfixturevalue(variant)
    u = model.input_vector(**U_HOT)
    base = _sensors(model, u)
    names = _applicable(model)
    assert len(names) >= 6
    for name in names:
        effect = get_effect(name)
        assert np.max(np.abs(_sensors(model.with_effect(name), u) - base)) < 1e-9, name
        typical = {p.name: p.typical for p in effect.parameters}
        change = _sensors(model.with_effect(name, **typical), u) - base
        assert np.all(np.sign(change) == DIRECTIONS[name]) and np.max(np.abs(change)) > 0.1, (name, change)


def test_design_model_plus_two_effects_is_exactly_the_nonlinear_model(plant_model, design_model):
    """Quadratic loss and resistance-temperature effects restore the simulation model (thesis 5.2)."""
    alpha = plant_model.parameters.value("alpha_cu")
    theta_ref = design_model.parameters.value("theta_ref")
    restored = (design_model.with_effect("quadratic_copper_loss", lambda_I2=1.0)
                .with_effect("copper_resistance_temperature", alpha_R=alpha / (1 + alpha * theta_ref)))
    for current in (2.0, 5.0, 7.0):
        u = plant_model.input_vector(current, current + 0.4, current - 0.3, 1.0, 25.0, 18.0)
        assert np.allclose(_sensors(restored, u), _sensors(plant_model, u), atol=1e-9)


def test_effect_parameters_are_model_parameters_with_exact_derivatives(plant_model):
    model = plant_model.with_effect("coolant_flow_reduction", k_flow=0.6)
    assert model.parameters["k_flow"].value == 0.6 and model.spec.effects == ("coolant_flow_reduction",)
    column = model.parameter_names.index("k_flow")
    J = np.asarray(model.functions["jac_p"](np.full(8, 60.0), model.input_vector(**U_HOT), model.p0))
    assert np.all(J[:, column] <= 0) and np.any(J[:, column] < 0)  # more flow cools every node


@pytest.mark.parametrize("call, named", [
    (lambda m: m.with_effect("coolant_flow_reductio"), "did you mean coolant_flow_reduction"),
    (lambda m: m.with_effect("coolant_flow_reduction", k=0.5), "k_flow"),
    (lambda m: m.with_effect("coolant_flow_reduction", k_flow=-1.0), "k_flow"),
    (lambda m: m.with_effect("coolant_flow_reduction").with_effect("coolant_flow_reduction"), "already applied"),
    (lambda m: m.with_effect("quadratic_copper_loss"), "I2_slope"),
])
def test_bad_effect_requests_are_refused_clearly(plant_model, call, named):
    with pytest.raises(InputError, match=named):
        call(plant_model)


def test_a_user_effect_in_a_few_lines(plant_model, monkeypatch):
    """Registered by name into a private copy of the registry (the package's is never touched),
    and usable without registering through a candidate Catalogue."""
    from genthermal import effects
    from genthermal.diagnose.catalogue import Catalogue

    monkeypatch.setattr(effects, "CATALOGUE", dict(CATALOGUE))

    def rotor_loss(network, roles, k):
        return network.with_heat_sources([HeatSource("rotor", k * input_symbol("I_exc") ** 2, "rotor")])

    effect = Effect("test_rotor_copper_loss", "rotor field loss k I_exc^2", r"q_r = k I_{exc}^2",
                    (EffectParameter("k_rotor", 0.0, "W/A^2", 0.0, 100.0, 20.0),), rotor_loss)
    register_effect(effect)
    u = plant_model.input_vector(**U_HOT)
    x_base = plant_model.steady_state(u)
    model = plant_model.with_effect("test_rotor_copper_loss", k_rotor=30.0)
    x = model.steady_state(u)
    rotor = model.state_names.index("rotor")
    assert x[rotor] - x_base[rotor] > 2.0
    with pytest.raises(InputError, match="already registered"):
        register_effect(effect)
    base = Catalogue(CATALOGUE.values())
    extended = base.extended(effect)
    assert "test_rotor_copper_loss" in extended and "test_rotor_copper_loss" not in base
    assert list(extended.without("test_rotor_copper_loss")) == list(base)
    with pytest.raises(InputError, match="two candidate effects"):
        extended.extended(effect)


def test_effect_with_onset_switches_the_model_mid_run(plant_model):
    inputs = load_mission("thesis_fig_7_7").to_inputs(10.0)
    blocked = plant_model.with_effect("coolant_flow_reduction", k_flow=0.3)
    onset = 66 * 60.0
    healthy = simulate(plant_model, inputs)
    faulty = simulate(plant_model, inputs, switches=[(onset, blocked)])
    before = faulty["time_s"] < onset
    assert np.array_equal(faulty[before].to_numpy(), healthy[before].to_numpy())
    assert faulty["T_winding"].max() > healthy["T_winding"].max() + 5.0
    # the state is continuous across the switch: no jump larger than a normal step
    assert np.max(np.abs(np.diff(faulty["T_winding"]))) < 1.0


def test_switch_to_a_model_with_other_states_is_refused(plant_model):
    from genthermal.model import ThermalModel

    class Other:
        state_names = ["a"]
        name = "other"

    inputs = load_mission("step_rated").to_inputs(60.0)
    with pytest.raises(InputError, match="same states"):
        simulate(plant_model, inputs, switches=[(600.0, Other())])
    assert ThermalModel  # the real class is what simulate expects
