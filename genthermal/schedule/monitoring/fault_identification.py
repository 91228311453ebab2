"""Identification of a fault from the in-flight record with diagnose's effect search (recalibrate
on the healthiest generator, then search the alarmed one's record over :data:`FAULT_EFFECTS`).
Method: docs/guide/flight-methods.md.
"""

from __future__ import annotations

import dataclasses
import time
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

if TYPE_CHECKING:
    from .monitor import DetectionSettings

#: Catalogue effects the manager watches for (heating faults).
FAULT_EFFECTS = ("coolant_flow_reduction", "phase_short_circuit", "end_winding_stray_loss", "excitation_iron_loss")


#: Suffix of a catalogue variant whose shape parameters are fitted (:func:`flight_catalogue`).
FREE_SHAPE_SUFFIX = "+shape"


def flight_catalogue(effects=FAULT_EFFECTS) -> dict:
    """The candidate effects of the in-flight identification: the registered catalogue's
    ``effects`` and, for each one with shape parameters, a variant named
    ``name + FREE_SHAPE_SUFFIX`` that fits them too (the blockage's convection exponent
    ``n_flow``, module docstring). Both compete by ΔBIC, so the extra parameter is kept only when
    the record asks for it: on the detection benchmark's blockages of the default exponent the
    free variant alone sized one k_flow 0.37 as 0.66 (n_flow 1.5) seven minutes after the onset.
    A variant's values name the registered effect's parameters (:func:`registered_effect_name`).

    Parameters
    ----------
    effects : sequence of str
        Registered effect names.

    Returns
    -------
    dict
        Candidate name → :class:`~genthermal.effects.Effect`.
    """
    from ...effects import get_effect

    catalogue = {}
    for name in effects:
        effect = get_effect(name)
        catalogue[name] = effect
        if effect.shape_parameters:
            catalogue[name + FREE_SHAPE_SUFFIX] = dataclasses.replace(
                effect, name=name + FREE_SHAPE_SUFFIX, parameters=effect.all_parameters, shape_parameters=())
    return catalogue


def registered_effect_name(candidate: str) -> str:
    """The registered effect of a :func:`flight_catalogue` candidate (its variant suffix dropped)."""
    return candidate[:-len(FREE_SHAPE_SUFFIX)] if candidate.endswith(FREE_SHAPE_SUFFIX) else candidate


def severe_end(interval, neutral: float) -> float:
    """The end of ``interval`` (a ParameterInterval) farthest from ``neutral`` on the side of its
    estimate, or the estimate where that end is the parameter's bound or no end lies on that side."""
    direction = np.sign(interval.estimate - neutral)
    ends = [(end, bound) for end, bound in ((interval.low, interval.at_lower), (interval.high, interval.at_upper))
            if direction and np.sign(end - neutral) == direction]
    if not ends:
        return interval.estimate
    end, bound = max(ends, key=lambda item: abs(item[0] - neutral))
    return interval.estimate if bound else end


@dataclasses.dataclass
class Identification:
    """An effect identified in flight.

    Attributes
    ----------
    generator : int
    detected_at_s : float
        Time of the alarm, s.
    effect : str or None
        Identified effect, None when nothing significant explains the record.
    values : dict
        Fitted parameters of the effect.
    onset_s : float or None
        Fitted onset, s since the mission start.
    delta_bic : float or None
        ΔBIC of the effect (confidence: below -10 is very strong evidence).
    rmse_before_K, rmse_after_K : float or None
        Fit of the record without and with the effect, K.
    runner_up : str or None
        Second-ranked effect and its ΔBIC gap, for ambiguity.
    equivalent : list of str
        Other effects that explain the record as well (within ``equivalent_delta_bic``).
    solve_s : float
        Wall-clock time of the identification, s.
    intervals : dict
        Parameter name → :class:`~genthermal.diagnose.interval.ParameterInterval` of each
        parameter the identification fitted (a ``+shape`` variant's shape parameters included).
    """

    generator: int
    detected_at_s: float
    effect: str | None
    values: dict
    onset_s: float | None
    delta_bic: float | None
    rmse_before_K: float | None
    rmse_after_K: float | None
    runner_up: str | None
    solve_s: float
    equivalent: list = dataclasses.field(default_factory=list)
    intervals: dict = dataclasses.field(default_factory=dict)

    @property
    def believed_values(self) -> dict:
        """The values the manager believes (docs/guide/flight-methods.md, "Uncertainty"): each
        switching parameter of the registered effect at the end of its interval farthest from its
        neutral value on the side of its estimate (the most severe fault of that direction the
        record allows), or at its estimate where that end is the parameter's bound (the record
        does not bound the fault: a blockage sized k_flow 0.24 in 0.05-2.0, both ends bounds, whose
        end farthest from the neutral 1 is a flow doubled); the shape parameters (``n_flow``,
        fitted by the ``+shape`` variant: lower is not milder or more severe by itself) at their
        estimate."""
        from ...effects import get_effect

        if not self.effect:
            return {}
        believed = dict(self.values)
        for parameter in get_effect(self.effect).parameters:  # the registered effect's: not its shape
            interval = self.intervals.get(parameter.name)
            if interval is not None:
                believed[parameter.name] = severe_end(interval, parameter.neutral)
        return believed

    @property
    def effects(self) -> tuple:
        """The belief as ``((effect, ((name, value), ...)),)`` at :attr:`believed_values` (empty when
        none was identified)."""
        return ((self.effect, tuple(self.believed_values.items())),) if self.effect else ()

    def to_dict(self, names) -> dict:
        """JSON entry: generator name, effect, parameters (estimates), the values believed, onset
        and confidence (with each parameter's interval)."""
        return {"generator": names[self.generator], "detected_at_s": self.detected_at_s, "effect": self.effect,
                "parameters": self.values, "believed": self.believed_values, "onset_s": self.onset_s,
                "confidence": {"delta_bic": self.delta_bic, "rmse_before_K": self.rmse_before_K,
                               "rmse_after_K": self.rmse_after_K, "runner_up": self.runner_up,
                               "equivalent": list(self.equivalent),
                               "intervals": {n: i.to_dict() for n, i in self.intervals.items()}},
                "solve_s": self.solve_s}


def confirms(new, believed, tolerance: float) -> bool:
    """True when the effects ``new`` (``((name, ((parameter, value), ...)),)``, registered names)
    are ``believed`` with every parameter within ``tolerance`` times the larger of the believed
    value and the parameter's typical value (``DetectionSettings.confirm_tolerance``)."""
    from ...effects import get_effect

    if len(new) != len(believed) or not new:
        return False
    for (name, values), (old_name, old_values) in zip(new, believed):
        values, old_values = dict(values), dict(old_values)
        if name != old_name or set(values) != set(old_values):
            return False
        typical = {p.name: abs(p.typical or 0.0) for p in get_effect(name).all_parameters}
        if any(abs(values[k] - old_values[k]) > tolerance * max(abs(old_values[k]), typical.get(k, 0.0))
               for k in values):
            return False
    return True


def implausible(candidate) -> str | None:
    """Why a candidate of the flight's search (a ``+shape`` variant too) is no finding: its values
    or onset judged by its registered effect (:meth:`~genthermal.effects.Effect.implausible`: a
    parameter outside its plausible range, a design property begun in flight), or None."""
    from ...effects import get_effect

    return get_effect(registered_effect_name(candidate.effect)).implausible(candidate.values, candidate.onset_s)


def identify_fault(model, record: pd.DataFrame, generator: int, detected_at_s: float,
                   settings: DetectionSettings, error_model=None) -> Identification:
    """Identify the effect behind an alarm from the record (module docstring): the best-ranked
    significant effect of diagnose's search whose onset is at most ``max_onset_lead_s`` before
    the alarm and that makes the machine run hotter than the model, with the effects equivalent
    to it. An effect fitted on the cooling side of its neutral value (e.g. a "blockage" with
    ``k_flow`` > 1, more coolant than designed) is the model's error, not a fault: believing it
    made the planner load a healthy generator that had taken over shed load 1.7 K past θmax
    (``tests/test_closed_loop_shed.py``). Sensor faults are the sensor watch's
    (:mod:`genthermal.schedule.monitoring.sensor_watch`), so the search runs without its sensor screen. Each
    parameter of the effect carries its interval (module docstring, "Uncertainty").

    With ``error_model`` (an :class:`~genthermal.diagnose.error_model.ErrorModel` of ``model``'s
    sensors, :mod:`~genthermal.schedule.monitoring.flight_error`) every candidate is scored on
    effective samples (:class:`~genthermal.diagnose.error_model.WhitenedBIC`) and its practical
    tests are taken against the discrepancy floor, as offline; without it, as if the model's
    error were white sensor noise. Either way a candidate that is :func:`implausible` is no
    finding, and the next plausible one is taken."""
    from ...diagnose.catalogue import Catalogue
    from ...diagnose.discover import series_for
    from ...diagnose.discovery import Discovery
    from ...diagnose.fitter import OnsetFitter

    started = time.perf_counter()
    catalogue = flight_catalogue(settings.fault_effects)
    if error_model is not None:
        error_model.check_sensors(model.output_names)
    series = series_for(model, record, settings.identify_dt_s)
    discovery = Discovery(Catalogue.of(catalogue), fitter=OnsetFitter(pairs=False),  # one fault at a time
                          design_experiment=False, sensor_faults=False,  # no rig test in flight
                          error_model=error_model)
    diagnosis = discovery.fit(model, series)
    first = diagnosis.iterations[0]
    ranked = first.ranked
    earliest = min(detected_at_s - settings.max_onset_lead_s, settings.late_onset_s)

    def heats(candidate) -> bool:
        after = slice(candidate.onset_index, None)
        return bool(np.nanmean(candidate.predicted[:, after] - first.predicted_before[:, after]) > 0.0)

    admissible = [c for c in ranked if c.onset_s >= earliest and heats(c) and implausible(c) is None]
    best = admissible[0] if admissible and admissible[0].significant else None
    effect = None if best is None else registered_effect_name(best.effect)
    # the other explanations: other effects (a variant of the same effect is the same explanation)
    others = [c for c in admissible if registered_effect_name(c.effect) != effect]
    runner_up = (f"{registered_effect_name(others[0].effect)} "
                 f"(ΔBIC +{others[0].delta_bic - admissible[0].delta_bic:.0f})" if best is not None and others else None)
    elapsed = time.perf_counter() - started
    if best is None:
        return Identification(generator, detected_at_s, None, {}, None,
                              float(admissible[0].delta_bic) if admissible else None,
                              diagnosis.iterations[0].rmse_before, None, runner_up, elapsed)
    equivalent = list(dict.fromkeys(registered_effect_name(c.effect) for c in others
                                    if c.delta_bic - best.delta_bic <= settings.equivalent_delta_bic))
    intervals = parameter_intervals(model, series, catalogue, best, settings.interval_level, discovery.memo)
    return Identification(generator, detected_at_s, effect, dict(best.values), float(best.onset_s),
                          float(best.delta_bic), float(best.rmse_before), float(best.rmse_after), runner_up,
                          time.perf_counter() - started, equivalent, intervals)


def parameter_intervals(model, series, catalogue, candidate, level: float, memo: dict | None = None) -> dict:
    """Interval of each parameter of ``candidate`` (a first-round candidate of the search of
    ``model`` on ``series`` over ``catalogue``; module docstring, "Uncertainty"); ``memo``
    the search's (:attr:`Discovery.memo <genthermal.diagnose.discovery.Discovery.memo>`), whose
    simulators it reuses."""
    from ...diagnose.interval import fitted_intervals
    from ...diagnose.search import EffectSearch

    search = EffectSearch(model, series, cache=memo, catalogue=catalogue).fit_found()
    return fitted_intervals(search, candidate, level)
