"""The genthermal model plant: each generator's nonlinear model, the scenario's plant mismatch and its
faults switched in at their onsets (what ``fly`` flew before there were other plants)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..simulate import simulate
from .protocol import PlantSetup, Readings


class ModelPlant:
    """:class:`~genthermal.plants.protocol.Plant` of a power system's true plant models.

    Parameters
    ----------
    system : PowerSystem
        Its :meth:`~genthermal.schedule.power_system.PowerSystem.plant_model` (``--plant`` model, or
        the planning model with ``plant_mismatch``) and :meth:`plant_switches` (the faults' effects
        from their onsets).
    """

    def __init__(self, system):
        self.system = system
        self.sensor_names = tuple(system.plant_model(0).output_names)
        self._states = None

    def reset(self, setup: PlantSetup) -> None:
        """Every node of every generator at ``setup.initial_C``."""
        model = self.system.plant_model(0)
        self._states = np.full((len(setup.generator_names), model.n_states), float(setup.initial_C))

    def step(self, t_s: float, dt_s: float, inputs: dict) -> Readings:
        """Simulate every generator over the inputs (the faults that start within switch in)."""
        system = self.system
        n = next(iter(inputs.values())).shape[1]
        time_s = t_s + dt_s * np.arange(n + 1)
        values = np.empty((system.n_generators, len(self.sensor_names), n))
        for g in range(system.n_generators):
            model = system.plant_model(g, system.faults_known_at(t_s))
            _, switches = system.plant_switches(g)
            later = [(onset, m) for onset, m in switches if t_s < onset < t_s + n * dt_s]
            # the frame's last row repeats the final input, so the frame also yields the state at the end
            frame = pd.DataFrame({"time_s": time_s, **{name: np.append(inputs[name][g], inputs[name][g, -1])
                                                        for name in model.input_names}})
            run = simulate(model, frame, x0=self._states[g], switches=later)
            self._states[g] = run[[f"T_{name}" for name in model.state_names]].to_numpy()[-1]
            values[g] = run[list(self.sensor_names)].to_numpy()[1:].T
        return Readings(time_s[1:], values, self.sensor_names)
