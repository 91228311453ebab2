"""An FMU as the plant: an FMI 2.0 co-simulation FMU per generator, through FMPy (``--plant model.fmu``).

The FMU must take the machine's inputs and give its sensors as variables of those names (the FMUs
``genthermal fmu`` exports do); its states named ``x_<node>`` (those FMUs) start at the ambient, any
other FMU starts from its own start values. An FMU that is model exchange only, or of another FMI
version, is refused by name: a plant steps itself.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import numpy as np

from ..errors import InputError
from .protocol import PlantSetup, Readings


def _fmpy(path):
    try:
        import fmpy
        from fmpy.fmi2 import FMU2Slave
    except ImportError:
        raise InputError("--plant", str(path), "an FMU plant needs FMPy: pip install 'genthermal[fmu]'") from None
    return fmpy, FMU2Slave


class FmuPlant:
    """:class:`~genthermal.plants.protocol.Plant` of an FMI 2.0 co-simulation FMU, one instance per generator.

    Parameters
    ----------
    path : str or Path
        The ``.fmu`` file.

    Raises
    ------
    InputError
        When the file is not an FMU FMPy can read, is not FMI 2.0 or has no co-simulation interface.
    """

    def __init__(self, path):
        self.path, self._instances, self._unzipped = Path(path), [], None
        fmpy, self._slave = _fmpy(path)
        try:
            description = fmpy.read_model_description(str(self.path))
        except Exception as error:  # noqa: BLE001 - any unreadable file is named with FMPy's reason
            raise InputError("--plant", str(path), f"not an FMU FMPy can read: {type(error).__name__}: {error}") from None
        if description.fmiVersion != "2.0":
            raise InputError("--plant", str(path), f"an FMI {description.fmiVersion} FMU: the plant needs an FMI 2.0 "
                             "co-simulation FMU (genthermal fmu exports one)")
        if description.coSimulation is None:
            raise InputError("--plant", str(path), "a model-exchange FMU only (no CoSimulation element): the plant "
                             "needs an FMI 2.0 co-simulation FMU, which steps itself (genthermal fmu exports both)")
        self._description = description
        self._variables = {v.name: v for v in description.modelVariables}
        self.sensor_names = tuple(v.name for v in description.modelVariables if v.causality == "output")

    def reset(self, setup: PlantSetup) -> None:
        """Instantiate one co-simulation slave per generator, its ``x_*`` states at ``setup.initial_C``."""
        fmpy, _ = _fmpy(self.path)
        missing = [name for name in setup.input_names if self._variables.get(name) is None
                   or self._variables[name].causality != "input"]
        if missing:
            raise InputError("--plant", str(self.path), f"the FMU has no input variables {missing} (the machine's "
                             f"inputs are {list(setup.input_names)})")
        self.close()
        self._unzipped = tempfile.mkdtemp(prefix="genthermal-fmu-plant-")
        fmpy.extract(str(self.path), unzipdir=self._unzipped)
        self._inputs = [self._variables[name].valueReference for name in setup.input_names]
        self._input_names = tuple(setup.input_names)
        self._outputs = [self._variables[name].valueReference for name in self.sensor_names]
        states = [v.valueReference for name, v in self._variables.items() if name.startswith("x_")
                  and v.causality == "local" and v.variability == "continuous"]
        for name in setup.generator_names:
            slave = self._slave(guid=self._description.guid, unzipDirectory=self._unzipped,
                                modelIdentifier=self._description.coSimulation.modelIdentifier, instanceName=name)
            slave.instantiate()
            slave.setupExperiment(startTime=0.0)
            slave.enterInitializationMode()
            if states:
                slave.setReal(states, [float(setup.initial_C)] * len(states))
            slave.exitInitializationMode()
            self._instances.append(slave)

    def step(self, t_s: float, dt_s: float, inputs: dict) -> Readings:
        """One ``doStep`` of ``dt_s`` per step and generator, the inputs held over it."""
        n = next(iter(inputs.values())).shape[1]
        values = np.empty((len(self._instances), len(self.sensor_names), n))
        for g, slave in enumerate(self._instances):
            for i in range(n):
                slave.setReal(self._inputs, [float(inputs[name][g, i]) for name in self._input_names])
                slave.doStep(currentCommunicationPoint=t_s + i * dt_s, communicationStepSize=dt_s)
                values[g, :, i] = slave.getReal(self._outputs)
        return Readings(t_s + dt_s * np.arange(1, n + 1), values, self.sensor_names)

    def close(self) -> None:
        """Free the instances and the unzipped FMU."""
        for slave in self._instances:
            try:
                slave.terminate()
                slave.freeInstance()
            except Exception:  # noqa: BLE001 - freeing a failed instance must not hide the failure
                pass
        self._instances = []
        if self._unzipped is not None:
            shutil.rmtree(self._unzipped, ignore_errors=True)
            self._unzipped = None

    def __del__(self):
        self.close()
