"""The FMU export against FMPy: validation, simulation = genthermal, tunable parameters, directional
derivatives = finite differences, and the answers to bad input."""

import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

from genthermal import fmu as fmu_module
from genthermal.ccompile import find_compiler
from genthermal.cli import main
from genthermal.errors import CompilerNotFoundError, InputError
from genthermal.fmu import FmuError, export_fmu, piecewise_constant_input
from genthermal.mission import load_mission
from genthermal.simulate import simulate

fmpy = pytest.importorskip("fmpy", reason="FMPy validates and simulates the FMU (pip install fmpy)")
from fmpy.fmi2 import FMU2Model  # noqa: E402
from fmpy.model_description import read_model_description  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

#: The mission: thesis Fig 7.7 (4 h) up to 2 h, enough to heat the machine and step the load.
STOP_S = 7200.0


@pytest.fixture(scope="module")
def fmus(plant_model, design_model, tmp_path_factory):
    """The FMUs of the nonlinear and the linear model."""
    try:
        find_compiler()
    except CompilerNotFoundError as exc:
        pytest.skip(f"no C compiler: {exc}")
    root = tmp_path_factory.mktemp("fmu")
    return {"nonlinear": export_fmu(plant_model, root / "nonlinear.fmu").path,
            "linear": export_fmu(design_model, root / "linear.fmu").path}


def _model(variant, plant_model, design_model):
    return plant_model if variant == "nonlinear" else design_model


def _mission(dt_s):
    inputs = load_mission("thesis_fig_7_7").to_inputs(dt_s)
    return inputs[inputs["time_s"] <= STOP_S].reset_index(drop=True)


def _fly(path, model, kind, start_values=None):
    inputs = _mission(10.0)
    x0 = {f"x_{n}": float(inputs["T_ambient"].iloc[0]) for n in model.state_names}
    result = fmpy.simulate_fmu(str(path), fmi_type=kind, start_time=0.0, stop_time=STOP_S, output_interval=10.0,
                               input=piecewise_constant_input(inputs, model.input_names), relative_tolerance=1e-10,
                               start_values={**x0, **(start_values or {})}, output=list(model.output_names))
    grid = inputs["time_s"].to_numpy()
    return {name: np.interp(grid, result["time"], result[name]) for name in model.output_names}


@pytest.mark.parametrize("variant", ["nonlinear", "linear"])
def test_fmpy_validation_passes_and_the_description_names_everything(variant, fmus, plant_model, design_model):
    model = _model(variant, plant_model, design_model)
    assert validate_fmu(str(fmus[variant])) == []
    description = read_model_description(str(fmus[variant]))
    assert description.modelExchange.providesDirectionalDerivative
    assert description.coSimulation.providesDirectionalDerivative
    by_name = {v.name: v for v in description.modelVariables}
    assert [v.name for v in description.modelVariables if v.causality == "input"] == list(model.input_names)
    assert [v.name for v in description.modelVariables if v.causality == "output"] == list(model.output_names)
    for name in model.parameter_names:
        variable, parameter = by_name[name], model.parameters[name]
        assert (variable.causality, variable.variability) == ("parameter", "tunable")
        assert float(variable.start) == parameter.value and variable.unit == parameter.unit
        assert parameter.provenance in variable.description
    units = {u.name: u for u in description.unitDefinitions}
    assert units["degC"].baseUnit.K == 1 and units["degC"].baseUnit.offset == 273.15
    with zipfile.ZipFile(fmus[variant]) as archive:  # the sources build the binary elsewhere
        names = archive.namelist()
        xml = ET.fromstring(archive.read("modelDescription.xml"))
    listed = {f.get("name") for f in xml.iter("File")}
    assert "fmi2_wrapper.c" in listed and all(f"sources/{name}" in names for name in listed)


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_fmpy_simulation_of_the_linear_model_equals_genthermal(kind, fmus, design_model):
    reference = simulate(design_model, _mission(10.0))  # exact zero-order hold
    flown = _fly(fmus["linear"], design_model, kind)
    for name in design_model.output_names:
        assert np.max(np.abs(flown[name] - reference[name].to_numpy())) < 1e-6, name
    assert reference["T_winding"].max() > 60.0  # the mission heats the machine


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_fmpy_simulation_of_the_nonlinear_model_equals_genthermal(kind, fmus, plant_model):
    # genthermal's nonlinear step (ETD2RK) is second order: at 0.5 s it is converged to ~1e-8 K,
    # at its default 10 s it is 2e-4 K from the exact solution the FMU integrates.
    fine = simulate(plant_model, _mission(0.5)).iloc[::20]
    default = simulate(plant_model, _mission(10.0))
    flown = _fly(fmus["nonlinear"], plant_model, kind)
    for name in plant_model.output_names:
        assert np.max(np.abs(flown[name] - fine[name].to_numpy())) < 1e-6, name
        assert np.max(np.abs(flown[name] - default[name].to_numpy())) < 3e-4, name


def test_a_tuned_parameter_start_value_changes_the_fmu_like_the_model(fmus, design_model):
    tuned = design_model.with_parameters(provenance="assumed", source="test", h_end_air=13.0)
    reference = simulate(tuned, _mission(10.0))
    flown = _fly(fmus["linear"], design_model, "CoSimulation", {"h_end_air": 13.0})
    default = simulate(design_model, _mission(10.0))
    assert np.max(np.abs(flown["T_winding"] - reference["T_winding"].to_numpy())) < 1e-6
    assert np.max(np.abs(reference["T_winding"] - default["T_winding"])) > 0.5  # the parameter matters


@pytest.mark.parametrize("variant", ["nonlinear", "linear"])
def test_directional_derivatives_equal_finite_differences(variant, fmus, plant_model, design_model, tmp_path):
    model = _model(variant, plant_model, design_model)
    description = read_model_description(str(fmus[variant]))
    unzipped = fmpy.extract(str(fmus[variant]), unzipdir=str(tmp_path / "unzipped"))
    instance = FMU2Model(guid=description.guid, unzipDirectory=unzipped,
                         modelIdentifier=description.modelExchange.modelIdentifier, instanceName="jacobian")
    instance.instantiate()
    instance.setupExperiment(startTime=0.0)
    instance.enterInitializationMode()
    instance.exitInitializationMode()
    refs = {v.name: v.valueReference for v in description.modelVariables}
    states = [refs[f"x_{n}"] for n in model.state_names]
    inputs = [refs[n] for n in model.input_names]
    unknowns = [refs[f"der(x_{n})"] for n in model.state_names] + [refs[n] for n in model.output_names]
    instance.enterEventMode()
    instance.newDiscreteStates()
    instance.enterContinuousTimeMode()
    n = model.n_states
    rng = np.random.default_rng(5)
    point = np.concatenate([rng.uniform(30.0, 120.0, n), [6.5, 7.0, 7.2, 1.1, 35.0, 22.0]])  # (x, u)

    def unknown_values(z):
        instance.setContinuousStates((fmpy.fmi2.fmi2Real * n)(*z[:n]), n)
        instance.setReal(inputs, list(z[n:]))
        return np.array(instance.getReal(unknowns))

    assert np.allclose(unknown_values(point)[:n], model.rhs(point[:n], point[n:]), rtol=1e-12, atol=1e-15)
    directions = list(np.eye(point.size)) + [rng.normal(size=point.size)]  # each known, then all at once
    for direction in directions:
        unknown_values(point)
        derivative = np.array(instance.getDirectionalDerivative(unknowns, states + inputs, list(direction)))
        h = 1e-4 * max(1.0, np.abs(point).max())
        central = (unknown_values(point + h * direction) - unknown_values(point - h * direction)) / (2 * h)
        assert np.allclose(derivative, central, rtol=1e-6, atol=1e-9), direction
    instance.terminate()
    instance.freeInstance()


def test_cli_writes_a_valid_fmu_and_names_bad_input(fmus, tmp_path, capsys):
    out = tmp_path / "m.fmu"
    assert main(["fmu", "--model", "genco_rf201a:linear", "--out", str(out)]) == 0
    assert "wrote" in capsys.readouterr().out and validate_fmu(str(out)) == []
    assert main(["fmu", "--model", "no_such_machine", "--out", str(tmp_path / "x.fmu")]) == 2
    assert "no_such_machine" in capsys.readouterr().err
    assert main(["fmu", "--out", str(tmp_path / "x.zip")]) == 2
    assert ".fmu" in capsys.readouterr().err
    assert not (tmp_path / "x.fmu").exists() and not (tmp_path / "x.zip").exists()


def test_what_fmi_cannot_express_is_refused_before_anything_is_written(design_model, tmp_path, monkeypatch):
    with pytest.raises(InputError, match="out"):
        export_fmu(design_model, tmp_path / "model.zip")
    monkeypatch.delitem(fmu_module.model_description.UNITS, "W/(m^2 K)")
    with pytest.raises(FmuError, match=r"parameter h_\w+ has unit 'W/\(m\^2 K\)'"):
        export_fmu(design_model, tmp_path / "model.fmu")
    assert list(tmp_path.iterdir()) == []


def test_without_compiler_no_fmu_is_left_behind(design_model, tmp_path, monkeypatch):
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setattr("genthermal.ccompile.shutil.which", lambda *args, **kwargs: None)
    with pytest.raises(CompilerNotFoundError):
        export_fmu(design_model, tmp_path / "model.fmu")
    assert list(tmp_path.iterdir()) == []
