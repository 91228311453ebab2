"""A user's own plant in a Python file (``fly --plant my_plant.py``).

Running the file is a trust decision the user makes on the command line; a data file (a scenario, a
model file) never names one. The file defines ``make_plant()``, which returns a
:class:`~genthermal.plants.protocol.Plant`. A file that raises on import, has no ``make_plant`` or
returns something that is not a plant is an :class:`~genthermal.errors.InputError` naming the file.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import InputError
from ..user_files import run_user_file, where_raised


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
    module = run_user_file(path, option, "plant")
    make = getattr(module, "make_plant", None)
    if not callable(make):
        raise InputError(option, str(path), "the plant file defines no make_plant() returning the plant")
    try:
        plant = make()
    except Exception as error:  # noqa: BLE001
        raise InputError(option, str(path), f"make_plant() raised {type(error).__name__}: {error}"
                         f"{where_raised(error, path)}") from None
    lacking = [a for a in ("sensor_names", "reset", "step") if not hasattr(plant, a)]
    if lacking:
        raise InputError(option, str(path), f"make_plant() returned a {type(plant).__name__} without {lacking}: "
                         "a plant has sensor_names, reset(setup) and step(t_s, dt_s, inputs) "
                         "(genthermal.plants.protocol.Plant)")
    return plant
