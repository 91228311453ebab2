"""``modelDescription.xml`` of an FMI 2.0 FMU of a ThermalModel (model exchange and co-simulation).

The variables, in value-reference order: the states (``x_<node>``, °C), their derivatives, the
inputs, the sensor outputs and every parameter (tunable, with unit and provenance). Units are
declared with their SI base-unit exponents from :data:`UNITS`; any other unit is refused
(:class:`FmuError`). Guide: ``docs/guide/embedded.md``.
"""

from __future__ import annotations

import dataclasses
import math
import xml.etree.ElementTree as ET

from ..codegen import CodegenError
from ..model import ThermalModel

#: FMI unit name -> SI base-unit exponents (and for degC the offset to kelvin, for rpm the factor
#: to rad/s).
UNITS = {
    "rpm": {"rad": 1, "s": -1, "factor": 2 * math.pi / 60.0},
    "W/K": {"kg": 1, "m": 2, "s": -3, "K": -1},
    "J/K": {"kg": 1, "m": 2, "s": -2, "K": -1},
    "1": {},
    "m": {"m": 1},
    "A": {"A": 1},
    "A^2": {"A": 2},
    "ohm": {"kg": 1, "m": 2, "s": -3, "A": -2},
    "W": {"kg": 1, "m": 2, "s": -3},
    "W/(m K)": {"kg": 1, "m": 1, "s": -3, "K": -1},
    "W/(m^2 K)": {"kg": 1, "s": -3, "K": -1},
    "J/(kg K)": {"m": 2, "s": -2, "K": -1},
    "kg/m^3": {"kg": 1, "m": -3},
    "kg/s": {"kg": 1, "s": -1},
    "1/K": {"K": -1},
    "K/s": {"K": 1, "s": -1},
    "degC": {"K": 1, "offset": 273.15},
}
#: Start value of every state, °C (a cold machine at 20 °C); set them before initialisation.
STATE_START_C = 20.0


class FmuError(CodegenError):
    """The model has something FMI 2.0 (or this export) cannot express."""


@dataclasses.dataclass(frozen=True)
class Variable:
    """One scalar variable of the FMU: its value reference is its position in the layout."""

    name: str
    causality: str
    variability: str
    unit: str
    description: str
    start: float | None = None
    initial: str | None = None
    derivative_of: int | None = None


def variables(model: ThermalModel) -> list[Variable]:
    """Every variable of the FMU of ``model``, in value-reference order.

    Raises
    ------
    FmuError
        A parameter whose unit is not in :data:`UNITS`, or two variables with one name.
    """
    states = [Variable(f"x_{n}", "local", "continuous", "degC", f"temperature of node {n}",
                       STATE_START_C, "exact") for n in model.state_names]
    derivatives = [Variable(f"der(x_{n})", "local", "continuous", "K/s", f"d/dt of the temperature of node {n}",
                            derivative_of=i + 1) for i, n in enumerate(model.state_names)]
    inputs = [Variable(i.name, "input", "continuous", i.unit, i.description, i.default)
              for i in model.spec.interface.inputs]
    outputs = [Variable(n, "output", "continuous", "degC", f"sensor temperature of node {model.spec.sensors[n]}")
               for n in model.output_names]
    parameters = []
    for name in model.parameter_names:
        parameter = model.parameters[name]
        if parameter.unit not in UNITS:
            raise FmuError(f"parameter {name} has unit {parameter.unit!r}, which this FMU export cannot declare "
                           f"in FMI units (known: {', '.join(UNITS)})")
        parameters.append(Variable(name, "parameter", "tunable", parameter.unit,
                                   f"{parameter.provenance}: {parameter.source}", parameter.value, "exact"))
    every = states + derivatives + inputs + outputs + parameters
    names = [v.name for v in every]
    clashes = sorted({n for n in names if names.count(n) > 1})
    if clashes:
        raise FmuError(f"FMI variable names must be unique; {model.name} has {', '.join(clashes)} twice")
    return every


def description_xml(model: ThermalModel, model_identifier: str, guid: str, source_files, generation_tool: str) -> str:
    """The XML text of ``modelDescription.xml``.

    Parameters
    ----------
    model : ThermalModel
    model_identifier : str
        Name of the shared library in ``binaries/<platform>/`` (a C identifier).
    guid : str
        Identifies this FMU; the binary refuses another.
    source_files : sequence of str
        Files in ``sources/`` that build the FMU.
    generation_tool : str
        E.g. ``genthermal 0.1.0``.
    """
    every = variables(model)
    root = ET.Element("fmiModelDescription", {
        "fmiVersion": "2.0", "modelName": model.name, "guid": guid, "generationTool": generation_tool,
        "description": f"lumped-parameter thermal network of {model.spec.name}, {model.spec.variant} model",
        "variableNamingConvention": "flat", "numberOfEventIndicators": "0"})
    for kind, extra in (("ModelExchange", {"completedIntegratorStepNotNeeded": "true"}),
                        ("CoSimulation", {"canHandleVariableCommunicationStepSize": "true"})):
        element = ET.SubElement(root, kind, {"modelIdentifier": model_identifier,
                                             "providesDirectionalDerivative": "true", **extra})
        files = ET.SubElement(element, "SourceFiles")
        for name in source_files:
            if name.endswith(".c"):
                ET.SubElement(files, "File", {"name": name})
    units = ET.SubElement(root, "UnitDefinitions")
    unknown = sorted({v.unit for v in every} - set(UNITS))
    if unknown:
        raise FmuError(f"unit {unknown[0]!r} of {model.name} has no FMI base-unit definition "
                       f"(known: {', '.join(UNITS)}); add it to genthermal.fmu.model_description.UNITS")
    for name in sorted({v.unit for v in every}):
        base = {k: repr(v) if isinstance(v, float) else str(v) for k, v in UNITS[name].items()}
        ET.SubElement(ET.SubElement(units, "Unit", {"name": name}), "BaseUnit", base)
    ET.SubElement(root, "DefaultExperiment", {"startTime": "0", "stopTime": "14400", "tolerance": "1e-8"})
    listed = ET.SubElement(root, "ModelVariables")
    for reference, variable in enumerate(every):
        attributes = {"name": variable.name, "valueReference": str(reference), "description": variable.description,
                      "causality": variable.causality, "variability": variable.variability}
        if variable.initial:
            attributes["initial"] = variable.initial
        scalar = ET.SubElement(listed, "ScalarVariable", attributes)
        real = {"unit": variable.unit}
        if variable.start is not None:
            real["start"] = repr(float(variable.start))
        if variable.derivative_of is not None:
            real["derivative"] = str(variable.derivative_of)
        ET.SubElement(scalar, "Real", real)
    structure = ET.SubElement(root, "ModelStructure")
    indices = {kind: [str(i + 1) for i, v in enumerate(every) if test(v)] for kind, test in (
        ("outputs", lambda v: v.causality == "output"), ("derivatives", lambda v: v.derivative_of is not None))}
    for tag, kinds in (("Outputs", ["outputs"]), ("Derivatives", ["derivatives"]),
                       ("InitialUnknowns", ["outputs", "derivatives"])):
        section = ET.SubElement(structure, tag)
        for index in sorted((i for kind in kinds for i in indices[kind]), key=int):
            ET.SubElement(section, "Unknown", {"index": index})
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
