"""Blockage physics: the outlet orifice relation and the flow-dependent internal convection."""

import numpy as np
import pytest

from genthermal.coolant import OUTLET_DIAMETER_MM, OUTLET_LOSS_SHARE, inlet_rise, outlet_flow_fraction
from genthermal.errors import InputError
from genthermal.mission import Mission
from genthermal.schedule.power_system import PowerSystem

U_RATED = dict(I_u=7.0, I_v=7.0, I_w=7.0, I_exc=1.0, T_inlet=20.0, T_ambient=20.0)


def test_open_outlet_passes_the_full_flow_and_a_smaller_one_less():
    diameters = np.linspace(7.0, OUTLET_DIAMETER_MM, 40)
    fractions = [outlet_flow_fraction(d) for d in diameters]
    assert fractions[-1] == pytest.approx(1.0, abs=1e-15)
    assert np.all(np.diff(fractions) > 0)


def test_small_orifice_flow_scales_with_its_area():
    # when the orifice dominates the circuit, Q ∝ C_d A ∝ d²: halving d quarters the flow
    small = outlet_flow_fraction(2.0, loss_share=OUTLET_LOSS_SHARE)
    assert outlet_flow_fraction(1.0) / small == pytest.approx(0.25, rel=1e-3)


def test_orifice_relation_is_the_series_resistance_operating_point():
    # Q ∝ 1/sqrt(R_total) with R_out ∝ d^-4: check against the resistances directly
    beta, d = 0.3, 17.0
    r_rest, r_out0 = 1.0, beta
    expected = np.sqrt((r_rest + r_out0) / (r_rest + r_out0 * (50.0 / d) ** 4))
    assert outlet_flow_fraction(d, 50.0, beta) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("kwargs, field", [
    (dict(diameter_mm=0.0), "outlet_diameter_mm"), (dict(diameter_mm=60.0), "outlet_diameter_mm"),
    (dict(diameter_mm=float("nan")), "outlet_diameter_mm"), (dict(diameter_mm=10.0, loss_share=-1.0), "loss_share"),
    (dict(diameter_mm=10.0, healthy_diameter_mm=0.0), "healthy_diameter_mm"),
])
def test_bad_orifice_inputs_name_the_field(kwargs, field):
    with pytest.raises(InputError) as error:
        outlet_flow_fraction(**kwargs)
    assert error.value.field == field


def _steady(model):
    u = model.input_vector(**U_RATED)
    return model.outputs(model.steady_state(u), u)


def test_full_flow_is_the_healthy_model_exactly_whatever_the_exponent(plant_model):
    healthy = _steady(plant_model)
    for n in (0.0, 0.5, 0.8, 1.5):
        blocked = plant_model.with_effect("coolant_flow_reduction", k_flow=1.0, n_flow=n)
        assert np.array_equal(_steady(blocked), healthy)


def test_internal_convection_scales_as_flow_to_the_n(plant_model):
    k, n = 0.4, 0.8
    blocked = plant_model.with_effect("coolant_flow_reduction", k_flow=k, n_flow=n)
    # the same model written by hand: air streams x k, every internal h x k^n
    by_hand = plant_model.with_effect("coolant_flow_reduction", k_flow=k, n_flow=0.0).with_parameters(
        "assumed", "test", **{h: plant_model.parameters.value(h) * k ** n
                              for h in ("h_top_air", "h_end_air", "h_air_gap")})
    assert np.allclose(_steady(blocked), _steady(by_hand), rtol=0, atol=1e-9)
    # less convection, hotter machine; a larger exponent, hotter still
    hotter = plant_model.with_effect("coolant_flow_reduction", k_flow=k, n_flow=1.2)
    assert np.all(_steady(hotter) > _steady(blocked)) and np.all(_steady(blocked) > _steady(by_hand.with_parameters(
        "assumed", "test", **{h: plant_model.parameters.value(h) for h in ("h_top_air", "h_end_air", "h_air_gap")})))


def test_flow_exponent_outside_its_range_is_refused(plant_model):
    with pytest.raises(InputError, match="n_flow"):
        plant_model.with_effect("coolant_flow_reduction", k_flow=0.5, n_flow=3.0)


def test_flow_exponent_survives_a_model_file(plant_model, tmp_path):
    from genthermal.model_file import load_model, save_model

    blocked = plant_model.with_effect("coolant_flow_reduction", k_flow=0.3, n_flow=0.55)
    loaded = load_model(save_model(blocked, tmp_path / "blocked.yaml"))
    assert loaded.parameters.value("n_flow") == 0.55 and loaded.parameters.value("k_flow") == 0.3


def test_inlet_rise_is_a_step_or_a_first_order_approach():
    t = np.array([0.0, 599.0, 600.0, 600.0 + 1200.0, 1e6])
    assert inlet_rise(t, 600.0, 31.0).tolist() == [0.0, 0.0, 31.0, 31.0, 31.0]
    gradual = inlet_rise(t, 600.0, 31.0, 1200.0)
    assert gradual[:3].tolist() == [0.0, 0.0, 0.0]
    assert gradual[3] == pytest.approx(31.0 * (1 - np.exp(-1.0))) and gradual[4] == pytest.approx(31.0)
    with pytest.raises(InputError, match="inlet_rise_tau"):
        inlet_rise(t, 600.0, 31.0, -1.0)
    # a scenario's fault carries it to every consumer of the inlet temperature
    document = {"name": "x", "generators": {"count": 2}, "actions": [{"condition": 5, "duration_min": 60}],
                "faults": [{"generator": 1, "kind": "inlet_rise", "onset_min": 10, "inlet_rise_C": 10,
                            "inlet_rise_tau_min": 20}]}
    system = PowerSystem.from_mission(Mission.from_dict(document))
    assert system.inlet_C(0, 1800.0) == pytest.approx(20.0 + 10.0 * (1 - np.exp(-1.0)))
    assert system.inlet_C(1, 1800.0) == pytest.approx(20.0)
    document["faults"][0]["inlet_rise_tau_min"] = -5
    with pytest.raises(InputError, match="inlet_rise_tau_min"):
        PowerSystem.from_mission(Mission.from_dict(document))
