"""Test data with a hidden physical effect: a known answer for the discovery loop.

:func:`make_hidden_effect_case` injects a catalogue effect into a mission run of the plant from an
onset (design properties from the start) and reads the run through the rig's noisy sensors
(:func:`genthermal.synth.synthesize`); a seeded draw gives random cases (:class:`HiddenEffectCase`, :class:`Injection`). The ``unbalance``
option adds a single-phase load that tells phase-local losses from balanced ones. Method:
``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Mapping, Sequence

import numpy as np
import pandas as pd

from ..design import linear_design_model
from ..effects import CATALOGUE, Effect, apply_effect, get_effect
from ..errors import InputError
from ..machines import build_model
from ..mission import load_mission
from ..model import ThermalModel
from ..simulate import simulate
from ..synth import THESIS_NOISE_VARIANCE_K2, synthesize
from .phase_winding import phase_resolved as split_by_phase

#: Missions hidden-effect cases are drawn on.
MISSIONS = ("thesis_fig_7_7", "varying_load")
#: Effects that are modelling choices of the linear design model: present from the start.
MODEL_SIMPLIFICATIONS = ("copper_resistance_temperature", "quadratic_copper_loss")
ONSET_RANGE = (0.15, 0.60)
#: Period of the single-phase load of the ``unbalance`` option, s (on for the second half).
UNBALANCE_PERIOD_S = 3600.0
ACTIVITY_RANGE = (0.6, 1.4)


@dataclasses.dataclass(frozen=True)
class Injection:
    """One injected effect: catalogue name, parameter values, onset (s from the start)."""

    effect: str
    values: dict
    onset_s: float = 0.0


@dataclasses.dataclass
class HiddenEffectCase:
    """Synthetic measurements with known injected effects.

    Attributes
    ----------
    data : pandas.DataFrame
        The record in the CSV schema of :mod:`genthermal.measurements`.
    injections : list of Injection
        The ground truth (empty: a healthy machine).
    plant : ThermalModel
        The model the data came from, without the injections.
    mission : str
    dt_s : float
    seed : int
    noise_var : (float, float)
        Winding and iron sensor noise variances, K².
    unbalance : float
        Extra current of phase u while the single-phase load is on (relative).
    """

    data: pd.DataFrame
    injections: list
    plant: ThermalModel
    mission: str
    dt_s: float
    seed: int
    noise_var: tuple
    unbalance: float = 0.0

    @property
    def noise_std(self) -> float:
        r"""Noise standard deviation of the compared signals, K: the winding temperature is the mean
        of three sensors, :math:`\sigma = \sqrt{(\sigma_w^2/3 + \sigma_i^2)/2}`."""
        winding, iron = self.noise_var
        return math.sqrt((winding / 3.0 + iron) / 2.0)

    def truth(self) -> dict:
        """JSON-ready ground truth."""
        return {"effects": [dataclasses.asdict(i) for i in self.injections], "plant": self.plant.name,
                "mission": self.mission, "dt_s": self.dt_s, "seed": self.seed, "noise_var_K2": list(self.noise_var),
                "noise_std_K": self.noise_std, "unbalance": self.unbalance}


def plant_for(effect: str | None, nonlinear: ThermalModel | None = None) -> ThermalModel:
    """The nonlinear model if it can take ``effect``, else its linear design model."""
    nonlinear = build_model() if nonlinear is None else nonlinear
    if effect is None or get_effect(effect).unavailable_reason(nonlinear) is None:
        return nonlinear
    return linear_design_model(nonlinear)


def random_injection(effect: str, duration_s: float, rng: np.random.Generator,
                     catalogue: Mapping[str, Effect] | None = None) -> Injection:
    """Draw clearly active values and an onset for ``effect`` (looked up in ``catalogue``, default
    the registered one; see the module docstring)."""
    values = {}
    for p in (get_effect(effect) if catalogue is None else catalogue[effect]).parameters:
        u = rng.uniform(*ACTIVITY_RANGE)
        typical = p.typical if p.typical is not None else p.upper
        value = typical ** u if p.neutral == 1.0 else p.neutral + u * (typical - p.neutral)
        values[p.name] = float(np.clip(value, p.lower, p.upper))
    onset = 0.0 if effect in MODEL_SIMPLIFICATIONS else float(rng.uniform(*ONSET_RANGE) * duration_s)
    if (get_effect(effect) if catalogue is None else catalogue[effect]).from_start:
        onset = 0.0  # a design property (drawn all the same, so the later draws stay as they were)
    return Injection(effect, values, onset)


def inject(plant: ThermalModel, injections: Sequence[Injection], inputs: pd.DataFrame, seed: int,
           noise_var=THESIS_NOISE_VARIANCE_K2, phase_resolved: bool = False,
           catalogue: Mapping[str, Effect] | None = None) -> pd.DataFrame:
    """Noisy record of ``plant`` on ``inputs`` with ``injections`` switched on at their onsets.

    With ``phase_resolved``, the plant's slot winding is one node per phase
    (:func:`genthermal.diagnose.phase_winding.phase_resolved`, taken after the effects) and each
    ``T_winding_<phase>`` column reads its own phase node. The injected effects are looked up by
    name in ``catalogue`` (default: the registered catalogue), e.g. the open-search library
    (:func:`genthermal.diagnose.open_search.heat_flow_library`)."""
    catalogue = CATALOGUE if catalogue is None else catalogue
    dt_s = float(inputs["time_s"].iloc[1] - inputs["time_s"].iloc[0])
    # the outlet PT100 is a channel of the iron PT100s kind: it shares their variance
    record = synthesize(plant, inputs, dt_s=dt_s, seed=seed, noise_var=(*noise_var, noise_var[-1]))
    if not injections and not phase_resolved:
        return record
    view = split_by_phase if phase_resolved else (lambda model: model)
    switches, model = [], plant
    for injection in sorted(injections, key=lambda i: i.onset_s):
        model = apply_effect(model, catalogue[injection.effect], provenance="assumed", source="hidden-effect test data",
                             **injection.values)
        switches.append((float(inputs["time_s"].iloc[0] + injection.onset_s), view(model)))
    healthy = simulate(plant, inputs)  # what the record was synthesized from
    faulty = simulate(view(plant), inputs, switches=switches)
    changed = record.copy()
    interface = plant.spec.interface
    sensors = [*interface.sensors, *([interface.outlet_sensor] if interface.outlet_sensor else [])]
    for sensor in sensors:
        for column in sensor.columns:
            output = column if column in faulty else sensor.output  # a phase-resolved plant reads each phase
            if column in record and output in faulty and sensor.output in healthy:
                changed[column] += faulty[output] - healthy[sensor.output]
    return changed


def make_hidden_effect_case(effects: Sequence[str | Injection] | str | None = "random",
                            mission: str = "thesis_fig_7_7", dt_s: float = 10.0, seed: int = 0,
                            noise_var=THESIS_NOISE_VARIANCE_K2, plant: ThermalModel | None = None,
                            unbalance: float = 0.0, phase_resolved: bool = False,
                            catalogue: Mapping[str, Effect] | None = None) -> HiddenEffectCase:
    """Build a hidden-effect test case.

    Parameters
    ----------
    effects : "random", None, str, or sequence of str / Injection
        ``"random"``: one effect drawn from those the nonlinear plant can take; ``None`` or ``[]``:
        healthy data; names get random values and onsets; Injections are used as given.
    mission : str
        Shipped mission name or YAML path (:data:`MISSIONS` are the usual ones).
    dt_s : float
        Sample period, s.
    seed : int
        Seeds the effect, its values, its onset and the sensor noise.
    noise_var : (float, float)
        Winding and iron sensor noise variances, K².
    plant : ThermalModel, optional
        The plant; default :func:`plant_for` the (first) effect.
    unbalance : float
        Phase u carries ``1 + unbalance`` times its mission current while the single-phase load
        is on (0: balanced, the missions as written).
    phase_resolved : bool
        Simulate the plant with one slot-winding node per phase
        (:mod:`genthermal.diagnose.phase_winding`): each phase sensor reads its own phase, so an
        effect in one phase (a shorted turn) shows as a spread between the phase readings.
    catalogue : mapping of str to Effect, optional
        Where the effect names are looked up (default: the registered catalogue); the open-search
        library gives records with library terms (their Injections given with values).
    """
    rng = np.random.default_rng(seed)
    nonlinear = build_model() if plant is None else plant
    if effects == "random":
        choices = [n for n, e in CATALOGUE.items() if e.unavailable_reason(nonlinear) is None]
        effects = [choices[int(rng.integers(len(choices)))]]
    elif effects is None:
        effects = []
    elif isinstance(effects, str):
        effects = [effects]
    names = [e.effect if isinstance(e, Injection) else e for e in effects]
    for name in names:
        if catalogue is None:
            get_effect(name)
        elif name not in catalogue:
            raise InputError("effect", name, f"not in the catalogue given: {', '.join(catalogue)}")
    if plant is None:
        plant = plant_for(names[0] if names else None, nonlinear) if catalogue is None else nonlinear
    inputs = load_mission(mission).to_inputs(dt_s)
    if unbalance:
        elapsed = inputs["time_s"] - inputs["time_s"].iloc[0]
        inputs[plant.spec.interface.generator.phase_inputs[0]] *= 1.0 + unbalance * ((elapsed % UNBALANCE_PERIOD_S) >= UNBALANCE_PERIOD_S / 2)
    duration = float(inputs["time_s"].iloc[-1] - inputs["time_s"].iloc[0])
    injections = [e if isinstance(e, Injection) else random_injection(e, duration, rng, catalogue) for e in effects]
    for injection in injections:
        if not 0.0 <= injection.onset_s <= duration:
            raise InputError(f"{injection.effect}.onset_s", injection.onset_s, f"must lie in [0, {duration:g}] s")
    data = inject(plant, injections, inputs, seed, noise_var, phase_resolved, catalogue)
    return HiddenEffectCase(data, injections, plant, mission, float(dt_s), seed, tuple(noise_var), unbalance)
