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
    plants : TruePlants
        A power system's true plants (:meth:`PowerSystem.true_plants
        <genthermal.schedule.power_system.PowerSystem.true_plants>`: the ``--plant`` model, or the
        planning model with ``plant_mismatch``, and the faults' effects from their onsets).
    """

    def __init__(self, plants):
        self.plants = plants
        self.sensor_names = tuple(plants.model(0).output_names)
        self._states = None

    def reset(self, setup: PlantSetup) -> None:
        """Every node of every generator at ``setup.initial_C``."""
        model = self.plants.model(0)
        self._states = np.full((len(setup.generator_names), model.n_states), float(setup.initial_C))

    def step(self, t_s: float, dt_s: float, inputs: dict) -> Readings:
        """Simulate every generator over the inputs (the faults that start within switch in)."""
        plants = self.plants
        n = next(iter(inputs.values())).shape[1]
        time_s = t_s + dt_s * np.arange(n + 1)
        values = np.empty((plants.n_generators, len(self.sensor_names), n))
        for g in range(plants.n_generators):
            model = plants.model(g, plants.faults_known_at(t_s))
            _, switches = plants.switches(g)
            later = [(onset, m) for onset, m in switches if t_s < onset < t_s + n * dt_s]
            # the frame's last row repeats the final input, so the frame also yields the state at the end
            frame = pd.DataFrame({"time_s": time_s, **{name: np.append(inputs[name][g], inputs[name][g, -1])
                                                        for name in model.input_names}})
            run = simulate(model, frame, x0=self._states[g], switches=later)
            self._states[g] = run[[f"T_{name}" for name in model.state_names]].to_numpy()[-1]
            values[g] = run[list(self.sensor_names)].to_numpy()[1:].T
        return Readings(time_s[1:], values, self.sensor_names)
