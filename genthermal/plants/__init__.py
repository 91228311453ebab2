"""Plants a flight flies (``genthermal fly --plant``): anything with the :class:`Plant` protocol.

* :mod:`.protocol` — :class:`Plant`, :class:`PlantSetup`, :class:`Readings`, the checks of a plant's answers;
* :mod:`.model_plant` — the genthermal model plant (the default);
* :mod:`.fmu_plant` — an FMI 2.0 co-simulation FMU through FMPy (``--plant model.fmu``);
* :mod:`.python_plant` — a user's plant in a Python file (``--plant my_plant.py``);
* :mod:`.log_plant` — a recorded flight replayed (``--plant log.csv``): decisions scored, not applied.
"""

from __future__ import annotations

from pathlib import Path

from .protocol import Plant, PlantFault, PlantSetup, Readings

__all__ = ["Plant", "PlantFault", "PlantSetup", "Readings", "external_plant", "is_external_plant"]


def is_external_plant(value) -> bool:
    """Whether a ``--plant`` value names an FMU, a Python file or a log rather than a genthermal model."""
    return value is not None and Path(str(value)).suffix.lower() in (".fmu", ".py", ".csv")


def external_plant(value, sensor_names=()):
    """The plant of ``--plant value``: an :class:`~.fmu_plant.FmuPlant` for ``.fmu``, a replayed log
    (:class:`~.log_plant.LogPlant`, of the machine's ``sensor_names``) for ``.csv``, the plant of a
    Python file (:func:`~.python_plant.load_python_plant`) for ``.py``."""
    suffix = Path(str(value)).suffix.lower()
    if suffix == ".fmu":
        from .fmu_plant import FmuPlant
        return FmuPlant(value)
    if suffix == ".csv":
        from .log_plant import LogPlant
        return LogPlant(value, sensor_names)
    from .python_plant import load_python_plant
    return load_python_plant(value)
