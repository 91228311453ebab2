"""Design the short rig test that tells two look-alike explanations apart.

:func:`separating_experiment` chooses, block by block, a test mission of at most 30 minutes (a
load level and a phase share per block, within the machine's ratings) that maximises the
separation of two candidate explanations after each is refitted on the test, in units of the
sensor noise, and returns a :class:`SeparatingExperiment`. Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import itertools
from pathlib import Path
from typing import Mapping

import numpy as np
import yaml

from ..conditions import Action
from ..effects import CATALOGUE, Effect
from ..errors import InputError
from ..mission import Mission
from ..model import ThermalModel
from ..outputs import write_text
from ..simulate import simulate

BLOCKS = 6
BLOCK_MIN = 5.0
LOAD_PERCENTS = (30.0, 60.0, 100.0)
PHASE_SHARES = ((1.0, 1.0, 1.0), (1.0, 0.2, 0.2), (0.2, 1.0, 0.2), (0.2, 0.2, 1.0))
#: Sample period of the predicted test, s.
DT_S = 10.0


@dataclasses.dataclass
class SeparatingExperiment:
    """A designed test and what it predicts.

    Attributes
    ----------
    mission : Mission
        The load profile (write it with :meth:`write`).
    candidates : tuple of str
        The two explanations compared (``"A"`` or ``"A + B"``).
    separation_sigma : float
        Largest predicted difference of a sensor output, in units of the noise.
    at_time_min, sensor : float, str
        Where that difference is largest.
    peak_winding_C : float
        Highest winding temperature either candidate predicts, °C.
    """

    mission: Mission
    candidates: tuple
    separation_sigma: float
    at_time_min: float
    sensor: str
    peak_winding_C: float

    def to_dict(self) -> dict:
        return {"candidates": list(self.candidates), "separation_sigma": self.separation_sigma,
                "at_time_min": self.at_time_min, "sensor": self.sensor, "peak_winding_C": self.peak_winding_C,
                "duration_min": self.mission.duration_s / 60.0, "scenario": self.mission.to_dict()}

    def write(self, path) -> Path:
        """Write the test as a scenario YAML file (``genthermal simulate``/``synth`` read it)."""
        return write_text(path, yaml.safe_dump(self.mission.to_dict(), sort_keys=False, allow_unicode=True))


def _candidate_model(model: ThermalModel, explanation: Mapping[str, Mapping[str, float]],
                     catalogue: Mapping[str, Effect]) -> ThermalModel:
    for name, values in explanation.items():
        model = model.with_effect(catalogue[name], **values)
    return model


def _step(explanation, effect: str, parameter: str, catalogue) -> float:
    """1 % of the parameter's value (or of its typical value at 0), downwards at the upper bound."""
    spec = next(p for p in catalogue[effect].parameters if p.name == parameter)
    value = explanation[effect][parameter]
    step = 0.01 * (abs(value) or abs(spec.typical or 1.0))
    return -step if value + step > spec.upper else step


def _stepped(explanation, effect: str, parameter: str, catalogue) -> dict:
    """``explanation`` with one parameter increased by :func:`_step`."""
    changed = {name: dict(values) for name, values in explanation.items()}
    changed[effect][parameter] += _step(explanation, effect, parameter, catalogue)
    return changed


def _mission(blocks, rated_A: float, T_inlet: float, label: str) -> Mission:
    actions = [Action(None, BLOCK_MIN * 60.0, load_percent=load, phase_share=share) for load, share in blocks]
    return Mission(f"separate_{label}", actions, rated_current_A=rated_A, T_inlet_C=T_inlet, T_ambient_C=T_inlet,
                   description=f"Designed test that separates {label.replace('_vs_', ' from ')}: "
                   "genthermal.diagnose.experiment.")


def separating_experiment(model: ThermalModel, first: Mapping[str, Mapping[str, float]],
                          second: Mapping[str, Mapping[str, float]], noise_K: float,
                          catalogue: Mapping[str, Effect] = CATALOGUE, T_inlet_C: float = 20.0) -> SeparatingExperiment:
    """Design the test of the module docstring.

    Parameters
    ----------
    model : ThermalModel
        The model without the candidate effects.
    first, second : mapping
        Each explanation: effect name → fitted parameter values.
    noise_K : float
        Sensor noise standard deviation, K (> 0).
    catalogue : mapping of str to Effect
        Where the effect names are looked up.
    T_inlet_C : float
        Inlet and ambient temperature of the test, °C (the machine starts soaked at it).

    Returns
    -------
    SeparatingExperiment
    """
    if not (np.isfinite(noise_K) and noise_K > 0):
        raise InputError("noise_K", noise_K, "must be a positive noise standard deviation, K")
    for explanation in (first, second):
        for name in explanation:
            if name not in catalogue:
                raise InputError("effect", name, f"not in the catalogue: {', '.join(catalogue)}")
    explanations = (first, second)
    models = [_candidate_model(model, e, catalogue) for e in explanations]
    # each candidate with one parameter stepped by 1 % of its value (or of its effect's typical value)
    stepped = [[(_candidate_model(model, _stepped(e, name, p, catalogue), catalogue), _step(e, name, p, catalogue))
                for name in e for p in e[name]] for e in explanations]
    rated = model.spec.rated_current_A
    label = "_vs_".join("+".join(e) for e in (first, second))
    options = list(itertools.product(LOAD_PERCENTS, PHASE_SHARES))
    outputs = list(model.output_names)
    generator = model.spec.interface.generator
    limited = generator.limited_sensor
    theta_max = model.spec.interface.limits_C[limited]

    def evaluate(blocks):
        inputs = _mission(blocks, rated, T_inlet_C, label).to_inputs(DT_S, generator)
        runs = [simulate(m, inputs, x0=T_inlet_C)[outputs].to_numpy().T for m in models]
        peak = max(float(r[outputs.index(limited)].max()) for r in runs)
        best = None
        for refitted, truth in ((1, 0), (0, 1)):
            columns = [(simulate(m, inputs, x0=T_inlet_C)[outputs].to_numpy().T - runs[refitted]) / step
                       for m, step in stepped[refitted]]
            difference = runs[truth] - runs[refitted]
            if columns:
                J = np.column_stack([c.ravel() for c in columns])
                shift, *_ = np.linalg.lstsq(J, difference.ravel(), rcond=None)
                difference = difference - (J @ shift).reshape(difference.shape)
            sensor, sample = np.unravel_index(int(np.argmax(np.abs(difference))), difference.shape)
            score = float(abs(difference[sensor, sample]) / noise_K)
            if best is None or score < best[0]:
                best = (score, float(inputs["time_s"].iloc[sample] / 60.0), outputs[sensor], peak)
        return best

    chosen, best = [], None
    for block in range(BLOCKS):
        scored = []
        for option in options:
            result = evaluate(chosen + [option] * (BLOCKS - block))
            if result[3] <= theta_max:
                scored.append((result[0], option, result))
        if not scored:
            raise InputError("experiment", label, f"no test within the ratings keeps {limited} below {theta_max:g} °C")
        _, option, best = max(scored, key=lambda item: item[0])
        chosen.append(option)
    separation, at_min, sensor, peak = best
    return SeparatingExperiment(_mission(chosen, rated, T_inlet_C, label), (" + ".join(first), " + ".join(second)),
                                separation, at_min, sensor, peak)
