"""A model file with an effect and its onset reproduces the switched model (simulate, compare)."""

import numpy as np
import pytest

from genthermal.errors import InputError
from genthermal.mission import load_mission
from genthermal.model_file import load_model, save_model
from genthermal.simulate import simulate

ONSET_S = 3960.0


@pytest.fixture(scope="module")
def inputs():
    return load_mission("thesis_fig_7_7").to_inputs(10.0)


def test_saved_onset_is_loaded_and_switches_the_effect_on(plant_model, inputs, tmp_path):
    blocked = plant_model.with_effect("coolant_flow_reduction", k_flow=0.3)
    path = save_model(blocked, tmp_path / "blocked.yaml", {"coolant_flow_reduction": ONSET_S})
    loaded = load_model(path)
    assert loaded.spec.onsets == (("coolant_flow_reduction", ONSET_S),)
    expected = simulate(plant_model, inputs, switches=[(ONSET_S, blocked)])
    result = simulate(loaded, inputs)
    assert np.max(np.abs(result["T_winding"] - expected["T_winding"])) < 1e-9
    # and not the effect from the start, which runs much hotter before the onset
    always = simulate(blocked, inputs)
    before = inputs["time_s"] < ONSET_S
    assert np.max(np.abs(always["T_winding"][before] - result["T_winding"][before])) > 5.0
    # saving the loaded model keeps the onset
    assert load_model(save_model(loaded, tmp_path / "again.yaml")).spec.onsets == loaded.spec.onsets


def test_onsets_and_switches_together_are_refused(plant_model, inputs):
    blocked = plant_model.with_effect("coolant_flow_reduction", k_flow=0.3).with_onsets({"coolant_flow_reduction": 60})
    with pytest.raises(InputError, match="switches"):
        simulate(blocked, inputs, switches=[(100.0, plant_model)])


@pytest.mark.parametrize("onset, field", [(-5, "effects[0].onset_s"), ("soon", "effects[0].onset_s")])
def test_bad_onset_in_a_model_file_names_the_field(onset, field, tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("machine: genco_rf201a\neffects:\n  - name: coolant_flow_reduction\n"
                    f"    parameters: {{k_flow: 0.5}}\n    onset_s: {onset}\n")
    with pytest.raises(InputError) as error:
        load_model(path)
    assert error.value.field == field


def test_onset_of_an_effect_the_model_lacks_is_refused(plant_model):
    with pytest.raises(InputError, match="not an effect"):
        plant_model.with_onsets({"coolant_flow_reduction": 60.0})
