"""Machines: the built-in thesis generator, and any machine a user plugs in.

``build_model("genco_rf201a")`` gives the thesis generator; ``build_model("path/to/motor.py")`` or
the name of an installed plug-in gives a user's machine (:mod:`genthermal.machines.registry`). A
machine is a :class:`Machine`: its :class:`MachineInterface` (inputs, sensors, ratings, limits,
roles), its parameter set and its network builder.
"""

from __future__ import annotations

from ..model import ModelSpec, ThermalModel
from ..parameters import ParameterSet
from . import genco_rf201a
from .interface import GeneratorRole, InputKind, Machine, MachineInterface, ModelInput, Role, Sensor, SpeedRole
from .registry import BUILT_IN, known_machines, resolve_machine

#: Built-in machines by name (plug-ins are found through :func:`resolve_machine`).
MACHINES = BUILT_IN
DEFAULT_MACHINE = genco_rf201a.NAME

__all__ = ["MACHINES", "DEFAULT_MACHINE", "GeneratorRole", "InputKind", "Machine", "MachineInterface",
           "ModelInput", "Role", "Sensor", "SpeedRole", "build_model", "known_machines", "resolve_machine"]


def build_model(machine: "str | Machine" = DEFAULT_MACHINE, parameters: ParameterSet | None = None,
                from_data: bool = False) -> ThermalModel:
    """Build the nonlinear simulation model of a machine.

    Parameters
    ----------
    machine : str or Machine
        A built-in name (``"genco_rf201a"``), an installed plug-in's name, the path of a ``.py``
        machine file, or a :class:`Machine`.
    parameters : ParameterSet, optional
        Parameter values; defaults to the machine's own (with provenance).
    from_data : bool
        ``machine`` was read from a data file: a machine file must be trusted
        (:func:`~genthermal.machines.registry.resolve_machine`).

    Returns
    -------
    ThermalModel
        Use :func:`genthermal.design.linear_design_model` for the linear design model.
    """
    definition = resolve_machine(machine, from_data)
    parameters = parameters if parameters is not None else definition.default_parameters()
    source = machine if isinstance(machine, str) else definition.name
    spec = ModelSpec(name=definition.name, interface=definition.interface, machine_source=source)
    return ThermalModel(definition.build_network(parameters), parameters, spec)
