"""genthermal: lumped-parameter thermal models of electrical machines, and what uses them.

One symbolic network, many consumers: simulation, calibration and diagnosis, Kalman filters, load
planning and closed-loop flights, generated C and FMU export. The names below are the entry points;
they are imported on first use, so ``import genthermal`` stays light.

>>> import genthermal
>>> plant = genthermal.build_model()                       # doctest: +SKIP
>>> result = genthermal.simulate(plant, genthermal.load_mission("thesis_fig_7_7").to_inputs(10.0))  # doctest: +SKIP
"""

from __future__ import annotations

import importlib
import sys
import types

__version__ = "0.1.0"

# public name -> module that defines it
_EXPORTS = {
    # models
    "build_model": "genthermal.machines",
    "load_model": "genthermal.model_file",
    "save_model": "genthermal.model_file",
    "linear_design_model": "genthermal.design",
    # missions, simulation, measurements
    "load_mission": "genthermal.mission",
    "simulate": "genthermal.simulate",
    "synthesize": "genthermal.synth",
    "load_measurements": "genthermal.measurements",
    # calibration and diagnosis
    "calibrate": "genthermal.diagnose.calibrate",
    "diagnose": "genthermal.diagnose.discover",
    # filters
    "KalmanFilter": "genthermal.estimation.kalman",
    "ExtendedKalmanFilter": "genthermal.estimation.ekf",
    # load planning and flights
    "PowerSystem": "genthermal.schedule.power_system",
    "ManagerSettings": "genthermal.schedule.flight.manager_settings",
    "plan_mission": "genthermal.schedule.flight.open_loop",
    "fly": "genthermal.schedule.flight.closed_loop",
    # code generation
    "generate_c": "genthermal.codegen",
    "export_fmu": "genthermal.fmu",
    # errors
    "InputError": "genthermal.errors",
}

__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str):
    """Import an entry point on first use (PEP 562)."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'genthermal' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))


class _Package(types.ModuleType):
    """The package module: an entry point named like a sub-module (``simulate``, ``diagnose``)
    stays the function when that sub-module is imported (the import system would otherwise set the
    package attribute to the sub-module); the sub-module itself stays in ``sys.modules``."""

    def __setattr__(self, name, value):
        if name in _EXPORTS and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
