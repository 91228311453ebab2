"""Built-in machines. ``build_model("genco_rf201a")`` gives the thesis generator."""

from __future__ import annotations

from ..errors import InputError
from ..model import ModelSpec, ThermalModel
from ..parameters import ParameterSet
from . import genco_rf201a

MACHINES = {genco_rf201a.NAME: genco_rf201a}


def build_model(machine: str = genco_rf201a.NAME, parameters: ParameterSet | None = None) -> ThermalModel:
    """Build the nonlinear simulation model of a built-in machine.

    Parameters
    ----------
    machine : str
        Name of a built-in machine (``"genco_rf201a"``).
    parameters : ParameterSet, optional
        Parameter values; defaults to the machine's own (with provenance).

    Returns
    -------
    ThermalModel
        Use :func:`genthermal.design.linear_design_model` for the linear design model.
    """
    try:
        module = MACHINES[machine]
    except KeyError:
        raise InputError("machine", machine, f"unknown machine; built in: {', '.join(MACHINES)}") from None
    parameters = parameters if parameters is not None else module.default_parameters()
    spec = ModelSpec(name=module.NAME, sensors=dict(module.SENSORS),
                     boundary_inputs=dict(module.BOUNDARY_INPUTS), outlet_node=module.OUTLET_NODE,
                     rated_current_A=module.RATED_CURRENT_A, roles=dict(module.ROLES))
    return ThermalModel(module.build_network(parameters), parameters, spec)
