"""Parameter provenance and refusal of non-physical values at model build time."""

import pytest
import sympy

from genthermal.errors import InputError, ParameterError
from genthermal.machines import build_model
from genthermal.machines.genco_rf201a import default_parameters
from genthermal.parameters import PROVENANCES, Parameter


def test_every_parameter_has_provenance_and_a_source():
    for parameter in default_parameters().table():
        assert parameter["provenance"] in PROVENANCES
        assert len(parameter["source"]) > 10, parameter["name"]


def test_thesis_values_are_marked_thesis():
    p = default_parameters()
    for name, value in {"k_cr": 0.13, "k_sa": 0.1, "s": 0.97, "s_c": 0.5, "alpha_cu": 0.0039,
                        "L_s": 0.053, "r_si1": 0.136, "k_sr": 20.0, "rho_copper": 8933.0}.items():
        assert p[name].value == value and p[name].provenance == "thesis"


@pytest.mark.parametrize("name, value", [
    ("h_end_air", -5.0),        # negative conductance
    ("rho_copper", 0.0),        # zero capacitance of the winding nodes
    ("m_dot_fan", -0.01),       # negative mass flow
    ("s_c", 1.5),               # winding factor above one
    ("L_s", float("nan")),
])
def test_non_physical_values_are_refused_naming_the_parameter(plant_model, name, value):
    with pytest.raises(ParameterError) as caught:
        plant_model.with_parameters(**{name: value})
    assert name in str(caught.value) and repr(value) in str(caught.value)


def test_non_physical_element_is_refused_when_the_model_is_built(plant_model):
    """A value inside every parameter's own range can still make an element non-physical:
    more slots than fit in the teeth annulus gives a negative tooth ratio."""
    with pytest.raises(ParameterError) as caught:
        plant_model.with_parameters(n_slots=80)
    assert "stator_teeth" in str(caught.value) and "n_slots" in str(caught.value)


def test_unknown_parameter_suggests_the_closest_name(plant_model):
    with pytest.raises(ParameterError, match="did you mean h_end_air"):
        plant_model.with_parameters(h_end_ai=10.0)


def test_unknown_machine_is_refused():
    with pytest.raises(InputError, match="genco_rf201a"):
        build_model("genco")


def test_parameter_provenance_must_be_known():
    with pytest.raises(ParameterError, match="provenance"):
        Parameter("x", 1.0, "m", "guessed", "because")


def test_fitted_values_record_their_provenance(plant_model):
    fitted = plant_model.with_parameters(h_end_air=20.0, source="fitted to run 3")
    assert fitted.parameters["h_end_air"].provenance == "fitted"
    assert fitted.parameters["h_end_air"].source == "fitted to run 3"
    assert isinstance(fitted.parameters["h_end_air"].symbol, sympy.Symbol)
