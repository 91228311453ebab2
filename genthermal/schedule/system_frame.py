"""What a flight's parts read of a power system, in place of the whole ``PowerSystem``.

:class:`SystemFrame` (names, limits, currents, the machine's inputs and sensors, the mission's
inlet) is what the planner, the recorder and the loop's input helpers receive; :class:`TruePlants`
(the true plant models and their fault switches) is what the model plant receives. Built by
:meth:`PowerSystem.frame <genthermal.schedule.power_system.PowerSystem.frame>` and
:meth:`PowerSystem.true_plants <genthermal.schedule.power_system.PowerSystem.true_plants>`.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable


@dataclasses.dataclass(frozen=True)
class SystemFrame:
    """A power system without its models and faults.

    Attributes
    ----------
    generator_names : tuple of str
    limit_C : float
        θmax, °C.
    rated_current_A, rest_current_A, current_limit_A : float
        Rated phase current, minimum power mode and highest phase current, A RMS.
    T_ambient_C : float
        The mission's ambient temperature, °C.
    power_factor : float
        The mission's power factor (the exciter law).
    input_names, output_names : tuple of str
        The machine's inputs and sensors.
    role : object
        The machine interface's generator role (coolant and ambient inputs, exciter law).
    inlet_C : callable
        ``inlet_C(generator, t_s, currents_A=None)``: the coolant inlet at ``t_s``, °C
        (:meth:`PowerSystem.inlet_C <genthermal.schedule.power_system.PowerSystem.inlet_C>`).
    """

    generator_names: tuple
    limit_C: float
    rated_current_A: float
    rest_current_A: float
    current_limit_A: float
    T_ambient_C: float
    power_factor: float
    input_names: tuple
    output_names: tuple
    role: Any
    inlet_C: Callable

    @property
    def n_generators(self) -> int:
        """Number of generators."""
        return len(self.generator_names)


@dataclasses.dataclass(frozen=True)
class TruePlants:
    """The true plants of a power system, as a model plant flies them.

    Attributes
    ----------
    n_generators : int
    model : callable
        ``model(generator, fault_indices=())``: the true plant model with those faults.
    faults_known_at : callable
        ``faults_known_at(t_s)``: indices of the faults started at ``t_s`` (s).
    switches : callable
        ``switches(generator)``: the plant before any fault and its ``(onset_s, model)`` switches.
    """

    n_generators: int
    model: Callable
    faults_known_at: Callable
    switches: Callable
