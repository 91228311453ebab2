"""Phase-resolved winding: one slot-winding node per phase, equal to the single node under
balanced load, and what lets a diagnosis tell a shorted turn from an end-winding stray loss."""

import dataclasses

import numpy as np
import pytest

from genthermal.diagnose.discovery import Discovery
from genthermal.diagnose.hidden import Injection, make_hidden_effect_case
from genthermal.diagnose.phase_winding import phase_resolved, phase_sensor, phases_differ
from genthermal.errors import InputError
from genthermal.mission import load_mission
from genthermal.simulate import simulate

DT_S = 60.0
PHASE_SENSORS = ("T_winding_u", "T_winding_v", "T_winding_w")


@pytest.fixture(scope="module")
def resolved(plant_model):
    return phase_resolved(plant_model)


def test_equal_to_the_single_node_model_under_balanced_load(plant_model, resolved):
    inputs = load_mission("thesis_fig_7_7").to_inputs(DT_S)
    inputs[["I_v", "I_w"]] = inputs[["I_u", "I_u"]].to_numpy()  # balanced phases
    lumped, split = simulate(plant_model, inputs), simulate(resolved, inputs)
    for sensor in PHASE_SENSORS:
        np.testing.assert_allclose(split[sensor], lumped["T_winding"], atol=1e-9)
    np.testing.assert_allclose(split["T_iron"], lumped["T_iron"], atol=1e-9)
    assert resolved.n_states == plant_model.n_states + 2
    assert list(resolved.output_names) == [*PHASE_SENSORS, "T_iron"]


def test_the_phase_with_more_current_runs_hotter_and_the_losses_add_up(plant_model, resolved):
    u = plant_model.input_vector(I_u=7.0, I_v=5.0, I_w=5.0, I_exc=1.5, T_inlet=25.0, T_ambient=22.0)
    t_u, t_v, t_w, t_iron = resolved.outputs(resolved.steady_state(u), u)
    assert t_u > t_v + 0.05 and t_v == pytest.approx(t_w, abs=1e-9)
    lumped = plant_model.outputs(plant_model.steady_state(u), u)
    # unbalance moves heat between phases; the mean winding and the iron stay within 0.1 K of the lumped model
    assert np.mean([t_u, t_v, t_w]) == pytest.approx(lumped[0], abs=0.1)
    assert t_iron == pytest.approx(lumped[1], abs=0.1)


def test_a_shorted_turn_heats_its_own_phase(plant_model):
    u = plant_model.input_vector(I_u=6.0, I_v=6.0, I_w=6.0, I_exc=1.5, T_inlet=25.0, T_ambient=22.0)
    shorted = phase_resolved(plant_model.with_effect("phase_short_circuit", R_short=0.5))
    t_u, t_v, t_w, _ = shorted.outputs(shorted.steady_state(u), u)
    assert t_u - t_v > 0.2 and t_v == pytest.approx(t_w, abs=1e-9)


def test_a_model_without_a_slot_winding_is_refused_by_name(plant_model):
    assert phase_sensor(plant_model).columns == PHASE_SENSORS
    interface = dataclasses.replace(plant_model.spec.interface, roles={})
    without_roles = plant_model.with_network(plant_model.network, interface=interface)
    assert phase_sensor(without_roles) is None
    with pytest.raises(InputError, match="slot_winding"):
        phase_resolved(without_roles)
    with pytest.raises(InputError, match="phases"):
        Discovery(phases="per-phase")


def test_shorted_turn_under_nearly_balanced_load_is_told_from_end_winding_stray_loss(plant_model):
    """With one node per winding the phase sensors show the shorted phase running hot; the lumped
    model sees the same I^2 heating as an end-winding loss and cannot tell them apart (a short
    present from the start: one that begins during the run is no stray loss, a design property)."""
    case = make_hidden_effect_case([Injection("phase_short_circuit", {"R_short": 0.3}, 0.0)],
                                   mission="thesis_fig_7_7", dt_s=DT_S, seed=12, plant=plant_model,
                                   phase_resolved=True, unbalance=0.05)
    assert phases_differ(case.data, DT_S, PHASE_SENSORS)
    look_alikes = Discovery(["phase_short_circuit", "end_winding_stray_loss"], design_experiment=False)
    resolved_fit = look_alikes.fit(plant_model, case.data)
    assert resolved_fit.output_names == [*PHASE_SENSORS, "T_iron", "T_outlet"]
    winner, other = resolved_fit.ranking
    assert resolved_fit.verdict == "phase_short_circuit"
    assert resolved_fit.found[0].onset_s <= 600.0
    assert winner.values["R_short"] == pytest.approx(0.3, rel=0.1)
    assert other.rmse_after >= 1.05 * winner.rmse_after and other.delta_bic - winner.delta_bic > 100
    lumped_fit = look_alikes.with_settings(phases="lumped").fit(plant_model, case.data)
    assert lumped_fit.output_names == ["T_winding", "T_iron", "T_outlet"]
    first, second = lumped_fit.ranking
    assert second.rmse_after <= 1.02 * first.rmse_after  # look-alikes on the mean winding temperature


def test_balanced_records_stay_lumped(plant_model):
    case = make_hidden_effect_case([Injection("end_winding_stray_loss", {"R_stray": 0.2}, 3000.0)],
                                   mission="thesis_fig_7_7", dt_s=DT_S, seed=14, plant=plant_model,
                                   phase_resolved=True)
    assert not phases_differ(case.data, DT_S, PHASE_SENSORS)
