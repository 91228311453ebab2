"""A user's own plant in a Python file (``fly --plant my_plant.py``).

Running the file is a trust decision the user makes on the command line; a data file (a scenario, a
model file) never names one. The file defines ``make_plant()``, which returns a
:class:`~genthermal.plants.protocol.Plant`. A file that raises on import, has no ``make_plant`` or
returns something that is not a plant is an :class:`~genthermal.errors.InputError` naming the file.
"""

from __future__ import annotations

import importlib.util
import sys
import traceback
from pathlib import Path

from ..errors import InputError


def _where(error: BaseException, path: Path) -> str:
    """``line N`` of ``path`` where ``error`` was raised, or an empty string."""
    lines = [frame.lineno for frame in traceback.extract_tb(error.__traceback__) if Path(frame.filename) == path]
    return f" (line {lines[-1]})" if lines else ""


def load_python_plant(path, option: str = "--plant"):
    """The plant ``make_plant()`` of the Python file ``path`` returns.

    Raises
    ------
    InputError
        Naming ``option`` and the file: it does not exist, raises on import (the exception and its
        line), defines no ``make_plant``, or ``make_plant()`` raises or returns no plant (an object
        with ``sensor_names``, ``reset`` and ``step``).
    """
    path = Path(path).resolve()
    if not path.is_file():
        raise InputError(option, str(path), "no such Python file")
    name = f"genthermal_user_plant_{abs(hash(str(path)))}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except Exception as error:  # noqa: BLE001 - whatever the user's file raises is named, never a traceback
        sys.modules.pop(name, None)
        raise InputError(option, str(path), f"importing the plant file raised {type(error).__name__}: {error}"
                         f"{_where(error, path)}") from None
    make = getattr(module, "make_plant", None)
    if not callable(make):
        raise InputError(option, str(path), "the plant file defines no make_plant() returning the plant")
    try:
        plant = make()
    except Exception as error:  # noqa: BLE001
        raise InputError(option, str(path), f"make_plant() raised {type(error).__name__}: {error}"
                         f"{_where(error, path)}") from None
    lacking = [a for a in ("sensor_names", "reset", "step") if not hasattr(plant, a)]
    if lacking:
        raise InputError(option, str(path), f"make_plant() returned a {type(plant).__name__} without {lacking}: "
                         "a plant has sensor_names, reset(setup) and step(t_s, dt_s, inputs) "
                         "(genthermal.plants.protocol.Plant)")
    return plant
