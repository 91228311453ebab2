"""Discovery beyond one catalogue effect: jointly fitted pairs, "something is still missing", and
the open search over generic heat flows (records at 60 s to keep the file fast; the full
leave-one-effect-out evaluation is benchmarks/bench_open_search.py)."""

import math

import numpy as np
import pytest

from genthermal.diagnose.catalogue import Catalogue
from genthermal.diagnose.discover import diagnose
from genthermal.diagnose.discovery import Discovery
from genthermal.diagnose.experiment import separating_experiment
from genthermal.diagnose.fitter import OnsetFitter
from genthermal.diagnose.hidden import Injection, make_hidden_effect_case
from genthermal.diagnose.open_search import (conductance_effect, effect_code, heat_flow_effect, heat_flow_library,
                                             node_groups)
from genthermal.diagnose.report import write_diagnosis_report
from genthermal.effects import CATALOGUE
from genthermal.errors import InputError
from genthermal.mission import load_mission
from genthermal.synth import THESIS_NOISE_VARIANCE_K2

DT_S = 60.0
SENSOR_NOISE_STD = math.sqrt(sum(THESIS_NOISE_VARIANCE_K2) / 2)
#: A blockage from 80 min on top of an end-winding stray loss present from the start: greedy search
#: fits the blockage from the start (it absorbs the stray loss's warming).
TWO_EFFECTS = [Injection("coolant_flow_reduction", {"k_flow": 0.6}, 4800.0),
               Injection("end_winding_stray_loss", {"R_stray": 0.2}, 0.0)]


@pytest.fixture(scope="module")
def discovery():
    """One Discovery for the file: the models and simulators it builds for the plant are reused."""
    return Discovery()


@pytest.fixture(scope="module")
def two_effect_case(plant_model):
    return make_hidden_effect_case(TWO_EFFECTS, mission="thesis_fig_7_7", dt_s=DT_S, seed=4, plant=plant_model)


@pytest.mark.slow
def test_pair_fitted_jointly_names_both_effects_and_onsets(plant_model, two_effect_case, discovery):
    """A blockage fitted from the start absorbs the stray loss's warming (it also lowers the internal
    convection); the joint search starts its onset descent from each effect's onset alone with the
    other present from the start, and finds both onsets. On the lumped winding a shorted turn from
    the start fits as well as the stray loss; the three phase sensors, equal here, rule it out."""
    result = discovery.fit(plant_model, two_effect_case.data)
    found = {f.effect: f.onset_s for f in result.found}
    assert set(found) == {i.effect for i in TWO_EFFECTS}, result.verdict
    for injection in TWO_EFFECTS:
        assert abs(found[injection.effect] - injection.onset_s) <= 600.0
    assert result.iterations[0].rmse_after <= 1.5 * SENSOR_NOISE_STD
    # the best single effect alone leaves several times the noise: the pair is needed
    assert result.iterations[0].ranked[0].rmse_after > 3 * SENSOR_NOISE_STD
    assert not result.unexplained and result.to_dict()["verdict"] == result.verdict


@pytest.mark.slow
def test_two_workers_fit_the_pairs_of_one_process(plant_model, two_effect_case, discovery):
    """Every stage of the pair search runs in the worker pool with two workers (the singles and
    their polish, the pair grid, one descent per starting point, the polish of the best pairs, the
    look-alike refit per phase): the rankings are those of one process, to the last digit."""
    three = Catalogue.registered().only(["coolant_flow_reduction", "end_winding_stray_loss", "phase_short_circuit"])
    results = [discovery.with_settings(candidates=three, fitter=OnsetFitter(workers=workers)).fit(
        plant_model, two_effect_case.data) for workers in (1, 2)]
    (one, two) = ([(tuple(c.effects) if hasattr(c, "effects") else c.effect, c.rss)
                   for c in [*r.iterations[0].ranked, *r.iterations[0].pairs]] for r in results)
    assert one == two and len(one) >= 5
    assert results[0].verdict == results[1].verdict


def test_a_partial_fit_says_something_is_still_missing(plant_model, two_effect_case, discovery):
    blockage_only = discovery.with_settings(candidates=Catalogue.registered().only(["coolant_flow_reduction"]))
    result = blockage_only.fit(plant_model, two_effect_case.data)
    assert result.verdict == "coolant_flow_reduction"
    document = result.to_dict()
    assert document["unexplained"] is True
    assert document["residual"]["largest"]["sensor"] == "T_winding"
    assert "Something is still missing" in document["residual"]["summary"]


def test_healthy_data_leave_nothing_unexplained(plant_model, discovery):
    case = make_hidden_effect_case(None, mission="thesis_fig_7_7", dt_s=DT_S, seed=5, plant=plant_model)
    result = discovery.fit(plant_model, case.data)
    assert result.verdict == "none" and not result.unexplained


def _steady_winding(model, **inputs):
    u = model.input_vector(**inputs)
    return model.outputs(model.steady_state(u), u)


def test_library_terms_are_the_physics_they_name(plant_model):
    """An I_u² heat flow into the slot winding is the catalogue's shorted turn; the air-stream
    conductance factor is its blockage with the internal convection held (n_flow 0); neutral values
    leave the model unchanged."""
    groups = node_groups(plant_model)
    inputs = dict(I_u=6.0, I_v=5.0, I_w=4.0, I_exc=1.5, T_inlet=25.0, T_ambient=22.0)
    short = plant_model.with_effect(heat_flow_effect("slot winding", groups["slot winding"], "I_u2"),
                                    k_heat_I_u2_slot_winding=0.3)
    np.testing.assert_allclose(_steady_winding(short, **inputs),
                               _steady_winding(plant_model.with_effect("phase_short_circuit", R_short=0.3), **inputs),
                               atol=1e-9)
    blocked = plant_model.with_effect(conductance_effect("air_streams"), k_conductance_air_streams=0.5)
    np.testing.assert_allclose(_steady_winding(blocked, **inputs),
                               _steady_winding(plant_model.with_effect("coolant_flow_reduction", k_flow=0.5, n_flow=0.0), **inputs),
                               atol=1e-9)
    library = heat_flow_library(plant_model)
    for name in ("heat_I2_theta_slot_winding", "heat_constant_frame", "conductance_frame_to_ambient"):
        effect = library[name]
        neutral = plant_model.with_effect(effect)
        np.testing.assert_allclose(_steady_winding(neutral, **inputs), _steady_winding(plant_model, **inputs),
                                   atol=1e-9, err_msg=effect.name)


def test_open_search_finds_form_and_group_and_writes_an_effect(plant_model, discovery):
    """Excitation iron loss with the catalogue out of play: the library term of the right form
    and node group wins over the other forms into the iron and the same form into the rotor."""
    case = make_hidden_effect_case([Injection("excitation_iron_loss", {"k_exc": 30.0}, 5000.0)],
                                   mission="thesis_fig_7_7", dt_s=DT_S, seed=9, plant=plant_model)
    terms = ["heat_I_exc2_stator_iron", "heat_I2_stator_iron", "heat_constant_stator_iron", "heat_I_exc2_rotor"]
    result = discovery.with_settings(candidates=Catalogue.of(heat_flow_library(plant_model)).only(terms)).fit(
        plant_model, case.data)
    assert [f.effect for f in result.found] == ["heat_I_exc2_stator_iron"]
    assert result.iterations[0].rmse_after <= 2 * SENSOR_NOISE_STD and not result.unexplained
    assert abs(result.found[0].onset_s - 5000.0) <= 600.0
    code = effect_code(result.found[0], result.catalogue, "found_iron_loss")
    namespace = {"model": plant_model}
    exec(code, namespace)
    assert "found_iron_loss" not in CATALOGUE  # the written code changes no global state
    kept = namespace["model"]
    assert "found_iron_loss" in kept.spec.effects
    assert kept.parameters["k_found_iron_loss"].value == pytest.approx(result.found[0].values["k_heat_I_exc2_stator_iron"],
                                                                      rel=1e-5)


#: Two library terms in different node groups with different onsets: an excitation-dependent heat
#: flow into the stator iron from 0.8 h and a constant heat flow into the frame from 2.3 h.
TWO_TERMS = [Injection("heat_I_exc2_stator_iron", {"k_heat_I_exc2_stator_iron": 25.0}, 0.8 * 3600),
             Injection("heat_constant_frame", {"k_heat_constant_frame": 150.0}, 2.3 * 3600)]


@pytest.mark.slow
def test_open_search_adds_a_second_term_in_another_node_group(plant_model, discovery):
    """Of the iron terms alone, ΣI² fits best (the excitation follows the load); the pair search
    picks the frame term as the partner that explains what the best single leaves, then swaps the
    iron term for the form that explains its part better: both terms, groups, forms and onsets."""
    library = heat_flow_library(plant_model)
    case = make_hidden_effect_case(TWO_TERMS, mission="thesis_fig_7_7", dt_s=DT_S, seed=5, plant=plant_model,
                                   catalogue=library)
    result = discovery.with_settings(candidates=Catalogue.of(library), design_experiment=False).fit(
        plant_model, case.data)
    found = {f.effect: f for f in result.found}
    assert set(found) == {i.effect for i in TWO_TERMS}, result.verdict
    for injection in TWO_TERMS:
        assert abs(found[injection.effect].onset_s - injection.onset_s) <= 600.0
        (name, value), = injection.values.items()
        assert found[injection.effect].values[name] == pytest.approx(value, rel=0.1)
    assert result.iterations[0].rmse_after <= 1.5 * SENSOR_NOISE_STD and not result.unexplained
    # one term alone leaves many times the noise: the second term is needed
    assert result.iterations[0].ranked[0].rmse_after > 5 * SENSOR_NOISE_STD


def test_residual_screen_prefers_the_missing_shape_over_a_look_alike():
    """The screen scores what a candidate adds beyond the chosen effect's own shape."""
    from genthermal.diagnose.joint import screen
    from genthermal.diagnose.search import Candidate, OnsetResponses

    time = np.linspace(0.0, 1.0, 50)
    chosen_shape, missing_shape = np.vstack([time, time]), np.vstack([np.sin(6 * time), 0 * time])

    def candidate(name, shape):
        return Candidate(name, {}, 0.0, 0, 1.0, 1, 1.0, 1.0, 0.0, {}, np.zeros((2, 50)),
                         onset_responses=OnsetResponses(np.array([0]), shape[None]))

    other_shape = np.vstack([0 * time, np.cos(3 * time)])
    look_alike, missing = candidate("look_alike", chosen_shape + 0.01 * other_shape), candidate("missing", missing_shape)
    residual = 2.0 * chosen_shape + missing_shape  # what a refit of the chosen effect takes, and what it cannot
    assert [c.effect for c in screen(residual, [look_alike, missing], [chosen_shape])] == ["missing", "look_alike"]
    assert [c.effect for c in screen(residual, [look_alike, missing])][0] == "look_alike"


@pytest.mark.parametrize("call, field", [
    (lambda model: heat_flow_effect("rotor", ("rotor",), "I_cubed"), "form"),
    (lambda model: conductance_effect("shaft_bearing"), "conductance"),
    (lambda model: diagnose(model, None, effects=["no_such_effect"]), "effects"),
    (lambda model: OnsetFitter(pair_starts=(("coolant_flow_reduction", -60.0, "end_winding_stray_loss", 0.0),)),
     "pair_starts"),
    (lambda model: make_hidden_effect_case([Injection("heat_I2_rotor", {}, 0.0)], catalogue={}), "effect"),
])
def test_bad_inputs_name_the_field(call, field, plant_model):
    with pytest.raises(InputError) as error:
        call(plant_model)
    assert field in str(error.value)


def test_look_alike_diagnosis_designs_a_test_that_separates_them(plant_model, discovery, tmp_path):
    """A shorted turn present from the start under balanced load looks like end-winding stray loss
    (one that begins during the run cannot be a stray loss, a design property); the designed test
    (≤ 30 min, within the ratings) separates the two explanations by ≥ 5 noise σ even with their
    parameters refitted, is a scenario file the rig can run, and run on the plant it names the
    shorted turn."""
    case = make_hidden_effect_case([Injection("phase_short_circuit", {"R_short": 0.3}, 0.0)],
                                   mission="thesis_fig_7_7", dt_s=DT_S, seed=12, plant=plant_model)
    # the three phase sensors of this record read one plant node: trusted as phase sensors they would
    # be evidence against a shorted turn (see tests/test_phase_winding.py), so the winding is kept lumped
    look_alikes = discovery.with_settings(candidates=["phase_short_circuit", "end_winding_stray_loss"],
                                          phases="lumped")
    result = look_alikes.fit(plant_model, case.data)
    experiment = result.experiment
    assert experiment is not None and set(experiment.candidates) == {"phase_short_circuit", "end_winding_stray_loss"}
    assert experiment.separation_sigma >= 5.0 and experiment.mission.duration_s <= 1800.0
    assert experiment.peak_winding_C <= 110.0
    path = experiment.write(tmp_path / "separate.yaml")
    inputs = load_mission(path).to_inputs(10.0)
    assert inputs[["I_u", "I_v", "I_w"]].to_numpy().max() <= plant_model.spec.rated_current_A + 1e-9
    # the record itself could not separate them: the designed test can
    ranked = result.iterations[0].ranked
    assert abs(ranked[0].rmse_after - ranked[1].rmse_after) <= 0.02 * ranked[0].rmse_after
    # run the designed test on the plant (the shorted turn, not a fitted model): it now tells them apart
    rig = make_hidden_effect_case([Injection("phase_short_circuit", {"R_short": 0.3}, 0.0)], mission=str(path),
                                  dt_s=10.0, seed=13, plant=plant_model)
    retest = look_alikes.fit(plant_model, rig.data)
    winner, other = retest.iterations[0].ranked[:2]
    assert retest.verdict == "phase_short_circuit" and other.rmse_after >= 3 * winner.rmse_after
    report = write_diagnosis_report(result, tmp_path / "report")
    assert (tmp_path / "report" / "separating_test.yaml").is_file()
    assert "tells the look-alikes apart" in report.read_text()
    with pytest.raises(InputError, match="noise_K"):
        separating_experiment(plant_model, {"phase_short_circuit": {"R_short": 0.3}},
                              {"end_winding_stray_loss": {"R_stray": 0.1}}, 0.0)
