"""Discovery as one composed object: candidates, a criterion and a fitter behind ``fit``.

A :class:`Discovery` is built from a :class:`~genthermal.diagnose.catalogue.Catalogue`, a
criterion (:class:`~genthermal.diagnose.criterion.BIC` by default) and a fitter
(:class:`~genthermal.diagnose.fitter.OnsetFitter`), in the manner of pysindy's
``SINDy(feature_library, optimizer)``; :meth:`Discovery.fit` returns a
:class:`~genthermal.diagnose.discover.Diagnosis`. It memoises the models it builds, so fitting
one model to several records builds them once. Guide: ``docs/guide/calibration-diagnosis.md``.
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Sequence

import numpy as np

from ..errors import InputError
from ..model import ThermalModel
from .compare import MeasuredSeries, as_measurements
from .catalogue import Catalogue
from .criterion import BIC
from .design_scale import DesignSensorScale
from .discover import (DEFAULT_BASELINE_PARAMETERS, NOISE_FLOOR_FACTOR, Diagnosis, Iteration, _explanations,
                       choose_pair, explain, explain_pair, implausible_reason, is_significant, misfit_of, rival,
                       same_change, series_for)
from .baseline_set import calibrate_baselines
from .error_model import (STRUCTURE_OVER_FLOOR, UNEXPLAINED_OVER_FLOOR, ErrorModel, baseline_error_model,
                          baseline_records, widened_calibration)
from .experiment import separating_experiment
from .fitter import OnsetFitter
from .joint import JointCandidate
from .onset_profile import refine_verdict
from .phase_winding import phase_sensor
from .sensor_view import SensorView, view_for
from .residual import LEVEL_FACTOR, STRUCTURE_LEVEL_FACTOR, residual_tests
from .search import EffectSearch, FoundEffect, noise_std
from .sensor_screen import SensorScreen, corrected_record


def residual_verdict(series, predicted, viewed: ThermalModel, error_model=None) -> dict:
    """The residual tests (:func:`~genthermal.diagnose.residual.residual_tests`) of ``predicted``
    against the sensor noise of ``series``, or with an ``error_model`` against the discrepancy floor
    (each sensor's own floor, the factors :data:`~genthermal.diagnose.error_model.UNEXPLAINED_OVER_FLOOR`
    and :data:`~genthermal.diagnose.error_model.STRUCTURE_OVER_FLOOR`): the one rule for "is
    something still missing", for the verdict and for whether a further effect is sought."""
    noise = noise_std(series.outputs)
    if error_model is None:
        return residual_tests(series, predicted, noise, viewed.output_names, viewed.spec.interface,
                              "the sensor noise", None, (LEVEL_FACTOR, STRUCTURE_LEVEL_FACTOR))
    return residual_tests(series, predicted, max(noise, error_model.floor_K), viewed.output_names,
                          viewed.spec.interface, "the discrepancy floor",
                          {e.sensor: max(e.level_K, noise) for e in error_model.sensors},
                          (UNEXPLAINED_OVER_FLOOR, STRUCTURE_OVER_FLOOR))


def final_residual(series, predicted, viewed: ThermalModel, error_model=None) -> dict:
    """:func:`residual_verdict` with, when the phase sensors are fitted one by one, their spread
    against its baseline level (:mod:`~genthermal.diagnose.phase_spread`, ``phase_spread`` in the
    result): the verdict's test. It does not decide whether another catalogue effect is sought:
    no catalogue round can remove a one-phase difference the first round leaves (the catalogue's
    one phase-resolved effect was fitted there); the open search can."""
    residual = residual_verdict(series, predicted, viewed, error_model)
    spread = None if error_model is None or error_model.phase_spread is None else \
        error_model.phase_spread.test(predicted - series.outputs, viewed.output_names, series.dt_s)
    if spread is not None:
        residual["phase_spread"] = spread
        if spread["unexplained"]:
            residual["summary"] = (residual["summary"] + " " + spread["summary"] if residual["unexplained"] else
                                   f"{spread['summary']} Do not read the effects found as the whole answer.")
            residual["unexplained"] = True
    return residual


class Discovery:
    """Find the effect(s) a model lacks to explain a record.

    Parameters
    ----------
    candidates : Catalogue, mapping of str to Effect, or sequence of Effect or str, optional
        The effects searched. Default: the registered catalogue with shape parameters fitted
        (:meth:`Catalogue.for_diagnosis`, taken when the Discovery is built); each fit searches
        those that apply to its model.
    criterion : BIC, AIC or compatible, optional
        Information criterion (:mod:`genthermal.diagnose.criterion`); default BIC.
    fitter : OnsetFitter, optional
        Fitting settings (:class:`~genthermal.diagnose.fitter.OnsetFitter`); default: pairs on.
    iterate : bool
        After the first verdict, add it and search again until nothing is significant.
    max_iterations : int
        Bound on the rounds with ``iterate`` (≥ 1).
    baseline_parameters : sequence of str
        Parameters calibrated on a healthy baseline record when :meth:`fit` gets one (those the
        model lacks are skipped).
    design_experiment : bool
        When another explanation fits about as well as the verdict, design the rig test that
        separates them (:func:`~genthermal.diagnose.experiment.separating_experiment`).
    progress : callable, optional
        Called with one line of text as each stage finishes.
    phases : {"auto", "resolved", "lumped"}
        Winding sensors: ``"resolved"`` fits the phase-resolved winding view of the model
        (:mod:`genthermal.diagnose.phase_winding`) to ``T_winding_u/v/w`` one by one; ``"lumped"``
        fits the model's single winding node to their mean; ``"auto"`` resolves the phases when the
        record has the three columns and they differ by more than noise
        (:func:`~genthermal.diagnose.phase_winding.phases_differ`) — a fault in one phase, or an
        unbalanced load.
    outlet : bool or None
        Fit the cooling-air outlet sensor ``T_outlet`` too (less coolant flow heats the outlet
        air, better frame cooling does not); None: when the record has it and the model has an
        outlet node (:mod:`genthermal.diagnose.sensor_view`).
    sensor_faults : bool
        Weigh sensor faults (bias, drift, stuck, gain, noise of one sensor) against the
        candidates (:mod:`genthermal.diagnose.sensor_screen`): the verdict is then about the
        machine on the record with the faulty sensors corrected.
    error_model : ErrorModel, optional
        The calibrated model's error (:mod:`~genthermal.diagnose.error_model`) to score every
        hypothesis with when :meth:`fit` gets no baseline to estimate it on (the flight's, from
        a healthy generator's record: :mod:`genthermal.schedule.monitoring.flight_error`). It must
        describe the sensors the fit compares (InputError otherwise).
    """

    PHASE_MODES = ("auto", "resolved", "lumped")

    def __init__(self, candidates=None, criterion=None, fitter: OnsetFitter | None = None, iterate: bool = False,
                 max_iterations: int = 4, baseline_parameters: Sequence[str] = DEFAULT_BASELINE_PARAMETERS,
                 design_experiment: bool = True, progress: Callable[[str], None] | None = None,
                 phases: str = "auto", outlet: bool | None = None, sensor_faults: bool = True,
                 error_model: ErrorModel | None = None):
        if phases not in self.PHASE_MODES:
            raise InputError("phases", phases, f"must be one of {', '.join(self.PHASE_MODES)}")
        self.phases, self.outlet, self.sensor_faults = phases, outlet, bool(sensor_faults)
        if int(max_iterations) != max_iterations or max_iterations < 1:
            raise InputError("max_iterations", max_iterations, "must be an integer >= 1")
        self.candidates = Catalogue.for_diagnosis() if candidates is None else Catalogue.of(candidates)
        self.criterion = BIC() if criterion is None else criterion
        for attribute in ("delta", "evidence_limit", "name"):
            if not hasattr(self.criterion, attribute):
                raise InputError("criterion", repr(self.criterion), f"has no {attribute!r}: use BIC() or AIC()")
        self.fitter = OnsetFitter() if fitter is None else fitter
        if not isinstance(self.fitter, OnsetFitter):
            raise InputError("fitter", repr(self.fitter), "expected an OnsetFitter")
        self.iterate, self.max_iterations = bool(iterate), int(max_iterations)
        self.baseline_parameters = tuple(baseline_parameters)
        self.design_experiment, self.progress = bool(design_experiment), progress
        self._memo: dict = {}
        #: Baseline calibrations and error models already made, by model and records.
        self._baselines: dict = {}
        if error_model is not None and not isinstance(error_model, ErrorModel):
            raise InputError("error_model", type(error_model).__name__, "expected a genthermal.diagnose.ErrorModel")
        #: Error model given, or of a baseline calibrated earlier (a tie-break refit of the calibrated model).
        self._error_model = error_model

    @property
    def memo(self) -> dict:
        """Models and simulators built by this discovery's fits, by structure: an
        :class:`~genthermal.diagnose.search.EffectSearch` given it as ``cache`` on the same model
        reuses them."""
        return self._memo

    def __repr__(self) -> str:
        return (f"Discovery(candidates={self.candidates!r}, criterion={self.criterion!r}, fitter={self.fitter!r}, "
                f"iterate={self.iterate})")

    def with_settings(self, **changes) -> "Discovery":
        """The same discovery with some constructor settings changed (``candidates``,
        ``criterion``, ``fitter``, ``iterate``, ...), sharing this one's memo: models and
        simulators already built are reused (memo keys hold the Effect objects, so effects of the
        same name in different catalogues never mix)."""
        settings = dict(candidates=self.candidates, criterion=self.criterion, fitter=self.fitter,
                        iterate=self.iterate, max_iterations=self.max_iterations,
                        baseline_parameters=self.baseline_parameters, design_experiment=self.design_experiment,
                        progress=self.progress, phases=self.phases, outlet=self.outlet,
                        sensor_faults=self.sensor_faults, error_model=self._error_model)
        unknown = sorted(set(changes) - set(settings))
        if unknown:
            raise InputError("setting", unknown[0], f"unknown; Discovery takes {', '.join(settings)}")
        other = Discovery(**{**settings, **changes})
        other._memo = self._memo
        return other

    def _view(self, model: ThermalModel, measured) -> SensorView | None:
        """The sensors of the record ``measured`` (MeasurementData or MeasuredSeries) to fit
        (:func:`~genthermal.diagnose.sensor_view.view_for`), None when they are the model's own."""
        if isinstance(measured, MeasuredSeries):
            if self.phases == "resolved" or self.outlet:
                raise InputError("data", "MeasuredSeries", "give the record itself to fit phase or outlet sensors")
            return None
        view = view_for(model, measured.frame, float(np.median(np.diff(measured.time_s))), self.phases, self.outlet)
        return view if view.changes_model else None

    @staticmethod
    def _worth_pairs(ranked, search: EffectSearch, viewed: ThermalModel, error_model=None) -> bool:
        """Fit pairs when the best single effect leaves more than noise: above
        :data:`~genthermal.diagnose.discover.NOISE_FLOOR_FACTOR` σ, and either called unexplained by
        the residual tests or above their structure level
        (:data:`~genthermal.diagnose.residual.STRUCTURE_LEVEL_FACTOR` σ: a weaker second effect can
        leave a residual too small to show clear structure; whether a pair is kept is decided by
        :func:`~genthermal.diagnose.discover.choose_pair`'s tests, not here). With an
        ``error_model``, only when the best single effect leaves the residual unexplained against the
        discrepancy floor (:func:`residual_verdict`): what the first effect leaves within the
        calibrated model's error on other missions is no second effect's to explain."""
        if len(ranked) < 2 or ranked[0].rmse_after <= NOISE_FLOOR_FACTOR * search.noise:
            return False
        if error_model is not None:
            return residual_verdict(search.series, ranked[0].predicted, viewed, error_model)["unexplained"]
        return (ranked[0].rmse_after > STRUCTURE_LEVEL_FACTOR * search.noise
                or residual_tests(search.series, ranked[0].predicted, search.noise, viewed.output_names,
                                  viewed.spec.interface)["unexplained"])

    def _can_resolve_phases(self, model: ThermalModel, measured, view) -> bool:
        """True when ``phases="auto"`` kept the winding lumped but the record has the three phase
        sensors and the model a slot winding to split."""
        reader = phase_sensor(model)
        return (self.phases == "auto" and not (view and view.phases) and not isinstance(measured, MeasuredSeries)
                and reader is not None and all(c in measured.frame for c in reader.columns))

    def _phase_tie_break(self, model: ThermalModel, measured, dt_s, first: Iteration, other,
                         error_model=None) -> Diagnosis | None:
        """Two explanations fit the lumped winding about equally well: refit their effects with one
        winding node per phase sensor (a loss in one phase heats that phase, one in every phase
        does not spread them). Returns that diagnosis when it has a verdict, no look-alike left and
        a residual its tests call explained, else None: a refit that leaves the record unexplained
        cannot tell apart two explanations that each explain it."""
        chosen = first.added_pair or first.added
        names = list(dict.fromkeys([*_explanations(chosen), *_explanations(other)]))
        self._report(f"look-alikes {' + '.join(_explanations(chosen))} and {' + '.join(_explanations(other))}: "
                     "refitting them with one winding node per phase sensor")
        # pairs warm-started from their fits on the lumped winding (the same record, other sensors)
        starts = tuple((a, pair.onsets_s[a], b, pair.onsets_s[b]) for pair in (chosen, other)
                       if isinstance(pair, JointCandidate) for a, b in [pair.effects])
        resolved = self.with_settings(candidates=self.candidates.only(names), phases="resolved", iterate=False,
                                      fitter=dataclasses.replace(self.fitter, pair_starts=starts))
        resolved._error_model = error_model
        diagnosis = resolved.fit(model, measured, dt_s=dt_s)
        floor = None if error_model is None else error_model.floor_K
        if diagnosis.verdict == "none" or diagnosis.unexplained or rival(diagnosis.iterations[0], floor) is not None:
            return None
        diagnosis.iterations[0].explanation += (
            f" On the lumped winding {' + '.join(_explanations(chosen))} and {' + '.join(_explanations(other))} "
            f"explained the data about equally well (RMSE {chosen.rmse_after:.3f} and {other.rmse_after:.3f} K); "
            "the phase sensors tell them apart.")
        return diagnosis

    def _refine_onsets(self, search: EffectSearch, iteration: Iteration, runner_up):
        """Refine the onsets of the first round's verdict on their profile and give their
        intervals (:func:`~genthermal.diagnose.onset_profile.refine_verdict`); the iteration's
        verdict and explanation are updated. Returns the single effect added (None for a pair)."""
        if iteration.added_pair:
            chosen = iteration.added_pair = refine_verdict(search, iteration.added_pair, iteration.pairs)
            iteration.explanation = explain_pair(chosen, search, iteration.ranked[0])
        else:
            chosen = iteration.added = refine_verdict(search, iteration.added, iteration.ranked)
            iteration.explanation = explain(chosen, search, runner_up)
        profiles = chosen.onset_profiles
        iteration.explanation += (
            f" Onsets the data allow ({search.criterion.name} within {profiles[0].threshold:g} of the best, "
            "the other values and the initial state refitted at each): "
            + "; ".join(f"{p.effect} {p.interval_s[0] / 3600:.2f}-{p.interval_s[1] / 3600:.2f} h" for p in profiles)
            + ".")
        onsets = chosen.onsets_s if iteration.added_pair else {chosen.effect: chosen.onset_s}
        self._report("onsets profiled: " + "; ".join(
            f"{p.effect} {onsets[p.effect] / 3600:.2f} h ({p.interval_s[0] / 3600:.2f}-{p.interval_s[1] / 3600:.2f} h)"
            for p in profiles))
        return iteration.added

    def _baseline_calibration(self, model: ThermalModel, baseline: list, dt_s):
        """The calibration of the baseline parameters ``model`` has on the ``baseline`` records
        (cached by the records' identity), or None when it has none of them."""
        from .calibrate import calibrate

        names = [n for n in self.baseline_parameters if n in model.parameters]
        if not names:
            self._report("baseline: the model has none of the baseline parameters "
                         f"({', '.join(self.baseline_parameters)}): taken as calibrated, the baseline gives the error model")
            return None
        key = ("calibration", model, tuple(id(b) for b in baseline), dt_s)
        if key not in self._baselines:  # the records are kept with it: their ids stay theirs
            self._baselines[key] = (baseline, calibrate(model, baseline[0], names, dt_s) if len(baseline) == 1 else
                                    calibrate_baselines(model, baseline, names, dt_s))
            self._report(f"baseline calibrated on {len(baseline)} record(s): {', '.join(names)}")
        return self._baselines[key][1]

    def _report(self, text: str) -> None:
        if self.progress:
            self.progress(text)

    def fit(self, model: ThermalModel, data, baseline=None, dt_s: float | None = None,
            found: Sequence[FoundEffect] = ()) -> Diagnosis:
        """Search ``data`` for the candidates ``model`` lacks.

        Parameters
        ----------
        model : ThermalModel
        data : MeasurementData, pandas.DataFrame or path
            The measurements to explain.
        baseline : MeasurementData, pandas.DataFrame or path, or a list of them, optional
            Healthy measurements of the same machine and sensors: ``baseline_parameters`` (those
            the model has; none: the model is taken as calibrated) are calibrated on them first, so
            that what remains in ``data`` is the effect; the calibrated model's error on them
            (:mod:`~genthermal.diagnose.error_model`) then scores every hypothesis (effective
            samples, tests against the discrepancy floor) and widens the calibration's intervals.
            Several records: one calibration over all, each from its own initial state, and one
            error model pooled over them (:mod:`~genthermal.diagnose.baseline_set`); fitting
            several ``data`` records against the same list (the same objects) calibrates once. A
            baseline of other sensors, or shorter than the error model needs, is refused
            (InputError).
        dt_s : float, optional
            Resample the data (and baseline) to this period first, s.
        found : sequence of FoundEffect, optional
            Effects the search starts from (their values and onsets refitted with each candidate;
            names looked up in ``candidates``): the catalogue's nearest effects under the open
            search (:mod:`~genthermal.diagnose.open_followup`). A candidate may begin with one of
            them, since it then describes that change's misfit.

        Returns
        -------
        Diagnosis
            ``ranking``, ``verdict``, ``improved_model()``, the residual tests and, for
            look-alikes, the separating experiment.
        """
        if not isinstance(model, ThermalModel):
            raise InputError("model", type(model).__name__, "expected a ThermalModel")
        measured = data if isinstance(data, MeasuredSeries) else as_measurements(data, model.spec.interface)
        prior = []
        if self.sensor_faults and not isinstance(measured, MeasuredSeries):
            # redundant sensors first, on the model's own sensor schema: a view that splits the
            # winding per phase would take a faulty phase sensor for that phase's heat
            own = series_for(model, measured, dt_s)
            prior = [h for h in SensorScreen(measured, own, model.spec.interface).found if h.evidence == "redundancy"]
            if prior:
                measured = corrected_record(measured, own, prior)
        view = self._view(model, measured)
        calibration, error_model = None, self._error_model
        if baseline is not None:
            baseline = baseline_records(baseline, measured, model.spec.interface)
            calibration = self._baseline_calibration(model, baseline, dt_s)
            if calibration is not None:
                model = calibration.model
        memo = self._memo if calibration is None else {}
        if view is not None and ("view", model, view) not in memo:
            memo[("view", model, view)] = view(model)
        viewed = model if view is None else memo[("view", model, view)]
        series = series_for(viewed, measured, dt_s)
        if baseline is not None:
            key = ("error model", model, view, tuple(id(b) for b in baseline), dt_s)
            if key not in self._baselines:  # the records are kept with it: their ids stay theirs
                error_model = baseline_error_model(model, viewed, baseline, dt_s, view, self.candidates)
                self._baselines[key] = (baseline, error_model)
                if calibration is not None:
                    calibration.fisher = widened_calibration(calibration.fisher, calibration.values, error_model)
            error_model = self._baselines[key][1]
            self._report(error_model.summary())
        elif error_model is not None and view is None:  # a phase or outlet view refits with the lumped one's
            error_model.check_sensors(viewed.output_names)
        criterion = self.criterion
        if error_model is not None and type(self.criterion) is BIC:
            criterion = error_model.criterion(series.dt_s, self.criterion.evidence_limit)
        if view is not None:
            self._report(f"fitting the record's sensors {', '.join(viewed.output_names)}"
                         + (" (one winding node per phase)" if view.phases else ""))
        screen = None
        if self.sensor_faults:
            screen = SensorScreen(measured, series, viewed.spec.interface, prior)
            series = screen.corrected_series()
        if screen is not None:
            screen.use_error_model(error_model, criterion)
        catalogue = self.candidates
        evidence = criterion.evidence_limit
        given = {f.effect for f in found}
        found: list[FoundEffect] = list(found)
        iterations: list[Iteration] = []
        while True:
            search = EffectSearch(model, series, found, memo, catalogue, criterion, view).fit_found()
            if error_model is not None:
                search.noise = max(search.noise, error_model.floor_K)
            # on top of given effects (the open search) the verdict's test decides, as it called them unexplained
            test = final_residual if given else residual_verdict
            if found and error_model is not None and not test(series, search.predicted_before, viewed,
                                                              error_model)["unexplained"]:
                # the found effects explain the record to the floor: no further effect is fitted
                self._report(f"round {len(iterations) + 1}: the residual after {', '.join(f.effect for f in found)} "
                             "is within the discrepancy floor's tests: nothing left for another effect")
                iterations.append(Iteration([], search.rmse_before, search.predicted_before, None,
                                            explain(None, search)))
                break
            ranked = self.fitter.singles(search)
            design = DesignSensorScale.of(search, phase_sensor(model).columns) if view and view.phases else None
            for candidate in ranked:
                candidate.significant = is_significant(candidate, search.noise, evidence, design)
            self._report(f"round {len(iterations) + 1}: {len(ranked)} single effects fitted"
                         + (f", best {ranked[0].effect} (RMSE {ranked[0].rmse_after:.3f} K)" if ranked else ""))
            # a further effect beginning with a found one is that change's misfit, not a second finding;
            # on top of the effects given (the nearest ones) it may describe that misfit where they act
            plausible = [c for c in ranked if implausible_reason(c) is None
                         and not any(same_change(c.onset_s, f.onset_s) and not (
                             f.effect in given and misfit_of(catalogue[c.effect], catalogue[f.effect])) for f in found)]
            best = plausible[0] if plausible and plausible[0].significant else None
            runner_up = ranked[1] if len(ranked) > 1 else None
            if screen is not None and not screen.model_round_done and screen.against_model(search, ranked,
                                                                                            search.noise):
                self._report(f"sensor fault: {screen.found[-1].fault.describe()}; the round runs again on the "
                             "corrected record")
                series = screen.corrected_series()
                continue
            iteration = Iteration(ranked, search.rmse_before, search.predicted_before, best,
                                  explain(best, search, runner_up))
            if self.fitter.pairs and not found and self._worth_pairs(ranked, search, viewed, error_model):
                iteration.pairs = self.fitter.joint(
                    search, ranked, lambda done, total, label: self._report(f"pair {done}/{total} fitted: {label}"))
                chosen = choose_pair(iteration.pairs, ranked, search.noise, evidence, design)
                if chosen is not None:
                    chosen.significant = True
                    iteration.added, iteration.added_pair = None, chosen
                    iteration.explanation = explain_pair(chosen, search, ranked[0])
            if self.fitter.onset_profiles and not found and (iteration.added_pair or iteration.added):
                best = self._refine_onsets(search, iteration, runner_up)
            iterations.append(iteration)
            if iteration.added_pair:
                chosen = iteration.added_pair
                intervals = {p.effect: p.interval_s for p in chosen.onset_profiles}
                found = [FoundEffect(e, chosen.values[e], chosen.onsets_s[e], chosen.onset_indices[e], intervals.get(e))
                         for e in chosen.effects]
            elif best is None:
                break
            else:
                found = [FoundEffect(f.effect, best.found_values[f.effect],
                                     search.elapsed_s(best.found_onsets[f.effect]), best.found_onsets[f.effect])
                         for f in found]
                intervals = {p.effect: p.interval_s for p in best.onset_profiles}
                found.append(FoundEffect(best.effect, best.values, best.onset_s, best.onset_index,
                                         intervals.get(best.effect)))
            if not self.iterate or len(iterations) >= self.max_iterations:
                break
        noise = noise_std(series.outputs)
        residual = final_residual(series, iterations[-1].predicted_after, viewed, error_model)
        residual["noise_K"] = noise
        if error_model is not None:
            residual["floor_K"] = error_model.floor_K
            residual["rmse_over_floor"] = residual["rmse_K"] / error_model.floor_K
            residual["error_model"] = error_model.to_dict()
            if iterations[0].rmse_before <= NOISE_FLOOR_FACTOR * error_model.floor_K:
                iterations[0].explanation += (
                    f" The record's residual before any effect, {iterations[0].rmse_before:.3f} K, is already within "
                    f"{NOISE_FLOOR_FACTOR:g}× the discrepancy floor ({error_model.floor_K:.3f} K, the calibrated "
                    "model's error on the healthy baseline): there is nothing for an effect to explain.")
        self._report(residual["summary"])
        experiment, other = None, rival(iterations[0], None if error_model is None else error_model.floor_K)
        if other is not None and not residual["level_ok"]:
            # neither explanation accounts for the data: separating them would tell nothing
            self._report(f"{' + '.join(_explanations(other))} fits about as well, but neither explains the data: "
                         "no look-alike test")
            other = None
        phase_sensor_faulty = screen is not None and any(h.evidence == "redundancy" for h in screen.found)
        # a phase sensor already claimed faulty would be refitted as a phase's heat: no tie-break on it
        if other is not None and not phase_sensor_faulty and self._can_resolve_phases(model, measured, view):
            separated = self._phase_tie_break(model, measured, dt_s, iterations[0], other, error_model)
            if separated is not None:
                return separated
        if other is not None and self.design_experiment:
            chosen = iterations[0].added_pair or iterations[0].added
            experiment = separating_experiment(model, _explanations(chosen), _explanations(other), noise, catalogue)
            self._report(f"look-alike: {' + '.join(_explanations(other))}; designed a "
                         f"{experiment.mission.duration_s / 60:.0f}-min test that separates them by "
                         f"{experiment.separation_sigma:.0f} σ")
            if iterations[0].added_pair:
                iterations[0].explanation += (f" Caution: {' + '.join(_explanations(other))} explains the data "
                                              f"almost as well (RMSE {other.rmse_after:.3f} K): these data cannot "
                                              "tell them apart.")
        if screen is not None and screen.found:
            iterations[0].explanation = (f"{screen.text(' + '.join(iterations[0].added_effects) or 'none')} "
                                         + iterations[0].explanation)
        if screen is not None and screen.limit_text():
            iterations[0].explanation += " " + screen.limit_text()
        return Diagnosis(model, series, noise, iterations, found, calibration, residual, catalogue, experiment,
                         criterion=criterion.name, output_names=viewed.output_names, sensor_screen=screen,
                         error_model=error_model)
