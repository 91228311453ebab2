"""The open library's conductance-change and temperature-dependent-loss terms: each is the physics
it names, and each is found on a short record (4 h at 60 s) with its node group, form and value
(the leave-one-effect-out evaluation is benchmarks/bench_open_search.py)."""

import math
import re

import numpy as np
import pytest

from genthermal.diagnose.catalogue import Catalogue
from genthermal.diagnose.discover import misfit_of
from genthermal.diagnose.discovery import Discovery
from genthermal.diagnose.hidden import Injection, make_hidden_effect_case
from genthermal.diagnose.loss_terms import loss_nodes, loss_reform_effect, loss_temperature_effect
from genthermal.diagnose.open_search import conductance_effect, describe_term, effect_code, heat_flow_library
from genthermal.diagnose.search import FoundEffect
from genthermal.effects import CATALOGUE
from genthermal.errors import InputError
from genthermal.synth import THESIS_NOISE_VARIANCE_K2

DT_S = 60.0
SENSOR_NOISE_STD = math.sqrt(sum(THESIS_NOISE_VARIANCE_K2) / 2)
INPUTS = dict(I_u=6.0, I_v=5.0, I_w=4.0, I_exc=1.5, T_inlet=25.0, T_ambient=22.0)


@pytest.fixture(scope="module")
def discovery():
    """One Discovery for the file: the models and simulators it builds are reused."""
    return Discovery(design_experiment=False)


def _steady_outputs(model, **inputs):
    u = model.input_vector(**inputs)
    return model.outputs(model.steady_state(u), u)


def test_a_blockage_is_the_air_stream_term_with_the_convection_term(plant_model):
    """Coolant flow x k with convection following as k^0.8 (the catalogue's blockage) is the air-stream
    conductance x k together with the internal-convection conductance x k^0.8; neutral is unchanged."""
    k = 0.4
    both = (plant_model.with_effect(conductance_effect("air_streams"), k_conductance_air_streams=k)
            .with_effect(conductance_effect("internal_convection"), k_conductance_internal_convection=k ** 0.8))
    np.testing.assert_allclose(_steady_outputs(both, **INPUTS),
                               _steady_outputs(plant_model.with_effect("coolant_flow_reduction", k_flow=k), **INPUTS),
                               atol=1e-9)
    convection = plant_model.with_effect(conductance_effect("internal_convection"), k_conductance_internal_convection=0.5)
    assert _steady_outputs(convection, **INPUTS)[0] > _steady_outputs(plant_model, **INPUTS)[0] + 1.0
    np.testing.assert_allclose(_steady_outputs(plant_model.with_effect(conductance_effect("internal_convection")),
                                               **INPUTS), _steady_outputs(plant_model, **INPUTS), atol=1e-9)


def test_temperature_dependent_copper_loss_is_the_resistance_rising_with_temperature(design_model, plant_model):
    """On the linear design model (copper loss held at theta_ref = 90 °C) the copper loss x k (theta - 90 °C)
    is the catalogue's resistance rising with temperature at alpha_R = k; on the nonlinear plant it
    is referred to 20 °C."""
    loss = loss_temperature_effect("copper")
    np.testing.assert_allclose(
        _steady_outputs(design_model.with_effect(loss, k_loss_theta_copper=0.005), **INPUTS),
        _steady_outputs(design_model.with_effect("copper_resistance_temperature", alpha_R=0.005), **INPUTS),
        atol=1e-9)
    assert set(loss_nodes(plant_model, "copper")) == {"stator_winding", "end_winding_in", "end_winding_out"}
    hotter = plant_model.with_effect(loss, k_loss_theta_copper=0.004)
    assert _steady_outputs(hotter, **INPUTS)[0] > _steady_outputs(plant_model, **INPUTS)[0] + 1.0


def test_a_linearised_copper_loss_undone_is_the_copper_loss_re_formed_on_I2(design_model):
    """The design model's copper loss R (a I + b) replaced by R I² (the catalogue's quadratic copper
    loss at weight w) is the copper loss re-formed with k_P = -w and k_I2 = w R, ΣI² shared as the
    copper loss is (by copper mass); neutral values change nothing."""
    weight = 0.9
    resistance = design_model.parameters["R0"].value * (
        1 + design_model.parameters["alpha_cu"].value * design_model.parameters["theta_ref"].value)
    reform = loss_reform_effect("copper")
    np.testing.assert_allclose(
        _steady_outputs(design_model.with_effect(reform, k_loss_I2_copper_P=-weight,
                                                 k_loss_I2_copper_I2=weight * resistance), **INPUTS),
        _steady_outputs(design_model.with_effect("quadratic_copper_loss", lambda_I2=weight), **INPUTS), atol=1e-9)
    np.testing.assert_allclose(_steady_outputs(design_model.with_effect(reform), **INPUTS),
                               _steady_outputs(design_model, **INPUTS), atol=1e-9)


def test_one_surface_convection_terms_together_are_the_whole_convection_term(plant_model):
    """The three one-surface convection factors at k are the internal-convection factor at k; one of
    them alone changes the outputs less, and its code rebuilds it."""
    library = heat_flow_library(plant_model)
    surfaces = [n for n in library if n.startswith("conductance_internal_convection_")]
    assert len(surfaces) == 3
    k, each = 0.6, plant_model
    for name in surfaces:
        each = each.with_effect(library[name], **{f"k_{name}": k})
    whole = plant_model.with_effect(library["conductance_internal_convection"], k_conductance_internal_convection=k)
    np.testing.assert_allclose(_steady_outputs(each, **INPUTS), _steady_outputs(whole, **INPUTS), atol=1e-9)
    top = plant_model.with_effect(library["conductance_internal_convection_h_top_air"],
                                  k_conductance_internal_convection_h_top_air=k)
    rise = _steady_outputs(top, **INPUTS)[0] - _steady_outputs(plant_model, **INPUTS)[0]
    assert 0 < rise < _steady_outputs(whole, **INPUTS)[0] - _steady_outputs(plant_model, **INPUTS)[0]
    found = FoundEffect("conductance_internal_convection_h_top_air",
                        {"k_conductance_internal_convection_h_top_air": k}, 3600.0, 60)
    assert "h_top_air multiplied by about 0.60 from 1.00 h" in describe_term(found, library)
    namespace = {"model": plant_model}
    exec(effect_code(found, library, "top_convection"), namespace)
    np.testing.assert_allclose(_steady_outputs(namespace["model"], **INPUTS), _steady_outputs(top, **INPUTS), atol=1e-9)
    with pytest.raises(InputError, match="coefficients"):
        conductance_effect("air_streams", coefficients=("h_top_air",))


def test_a_term_beginning_with_the_nearest_effect_must_act_where_it_acts(plant_model):
    """On top of a blockage, a term of the convection is its misfit, the insulation is not; on top
    of a short, a heat flow into the slot winding is."""
    library = heat_flow_library(plant_model)
    blockage, short = CATALOGUE["coolant_flow_reduction"], CATALOGUE["phase_short_circuit"]
    assert misfit_of(library["conductance_internal_convection_h_top_air"], blockage)
    assert misfit_of(library["conductance_air_streams"], blockage)
    assert not misfit_of(library["conductance_winding_insulation"], blockage)
    assert not misfit_of(library["heat_constant_stator_iron"], blockage)
    assert misfit_of(library["heat_I_w2_slot_winding"], short) and misfit_of(library["heat_I2_slot_winding"], short)
    assert not misfit_of(library["heat_constant_frame"], short)


def test_library_has_the_new_terms_and_refuses_unknown_ones(plant_model, design_model):
    for model in (plant_model, design_model):
        library = heat_flow_library(model)
        assert {"conductance_internal_convection", "loss_theta_copper", "loss_I2_copper"} <= set(library)
    for build in (loss_temperature_effect, loss_reform_effect):
        with pytest.raises(InputError, match="loss"):
            build("friction")
    with pytest.raises(InputError, match="conductance"):
        conductance_effect("rotor_to_shaft")


def test_open_search_finds_a_temperature_dependent_copper_loss(design_model, discovery):
    """Copper loss rising by 0.5 %/K from the start on the linear design model: of the terms that
    grow with the winding temperature or its current, the temperature-dependent copper loss wins,
    with its value."""
    library = heat_flow_library(design_model)
    case = make_hidden_effect_case([Injection("loss_theta_copper", {"k_loss_theta_copper": 0.005}, 0.0)],
                                   mission="thesis_fig_7_7", dt_s=DT_S, seed=21, plant=design_model, catalogue=library)
    terms = ["loss_theta_copper", "heat_I2_theta_slot_winding", "heat_I2_slot_winding", "heat_I2_end_windings",
             "heat_constant_slot_winding"]
    result = discovery.with_settings(candidates=Catalogue.of(library).only(terms)).fit(design_model, case.data)
    assert [f.effect for f in result.found] == ["loss_theta_copper"], result.verdict
    (found,) = result.found
    assert found.values["k_loss_theta_copper"] == pytest.approx(0.005, rel=0.1)
    assert found.onset_index == 0
    assert result.iterations[0].rmse_after <= 2 * SENSOR_NOISE_STD and not result.unexplained
    assert describe_term(found, result.catalogue).startswith("the copper loss of the windings rising by about 0.5")
    namespace = {"model": design_model}
    exec(effect_code(found, result.catalogue, "copper_warming"), namespace)
    assert "copper_warming" not in CATALOGUE
    assert namespace["model"].parameters["k_copper_warming"].value == pytest.approx(
        found.values["k_loss_theta_copper"], rel=1e-5)


def test_open_search_finds_a_fall_of_the_internal_convection(plant_model, discovery):
    """Internal convection halved from 1.5 h: the term, its value and onset, against the air-stream
    and insulation conductances and a constant heat flow into the winding."""
    library = heat_flow_library(plant_model)
    case = make_hidden_effect_case(
        [Injection("conductance_internal_convection", {"k_conductance_internal_convection": 0.5}, 5400.0)],
        mission="thesis_fig_7_7", dt_s=DT_S, seed=22, plant=plant_model, catalogue=library)
    terms = ["conductance_internal_convection", "conductance_air_streams", "conductance_winding_insulation",
             "heat_constant_slot_winding"]
    result = discovery.with_settings(candidates=Catalogue.of(library).only(terms)).fit(plant_model, case.data)
    assert [f.effect for f in result.found] == ["conductance_internal_convection"], result.verdict
    (found,) = result.found
    assert found.values["k_conductance_internal_convection"] == pytest.approx(0.5, rel=0.1)
    assert abs(found.onset_s - 5400.0) <= 600.0
    assert result.iterations[0].rmse_after <= 2 * SENSOR_NOISE_STD and not result.unexplained
    assert describe_term(found, result.catalogue) == (
        f"the internal convection to the cooling air multiplied by about "
        f"{found.values['k_conductance_internal_convection']:.2f} from {found.onset_s / 3600:.2f} h")


def test_open_search_finds_a_copper_loss_in_I2_instead_of_its_line(design_model, discovery):
    """The linear design model's copper loss replaced (90 %) by R I²: the re-formed copper loss wins
    over ΣI² and constant flows into the windings, with both values, from the start."""
    library = heat_flow_library(design_model)
    truth = {"k_loss_I2_copper_P": -0.9, "k_loss_I2_copper_I2": 1.45}
    case = make_hidden_effect_case([Injection("loss_I2_copper", truth, 0.0)], mission="thesis_fig_7_7", dt_s=DT_S,
                                   seed=23, plant=design_model, catalogue=library)
    terms = ["loss_I2_copper", "heat_I2_slot_winding", "heat_I2_end_windings", "heat_constant_slot_winding",
             "loss_theta_copper"]
    result = discovery.with_settings(candidates=Catalogue.of(library).only(terms)).fit(design_model, case.data)
    assert [f.effect for f in result.found] == ["loss_I2_copper"], result.verdict
    (found,) = result.found
    for name, value in truth.items():
        assert found.values[name] == pytest.approx(value, rel=0.1), name
    assert found.onset_index == 0
    assert result.iterations[0].rmse_after <= 2 * SENSOR_NOISE_STD and not result.unexplained
    assert re.fullmatch(r"the copper loss of the windings about 1\d % of the model's plus 1\.[34]\d W/A² × ΣI² "
                        r"\(shared as the copper loss\) from the start", describe_term(found, result.catalogue))
    namespace = {"model": design_model}
    exec(effect_code(found, result.catalogue, "copper_in_I2"), namespace)
    kept = namespace["model"].parameters
    assert kept["k_copper_in_I2_P"].value == pytest.approx(found.values["k_loss_I2_copper_P"], rel=1e-5)
    assert kept["k_copper_in_I2_I2"].value == pytest.approx(found.values["k_loss_I2_copper_I2"], rel=1e-5)


@pytest.mark.slow
@pytest.mark.parametrize("model_fixture", ["plant_model", "design_model"])
def test_open_search_on_a_healthy_record_finds_no_term(model_fixture, request, discovery):
    """With the new terms in the library, a healthy record still gives "none" and nothing unexplained."""
    model = request.getfixturevalue(model_fixture)
    case = make_hidden_effect_case(None, mission="thesis_fig_7_7", dt_s=DT_S, seed=24, plant=model)
    result = discovery.with_settings(candidates=Catalogue.of(heat_flow_library(model))).fit(model, case.data)
    assert result.verdict == "none" and result.found == [] and not result.unexplained
