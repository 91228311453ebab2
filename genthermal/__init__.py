"""genthermal: lumped-parameter thermal models of electrical machines, and what uses them.

One symbolic network, many consumers: simulation, calibration and diagnosis, Kalman filters, load
planning and closed-loop flights, generated C and FMU export. The names below are the entry points;
they are imported on first use, so ``import genthermal`` stays light.

>>> import genthermal
>>> plant = genthermal.build_model()                       # doctest: +SKIP
>>> result = genthermal.simulate(plant, genthermal.load_mission("thesis_fig_7_7").to_inputs(10.0))  # doctest: +SKIP
"""

from __future__ import annotations

import functools
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
    namesake = f"{__name__}.{name}"
    if module == namesake or module.startswith(namesake + "."):
        value = _EntryPoint(value, namesake)
    globals()[name] = value  # later look-ups skip this function
    return value


class _EntryPoint:
    """An entry point named like a sub-module (``simulate``, ``diagnose``): calling it calls the
    function, and its signature and docstring are the function's; every other attribute is the
    sub-module's, so ``genthermal.diagnose.compare`` and ``import genthermal.diagnose.report as r``
    reach the sub-package as well."""

    def __init__(self, function, module_name: str):
        functools.update_wrapper(self, function)
        self._module_name = module_name

    def __call__(self, *args, **kwargs):
        return self.__wrapped__(*args, **kwargs)

    def __getattr__(self, name: str):
        if name.startswith("_"):  # dunder protocols, and this object's own state before it is set
            raise AttributeError(name)
        module = importlib.import_module(self._module_name)
        try:
            return getattr(module, name)
        except AttributeError:
            pass
        try:
            return importlib.import_module(f"{self._module_name}.{name}")
        except ModuleNotFoundError:
            raise AttributeError(f"{self._module_name!r} has no attribute {name!r}") from None

    def __dir__(self):
        return sorted(set(super().__dir__()) | set(dir(importlib.import_module(self._module_name))))

    def __repr__(self):
        return f"<function {self.__wrapped__.__module__}.{self.__qualname__} (also the module {self._module_name})>"


def __dir__():
    return sorted(set(globals()) | set(__all__))


class _Package(types.ModuleType):
    """The package module: an entry point named like a sub-module (``simulate``, ``diagnose``)
    stays the entry point when that sub-module is imported (the import system would otherwise set
    the package attribute to the sub-module); the sub-module stays in ``sys.modules`` and is
    reached through the entry point's attributes (:class:`_EntryPoint`)."""

    def __setattr__(self, name, value):
        if name in _EXPORTS and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
