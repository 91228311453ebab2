"""Discover the physical effect a model lacks: fit every catalogue effect, rank by BIC, decide.

:func:`diagnose` fits every effect of :data:`genthermal.effects.CATALOGUE` the model lacks with
its onset, ranks them by ΔBIC and returns a :class:`Diagnosis`: the ranking, the verdict (an
effect, a pair ``"A + B"`` or ``"none"``), what is still unexplained, look-alikes with the rig
test that separates them, and the improved model. An effect is significant when it passes the
four tests of :func:`passes_tests`. Guide: ``docs/guide/calibration-diagnosis.md``; the rules:
``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Mapping, Sequence

import numpy as np

from ..effects import CATALOGUE, FROM_START_TOLERANCE_S, Effect
from ..errors import InputError
from ..machines.interface import Role
from ..model import ThermalModel
from .compare import MeasuredSeries, measured_series
from .design_scale import DesignSensorScale
from .experiment import SeparatingExperiment
from .joint import JointCandidate
from .residual import correlation
from .search import Candidate, EffectSearch, model_with_effects

DELTA_BIC_LIMIT = -10.0
MIN_RMSE_REDUCTION = 0.10
NOISE_FLOOR_FACTOR = 1.2
MIN_EXCESS_EXPLAINED = 0.5
#: Two onsets of a pair this close (s), both during the record, are one change (:func:`one_change`).
SAME_ONSET_S = 600.0
#: Parameters calibrated on a healthy baseline by default: the losses and the convection the
#: thesis does not give (``assumed`` in the machine) and the fitted winding conductivity.
DEFAULT_BASELINE_PARAMETERS = ("R0", "P_iron", "h_end_air", "h_top_air", "k_cr")


def passes_tests(rmse_before: float, rmse_after: float, delta_bic: float, noise: float,
                 evidence_limit: float = DELTA_BIC_LIMIT) -> bool:
    """The four tests of the module docstring for a change from ``rmse_before`` to ``rmse_after``
    (K) at a criterion change ``delta_bic``, with sensor noise ``noise`` (K); the change must be
    below ``evidence_limit`` (the criterion's, -10 for BIC)."""
    noise = noise if np.isfinite(noise) else 0.0
    return bool(delta_bic < evidence_limit
                and rmse_after <= (1 - MIN_RMSE_REDUCTION) * rmse_before
                and rmse_before > NOISE_FLOOR_FACTOR * noise
                and rmse_before ** 2 - rmse_after ** 2 >= MIN_EXCESS_EXPLAINED * (rmse_before ** 2 - noise ** 2))


def implausible_reason(candidate) -> str | None:
    """Why a Candidate or JointCandidate's fitted values are no finding: the first effect fitted
    outside its plausible range, or a design property fitted to begin during the record
    (:meth:`genthermal.effects.Effect.implausible`), or None."""
    onsets = candidate.onsets_s if isinstance(candidate, JointCandidate) else {candidate.effect: candidate.onset_s}
    for name, values in _explanations(candidate).items():
        effect = CATALOGUE.get(name)
        reason = effect.implausible(values, onsets.get(name)) if effect is not None else None
        if reason:
            return reason
    return None


def is_significant(candidate: Candidate, noise: float, evidence_limit: float = DELTA_BIC_LIMIT,
                   design: DesignSensorScale | None = None) -> bool:
    """The four tests of the module docstring, against the model without the candidate; with
    ``design`` (phase sensors fitted one by one), the practical tests pass on every sensor or on
    the design sensors (:mod:`genthermal.diagnose.design_scale`). A candidate fitted outside its
    plausible range (:func:`implausible_reason`) is never significant."""
    if implausible_reason(candidate) is not None:
        return False
    if passes_tests(candidate.rmse_before, candidate.rmse_after, candidate.delta_bic, noise, evidence_limit):
        return True
    return design is not None and passes_tests(design.rmse_before, design.rmse(candidate.predicted),
                                               candidate.delta_bic, design.noise, evidence_limit)


def one_change(pair: JointCandidate) -> bool:
    """True when both effects of ``pair`` begin during the record within :data:`SAME_ONSET_S` of each
    other: two independent faults do not start in the same minutes, so such a pair stands in for one
    change the catalogue lacks (the residual it leaves is then the open search's), not two findings."""
    first, second = (pair.onsets_s[name] for name in pair.effects)
    return same_change(first, second)


def same_change(first_s: float, second_s: float) -> bool:
    """Two onsets (s into the record) that are one change: both during the record (after
    :data:`~genthermal.effects.FROM_START_TOLERANCE_S`) and within :data:`SAME_ONSET_S`."""
    return min(first_s, second_s) > FROM_START_TOLERANCE_S and abs(first_s - second_s) <= SAME_ONSET_S


def misfit_of(candidate: Effect, nearest: Effect) -> bool:
    """True when ``candidate``, beginning with the catalogue's ``nearest`` effect (:func:`same_change`),
    describes that change's misfit: it acts on a part or input the nearest effect acts on (a role
    both need: a blockage's misfit lies in the air streams or the convection, a short's in the slot
    winding). A term on another part beginning in the same minutes would be a second fault starting
    with the first, which :func:`one_change` refuses for pairs."""
    return bool(set(candidate.needs) & set(nearest.needs))


def choose_pair(pairs: Sequence[JointCandidate], singles: Sequence[Candidate], noise: float,
                evidence_limit: float = DELTA_BIC_LIMIT, design: DesignSensorScale | None = None) -> JointCandidate | None:
    """The best-ranked pair that passes the four tests against the model without effects, against
    each of its two effects alone and against the best single effect (each effect must earn its
    place, and the pair must beat the best answer with one effect); None if no pair does. Pairs
    fitted outside their plausible range or of :func:`one_change` are passed over.

    With ``design`` (phase sensors fitted one by one), each comparison passes when it passes on
    every sensor or on the design sensors, the phase sensors averaged
    (:mod:`genthermal.diagnose.design_scale`): the phase spread's noise, which no effect common
    to all phases can explain, would otherwise dilute such an effect's share. The evidence is
    always the ΔBIC on every sensor."""
    by_name = {c.effect: c for c in singles}
    best_single = min(singles, key=lambda c: c.delta_bic)

    def beats(pair: JointCandidate, rival: Candidate | None) -> bool:
        """``pair`` passes the tests against ``rival`` (None: the model without effects)."""
        delta = pair.delta_bic - (rival.delta_bic if rival else 0.0)
        before = rival.rmse_after if rival else pair.rmse_before
        if passes_tests(before, pair.rmse_after, delta, noise, evidence_limit):
            return True
        return design is not None and passes_tests(design.rmse(rival.predicted) if rival else design.rmse_before,
                                                   design.rmse(pair.predicted), delta, design.noise, evidence_limit)

    for pair in sorted(pairs, key=lambda p: p.delta_bic):
        if implausible_reason(pair) is not None or one_change(pair):
            continue
        rivals = [None] + [by_name[e] for e in pair.effects] + [best_single]
        if all(beats(pair, rival) for rival in rivals):
            return pair
    return None


def series_for(model: ThermalModel, data, dt_s: float | None = None) -> MeasuredSeries:
    """Measurements of ``data`` on a uniform grid for ``model``'s outputs."""
    return measured_series(data, dt_s, model.output_names, model.spec.interface)


@dataclasses.dataclass
class Iteration:
    """One round of the discovery loop: the ranking and what was added.

    Attributes
    ----------
    ranked : list of Candidate
        Best ΔBIC first.
    rmse_before : float
        RMSE of the model at the start of the round (found effects refitted), K.
    predicted_before : numpy.ndarray
        Its outputs, (n_outputs, N), °C.
    added : Candidate or None
        The significant best candidate, if any (None when a pair was added).
    explanation : str
    pairs : list of JointCandidate
        Pairs fitted jointly in this round, best ΔBIC first (first round only, when one effect
        leaves more than noise).
    added_pair : JointCandidate or None
        The pair chosen by :func:`choose_pair`, if any.
    """

    ranked: list
    rmse_before: float
    predicted_before: np.ndarray
    added: Candidate | None
    explanation: str
    pairs: list = dataclasses.field(default_factory=list)
    added_pair: JointCandidate | None = None

    @property
    def added_effects(self) -> list[str]:
        """Names of the effects this round added."""
        if self.added_pair:
            return list(self.added_pair.effects)
        return [self.added.effect] if self.added else []

    @property
    def rmse_after(self) -> float:
        """RMSE at the end of the round, K."""
        chosen = self.added_pair or self.added
        return chosen.rmse_after if chosen else self.rmse_before

    @property
    def predicted_after(self) -> np.ndarray:
        """Outputs at the end of the round, (n_outputs, N), °C."""
        chosen = self.added_pair or self.added
        return chosen.predicted if chosen else self.predicted_before

    def to_dict(self) -> dict:
        return {"rmse_before": self.rmse_before, "added": " + ".join(self.added_effects) or None,
                "rmse_after": self.rmse_after, "explanation": self.explanation,
                "ranked": [c.to_dict() for c in self.ranked], "pairs": [p.to_dict() for p in self.pairs]}


@dataclasses.dataclass
class Diagnosis:
    """Result of :func:`diagnose`.

    Attributes
    ----------
    model : ThermalModel
        The model diagnosed (after the baseline calibration, if any).
    series : MeasuredSeries
    noise_std : float
        Sensor noise estimated from the data, K.
    iterations : list of Iteration
    found : list of FoundEffect
        Effects added (one or a pair without ``iterate``; the verdict), with their final values.
    calibration : CalibrationResult or None
        The baseline calibration.
    residual : dict
        :func:`~genthermal.diagnose.residual.residual_tests` of the final model: is something
        still missing, and where and when.
    catalogue : mapping of str to Effect
        The effects searched.
    experiment : SeparatingExperiment or None
        When another explanation fits about as well as the verdict (:func:`look_alike`): the short
        rig test that tells them apart (:mod:`genthermal.diagnose.experiment`).
    criterion : str
        Name of the information criterion that scored the candidates.
    output_names : list of str
        The sensors fitted, rows of ``series.outputs`` (the model's, or those of its phase-resolved
        winding view, :mod:`genthermal.diagnose.phase_winding`, when the record's phases differ).
    error_model : ErrorModel or None
        The calibrated model's error on the baseline (:mod:`genthermal.diagnose.error_model`).
    open_search : dict or None
        The open search run after the catalogue left the residual unexplained
        (:func:`~genthermal.diagnose.open_followup.open_followup`).
    """

    model: ThermalModel
    series: MeasuredSeries
    noise_std: float
    iterations: list
    found: list
    calibration: object = None
    residual: dict = dataclasses.field(default_factory=dict)
    catalogue: Mapping[str, Effect] = dataclasses.field(default_factory=lambda: CATALOGUE)
    experiment: SeparatingExperiment | None = None
    criterion: str = "BIC"
    output_names: list = dataclasses.field(default_factory=list)
    sensor_screen: object = None
    error_model: object = None
    open_search: dict | None = None

    def __post_init__(self):
        self.output_names = list(self.output_names) or list(self.model.output_names)

    @property
    def ranking(self) -> list:
        """The first round's single effects, best criterion change first (list of Candidate)."""
        return self.iterations[0].ranked

    @property
    def sensor_faults(self) -> list:
        """The sensor faults claimed (:class:`~genthermal.diagnose.sensor_faults.SensorHypothesis`);
        the physical verdict is about the record with them corrected."""
        return list(self.sensor_screen.found) if self.sensor_screen is not None else []

    @property
    def verdict(self) -> str:
        """The effect (or ``"A + B"`` pair) added in the first round, or ``"none"``."""
        return " + ".join(self.iterations[0].added_effects) or "none"

    @property
    def unexplained(self) -> bool:
        """True when the residual after the found effects is not sensor noise."""
        return bool(self.residual.get("unexplained", False))

    def improved_model(self) -> ThermalModel:
        """The model with every found effect at its fitted values (provenance ``fitted``)."""
        return model_with_effects(self.model, self.found, source=f"diagnosis on {self.series.source}",
                                  catalogue=self.catalogue)

    def _verdict_profiles(self) -> list:
        """The onset profiles of the first round's verdict (:mod:`~genthermal.diagnose.onset_profile`)."""
        chosen = self.iterations[0].added_pair or self.iterations[0].added
        return list(chosen.onset_profiles) if chosen is not None else []

    @property
    def nearest(self) -> bool:
        """True when the effects found leave the residual unexplained: they are the catalogue's
        nearest effects, not a confident verdict (the open search describes what they miss)."""
        return bool(self.found) and self.unexplained

    def claims(self) -> list:
        """Every claim with its kind (``machine_effect``, ``sensor_fault``, ``unexplained``), what it
        says, its evidence and its confidence (the criterion's change: ``strong`` below twice the
        evidence limit, else ``moderate``; ``nearest`` for effects that leave the residual
        unexplained; ``unexplained`` has the residual's level instead)."""
        claims = []
        rounds = {e: it for it in self.iterations for e in it.added_effects}
        for found in self.found:
            iteration = rounds.get(found.effect, self.iterations[0])
            chosen = iteration.added_pair or iteration.added
            delta = chosen.delta_bic if chosen is not None else float("nan")
            confidence = "nearest" if self.nearest else "strong" if delta < 2 * DELTA_BIC_LIMIT else "moderate"
            claims.append({"kind": "machine_effect", "effect": found.effect, "params": found.values,
                           "onset_s": found.onset_s, "evidence": f"{self.criterion} change {delta:.1f} on the record",
                           "delta_ic": delta, "confidence": confidence})
        for fault in (self.sensor_screen.found if self.sensor_screen is not None else []):
            claims.append({"kind": "sensor_fault", "sensor": fault.fault.sensor, "text": fault.fault.describe(),
                           "evidence": fault.evidence, "delta_ic": fault.delta_bic,
                           "confidence": "strong" if fault.evidence in ("redundancy", "frozen") or
                           fault.delta_bic < 2 * DELTA_BIC_LIMIT else "moderate"})
        if self.unexplained:
            terms = (self.open_search or {}).get("terms", [])
            text = "not explained by the catalogue" if not self.found else (
                f"not explained by the catalogue: {' + '.join(f.effect for f in self.found)}, the nearest catalogue "
                "effect, leaves a residual it does not explain")
            claims.append({"kind": "unexplained", "text": text, "residual": self.residual.get("summary", ""),
                           "evidence": "residual tests", "rmse_K": self.residual.get("rmse_K"),
                           "floor_K": self.residual.get("floor_K"),
                           "open_search_terms": [{k: t[k] for k in ("group", "form", "params", "onset_s", "text")}
                                                 for t in terms],
                           "confidence": "level"})
        return claims

    def to_pandas(self):
        """The claims as a tidy table, one row per claimed size (:func:`~genthermal.diagnose.result_views.claims_frame`).

        Returns
        -------
        pandas.DataFrame
            ``claim`` (index into ``to_dict()["claims"]``), ``kind``, ``subject``, ``quantity``,
            ``size``, ``unit``, ``bound_low``, ``bound_high``, ``onset_s`` (s), ``evidence``,
            ``delta_ic`` and ``confidence``.
        """
        from .result_views import claims_frame

        return claims_frame(self)

    def plot(self, path=None, ax=None):
        """Residual (model − measurement, K) per sensor before the diagnosis and with its found effects.

        Parameters
        ----------
        path : path-like, optional
            PNG file to write the figure to.
        ax : matplotlib.axes.Axes or sequence of Axes, optional
            Draw into this Axes (every sensor) or these (one per sensor) instead of a new figure.

        Returns
        -------
        matplotlib.figure.Figure
        """
        from .result_views import plot_residual_change

        return plot_residual_change(self, path=path, ax=ax)

    def to_dict(self) -> dict:
        """The JSON document of ``genthermal diagnose``."""
        first = self.iterations[0]
        return {
            "model": self.model.name, "data": self.series.source, "samples": int(self.series.time_s.size),
            "dt_s": self.series.dt_s, "noise_std_K": self.noise_std, "criterion": self.criterion,
            "sensors": self.output_names,
            "verdict": self.verdict, "nearest": self.nearest,
            "explanation": first.explanation, "ranked": [c.to_dict() for c in first.ranked],
            "pairs": [p.to_dict() for p in first.pairs],
            "thresholds": {"delta_bic_below": DELTA_BIC_LIMIT, "min_rmse_reduction": MIN_RMSE_REDUCTION,
                           "rmse_before_above_noise_factor": NOISE_FLOOR_FACTOR,
                           "min_excess_variance_explained": MIN_EXCESS_EXPLAINED},
            "found": [{"effect": f.effect, "params": f.values, "onset_s": f.onset_s,
                       "onset_interval_s": list(f.onset_interval_s) if f.onset_interval_s else None}
                      for f in self.found],
            "onset_profiles": [p.to_dict() for p in self._verdict_profiles()],
            "iterations": [it.to_dict() for it in self.iterations],
            "rmse_final": self.iterations[-1].rmse_after,
            "unexplained": self.unexplained, "residual": self.residual,
            "experiment": self.experiment.to_dict() if self.experiment else None,
            "sensor_faults": self.sensor_screen.to_list() if self.sensor_screen is not None else [],
            "sensor_error_limits_K": dict(self.sensor_screen.limits) if self.sensor_screen is not None else {},
            "open_search": self.open_search,
            "refused_sensor_faults": self.sensor_screen.refused_list() if self.sensor_screen is not None else [],
            "claims": self.claims(),
            "baseline_calibration": self.calibration.to_dict() if self.calibration else None,
        }


#: A runner-up closer than this in ΔBIC is reported as indistinguishable from the verdict ...
AMBIGUITY_BIC = 10.0
#: ... and so is one whose RMSE is within this share of the verdict's (with thousands of samples,
#: a ΔBIC of a few hundred can separate fits whose errors differ by 1 %, well below what a model
#: error of the plant can do).
AMBIGUITY_RMSE = 0.02


#: With an error model, two explanations that both leave at most this many discrepancy floors
#: explain the data equally well: the model's own error cannot rank them.
AMBIGUITY_FLOOR = 1.5


def look_alike(chosen, other, floor: float | None = None) -> bool:
    """True when ``other`` (a Candidate or JointCandidate) explains the data about as well as
    ``chosen``: ΔBIC within :data:`AMBIGUITY_BIC` or RMSE within :data:`AMBIGUITY_RMSE`, or, with
    the discrepancy ``floor`` (K), both within :data:`AMBIGUITY_FLOOR` floors."""
    if floor is not None and max(chosen.rmse_after, other.rmse_after) <= AMBIGUITY_FLOOR * floor:
        return implausible_reason(other) is None
    return bool(other.delta_bic - chosen.delta_bic < AMBIGUITY_BIC
                or other.rmse_after <= (1 + AMBIGUITY_RMSE) * chosen.rmse_after)


def _explanations(candidate) -> dict:
    """Effect → fitted values of a Candidate or JointCandidate."""
    return dict(candidate.values) if isinstance(candidate, JointCandidate) else {candidate.effect: candidate.values}


def rival(iteration: "Iteration", floor: float | None = None):
    """The best other explanation that looks alike the one ``iteration`` added (:func:`look_alike`
    with the discrepancy ``floor``, K), or None."""
    chosen = iteration.added_pair or iteration.added
    if chosen is None:
        return None
    pool = iteration.pairs if iteration.added_pair else iteration.ranked
    others = [c for c in pool if c is not chosen and implausible_reason(c) is None and look_alike(chosen, c, floor)]
    return min(others, key=lambda c: c.delta_bic) if others else None


def explain(candidate: Candidate | None, search: EffectSearch, runner_up: Candidate | None = None) -> str:
    """Plain language: what the residual looked like and which effect's signature it matches."""
    from .compare import winding_rate_K_per_min

    series, outputs = search.series, search.output_names
    residual = search.predicted_before - series.outputs
    if candidate is None:
        return (f"No effect is significant: the model explains the data to RMSE {search.rmse_before:.3f} K "
                f"against an estimated error level of {search.noise:.3f} K (sensor noise, or the discrepancy floor with a baseline); no catalogue effect passes the "
                "tests of evidence (ΔBIC), size (RMSE reduction) and share of the misfit explained.")
    effect = search.effect(candidate.effect)
    after = np.arange(series.time_s.size) >= candidate.onset_index
    when = (f"after t = {candidate.onset_s / 3600:.2f} h" if candidate.onset_index > 0 else "from the start")
    with np.errstate(all="ignore"):
        means = [np.nanmean(row[after]) if np.isfinite(row[after]).any() else np.nan for row in residual]
    biases = ", ".join(f"{'hot' if b > 0 else 'cold'} by {abs(b):.2f} K in {n}" for n, b in zip(outputs, means)
                       if np.isfinite(b))
    inputs = series.inputs
    interface = search.model.spec.interface
    regressors = {"I^2": np.mean([inputs[p].to_numpy() ** 2 for p in interface.load_currents], axis=0),
                  "winding temperature": series.outputs[0]}
    if interface.has_role(Role.EXCITATION_CURRENT):
        excitation = interface.role(Role.EXCITATION_CURRENT)
        regressors[excitation] = inputs[excitation].to_numpy()
    regressors["inlet temperature"] = inputs[interface.coolant_input].to_numpy()
    regressors["dθ/dt"] = winding_rate_K_per_min(series.time_s, series.outputs[0])
    links = []
    for name, e in zip(outputs, residual):
        scores = {r: correlation(e[after], v[after]) for r, v in regressors.items()}
        top = max(scores, key=lambda r: abs(scores[r]))
        links.append(f"the {name} error follows {top} (r = {scores[top]:+.2f})")
    values = ", ".join(f"{n} = {v:.4g} {p.unit}" for (n, v), p in zip(candidate.values.items(), effect.parameters))
    neutral = ", ".join(f"{p.name} = {p.neutral:g}" for p in effect.parameters)
    return (f"{candidate.effect}: {effect.summary}. {when.capitalize()} the model ran {biases}; "
            f"{'; '.join(links)}. That is the signature of this effect: {effect.signature}. "
            f"Fitted {values} (neutral {neutral}); RMSE {candidate.rmse_before:.3f} → {candidate.rmse_after:.3f} K "
            f"against an error level of {search.noise:.3f} K (ΔBIC = {candidate.delta_bic:.0f})."
            + _ambiguity(candidate, runner_up))


def explain_pair(pair: JointCandidate, search: EffectSearch, best_single: Candidate) -> str:
    """Plain language: the two effects fitted together and what one effect alone left."""
    parts = []
    for name in pair.effects:
        effect = search.effect(name)
        onset = pair.onsets_s[name]
        values = ", ".join(f"{n} = {v:.4g} {p.unit}" for (n, v), p in zip(pair.values[name].items(),
                                                                         effect.parameters))
        parts.append(f"{name} ({effect.summary}; {values}, "
                     f"{'from the start' if pair.onset_indices[name] == 0 else f'from t = {onset / 3600:.2f} h'})")
    return (f"Two effects at once: {' and '.join(parts)}, fitted jointly (values and both onsets). RMSE "
            f"{pair.rmse_before:.3f} → {pair.rmse_after:.3f} K against an error level of {search.noise:.3f} K "
            f"(ΔBIC = {pair.delta_bic:.0f}); the best single effect, {best_single.effect}, only reached "
            f"{best_single.rmse_after:.3f} K (ΔBIC = {best_single.delta_bic:.0f}), and each effect of the pair is "
            f"needed: the pair passes the significance tests against either effect alone.")


def _ambiguity(candidate: Candidate, runner_up: Candidate | None) -> str:
    if runner_up is None or not look_alike(candidate, runner_up):
        return ""
    return (f" Caution: {runner_up.effect} explains the data almost as well (RMSE {runner_up.rmse_after:.3f} K, "
            f"ΔBIC only {runner_up.delta_bic - candidate.delta_bic:.1f} higher): these data cannot tell the two "
            f"apart (e.g. with balanced phase currents a loss in I_u² grows like one in ΣI²); a test that "
            f"separates their signatures would (see the designed experiment).")


def diagnose(model: ThermalModel, data, baseline=None, baseline_parameters: Sequence[str] = DEFAULT_BASELINE_PARAMETERS,
             iterate: bool = False, dt_s: float | None = None, effects: Sequence[str] | None = None,
             max_iterations: int = 4, pairs: bool = True, catalogue: Mapping[str, Effect] | None = None,
             progress: Callable[[str], None] | None = None, design_experiment: bool = True,
             sensor_faults: bool = True) -> Diagnosis:
    """Find the catalogue effect(s) ``model`` lacks to explain ``data``: one call of
    :class:`~genthermal.diagnose.discovery.Discovery` (use a Discovery directly to fit several
    records of the same model and reuse what it builds).

    Parameters
    ----------
    model : ThermalModel
    data : MeasurementData, pandas.DataFrame or path
        The measurements to explain.
    baseline : MeasurementData, pandas.DataFrame or path, optional
        Healthy measurements of the same machine: ``baseline_parameters`` are calibrated on them
        first (:func:`genthermal.diagnose.calibrate.calibrate`), so that what remains is the effect.
    baseline_parameters : sequence of str
        Uncertain parameters to calibrate on the baseline (those the model lacks are skipped).
    iterate : bool
        Add the best significant effect and search again until nothing is significant.
    dt_s : float, optional
        Resample the data (and baseline) to this period first, s.
    effects : sequence of str, optional
        Restrict the candidates to these effects of ``catalogue``.
    max_iterations : int
        Bound on the rounds with ``iterate``.
    pairs : bool
        In the first round, when the residual after the best single effect fails the tests of
        :mod:`~genthermal.diagnose.residual`, fit pairs of effects jointly
        (:mod:`genthermal.diagnose.joint`) and prefer a pair that passes :func:`choose_pair`.
    catalogue : mapping of str to Effect, optional
        The effects searched (default: :meth:`Catalogue.for_diagnosis`, the registered effects with
        their shape parameters fitted).
    progress : callable, optional
        Called with one line of text as each stage of the search finishes.
    design_experiment : bool
        When another explanation fits about as well as the verdict, design the rig test that
        separates them (:func:`genthermal.diagnose.experiment.separating_experiment`).
    sensor_faults : bool
        Weigh sensor faults against the physical effects (:mod:`genthermal.diagnose.sensor_screen`):
        the verdict is then about the machine on the record with the faulty sensors corrected.

    Returns
    -------
    Diagnosis
    """
    from .catalogue import Catalogue
    from .discovery import Discovery
    from .fitter import OnsetFitter

    candidates = Catalogue.for_diagnosis() if catalogue is None else Catalogue.of(catalogue)
    for name in effects or ():
        if name not in candidates:
            raise InputError("effects", name, f"not in the catalogue: {', '.join(candidates)}")
    if effects is not None:
        candidates = candidates.only(effects)
    discovery = Discovery(candidates, fitter=OnsetFitter(pairs=pairs), iterate=iterate, max_iterations=max_iterations,
                          baseline_parameters=baseline_parameters, design_experiment=design_experiment,
                          progress=progress, sensor_faults=sensor_faults)
    return discovery.fit(model, data, baseline=baseline, dt_s=dt_s)
