"""Bad model files: one table row per case; a new bad input is one more row.

Numbers only as numbers: ``value: true`` or ``value: "17.2"`` is an error, never 1.0 or 17.2.
Each case ends in exit code 2 with one line naming the field, before the data file is read.
"""

import pytest

from genthermal.cli import main
from genthermal.errors import InputError
from genthermal.model_file import load_model

PARAMETER = "machine: genco_rf201a\nparameters:\n  h_end_air: {}\n"
EFFECT = "machine: genco_rf201a\neffects:\n  - {}\n"

# (case, file content (text or bytes), text the error must contain)
BAD_MODEL_FILES = [
    ("empty file", "", "mapping"),
    ("binary file", b"\x00\xff\xfe\x00\x89PNG\r\n" * 30, "not a text file"),
    ("a list", "- genco_rf201a\n", "mapping"),
    ("YAML syntax error", "machine: [genco\n", "YAML"),
    ("no machine", "variant: linear\n", "machine"),
    ("unknown machine", "machine: genco_rf999\n", "genco_rf999"),
    ("machine as a number", "machine: 201\n", "machine"),
    ("unknown variant", "machine: genco_rf201a\nvariant: quadratic\n", "variant"),
    ("unknown top-level key", "machine: genco_rf201a\nparamters: {}\n", "paramters"),
    ("unknown parameter", "machine: genco_rf201a\nparameters:\n  h_end_ari: {value: 15}\n", "h_end_ari"),
    ("value true", PARAMETER.format("{value: true}"), "parameters.h_end_air.value"),
    ("value as quoted text", PARAMETER.format("{value: '17.2'}"), "parameters.h_end_air.value"),
    ("value .inf", PARAMETER.format("{value: .inf}"), "finite"),
    ("value .nan", PARAMETER.format("{value: .nan}"), "finite"),
    ("value missing", PARAMETER.format("{provenance: fitted}"), "parameters.h_end_air.value"),
    ("bare value true", PARAMETER.format("yes"), "parameters.h_end_air.value"),
    ("non-physical value", PARAMETER.format("{value: -5}"), "h_end_air"),
    ("unknown provenance", PARAMETER.format("{value: 15, provenance: guessed}"), "provenance"),
    ("misspelt entry key", PARAMETER.format("{value: 15, sorce: rig}"), "sorce"),
    ("effects not a list", "machine: genco_rf201a\neffects: {name: coolant_flow_reduction}\n", "effects"),
    ("unknown effect", EFFECT.format("{name: coolant_flow, parameters: {k_flow: 0.5}}"), "coolant_flow"),
    ("effect parameter as text", EFFECT.format("{name: coolant_flow_reduction, parameters: {k_flow: half}}"),
     "k_flow"),
    ("effect parameter false", EFFECT.format("{name: coolant_flow_reduction, parameters: {k_flow: false}}"),
     "k_flow"),
    ("effect parameter out of range", EFFECT.format("{name: coolant_flow_reduction, parameters: {k_flow: 7}}"),
     "k_flow"),
    ("misspelt effect key", EFFECT.format("{name: coolant_flow_reduction, paramters: {k_flow: 0.5}}"),
     "paramters"),
    ("parameter given twice", "machine: genco_rf201a\nparameters:\n  h_end_air: {value: 15}\n  h_end_air: {value: 16}\n",
     "given twice"),
    ("brackets nested 5000 deep", "machine: genco_rf201a\nx: " + "[" * 5000 + "]" * 5000 + "\n", "nested too deeply"),
]


@pytest.mark.parametrize("content, named", [c[1:] for c in BAD_MODEL_FILES], ids=[c[0] for c in BAD_MODEL_FILES])
def test_bad_model_file_names_the_field(content, named, tmp_path, capsys):
    path = tmp_path / "model.yaml"
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    with pytest.raises(InputError) as caught:
        load_model(path)
    assert named in str(caught.value)
    assert main(["compare", str(tmp_path / "no_data.csv"), "--model", str(path)]) == 2
    err = capsys.readouterr().err
    assert named in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_numbers_written_as_numbers_are_read(tmp_path):
    path = tmp_path / "model.yaml"
    path.write_text(PARAMETER.format("{value: 17, provenance: fitted, source: rig}"))
    model = load_model(path)
    assert model.parameters.value("h_end_air") == 17.0 and model.parameters["h_end_air"].provenance == "fitted"


def test_a_runaway_model_has_no_steady_state_rather_than_one_below_ambient(tmp_path):
    """R0 of 1e200 ohm: Newton's only root is where the copper resistance vanishes (-256 °C); it is
    refused, not used as the initial state of a comparison."""
    path = tmp_path / "model.yaml"
    path.write_text("machine: genco_rf201a\nparameters:\n  R0: {value: 1.0e+200}\n")
    model = load_model(path)
    with pytest.raises(InputError, match="thermal runaway"):
        model.steady_state(model.input_vector(7.0, 7.0, 7.0, 1.0, 20.0, 20.0))
