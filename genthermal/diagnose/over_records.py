"""One effect fitted over several records at once: one set of its values, each record from its own state.

An effect present in every profile of a machine (a loss the model lacks) is fitted by
:func:`fit_effect_over_records` with :func:`~genthermal.diagnose.multi_record.fit_records`: the
effect from the start of every record, each record from its measured initial state. Its evidence
is the criterion's change summed over the records (each record's log-ratio of residual sums of
squares on its own samples, one penalty for the shared parameters), scored by the tests of
:func:`~genthermal.diagnose.discover.passes_tests` within the effect's plausible range.
:func:`diagnose_over_records` ranks every applicable catalogue effect so. Guide:
``docs/guide/calibration-diagnosis.md``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Sequence

import numpy as np

from ..errors import InputError
from ..model import ThermalModel
from .criterion import BIC
from .multi_record import Record, RecordsFit, fit_records, simulate_record
from .search import noise_std

#: Fewest samples of each record (as ``diagnose``: an effect's size needs a record of some length).
MIN_RECORD_SAMPLES = 30


@dataclasses.dataclass
class EffectOverRecords:
    """One effect fitted over several records.

    Attributes
    ----------
    effect : str
    fit : RecordsFit
        The fit of the effect's parameters (``fit.model`` has the effect at the fitted values).
    rss_before, rss_after : list of float
        Each record's sum of squared sensor errors without and with the effect, K².
    samples : list of int
        Each record's valid sensor samples.
    delta_ic : float
        The criterion's change summed over the records (module docstring).
    noise_K : float
        The error level the tests compare with (sensor noise or the discrepancy floor), K.
    significant : bool
        Passes the tests of :func:`~genthermal.diagnose.discover.passes_tests` and lies in its
        plausible range.
    implausible : str or None
        Why its fitted values are no finding for a real machine, or None.
    """

    effect: str
    fit: RecordsFit
    rss_before: list
    rss_after: list
    samples: list
    delta_ic: float
    noise_K: float
    significant: bool
    implausible: str | None

    @property
    def values(self) -> dict:
        """Fitted parameter name → value (model units)."""
        return {n: float(v) for n, v in zip(self.fit.names, self.fit.values)}

    @property
    def rmse_before(self) -> float:
        """RMSE over every sensor of every record without the effect, K."""
        return math.sqrt(sum(self.rss_before) / max(sum(self.samples), 1))

    @property
    def rmse_after(self) -> float:
        """RMSE over every sensor of every record with the effect, K."""
        return math.sqrt(sum(self.rss_after) / max(sum(self.samples), 1))

    def to_dict(self) -> dict:
        """JSON entry: the effect, its values with their 95 % intervals, the summed evidence and
        each record's RMSE before and after, K."""
        per_record = [{"record": name, "samples": n, "rmse_before_K": math.sqrt(b / max(n, 1)),
                       "rmse_after_K": math.sqrt(a / max(n, 1))}
                      for name, n, b, a in zip(self.fit.records, self.samples, self.rss_before, self.rss_after)]
        return {"effect": self.effect, "params": self.values,
                "ci95": {n: list(ci) for n, ci in zip(self.fit.names, self.fit.fisher["ci95"])},
                "delta_ic": self.delta_ic, "rmse_before": self.rmse_before, "rmse_after": self.rmse_after,
                "noise_K": self.noise_K, "significant": self.significant, "implausible": self.implausible,
                "converged": self.fit.converged, "warnings": self.fit.fisher["warnings"], "per_record": per_record}


def _rss(model: ThermalModel, record: Record) -> tuple[float, int]:
    error = simulate_record(model, record) - record.outputs
    valid = np.isfinite(error)
    return float(np.sum(error[valid] ** 2)), int(valid.sum())


def check_records(model: ThermalModel, records: Sequence[Record]) -> None:
    """Raise InputError naming the record when ``records`` are not one machine's profiles on the
    model's schema: fewer than two, other inputs or sensors, a sensor never measured or fewer than
    :data:`MIN_RECORD_SAMPLES` samples."""
    if len(records) < 2:
        raise InputError("records", len(records), "a fit over records needs at least two; one record: diagnose it")
    for record in records:
        if record.inputs.shape[0] != len(model.input_names) or record.outputs.shape[0] != len(model.output_names):
            raise InputError(f"{record.name}: columns", f"{record.inputs.shape[0]} inputs, "
                             f"{record.outputs.shape[0]} sensors", f"{model.name} has {len(model.input_names)} "
                             f"inputs and {len(model.output_names)} sensors")
        if record.n_samples < MIN_RECORD_SAMPLES:
            raise InputError(f"{record.name}: samples", record.n_samples,
                             f"too short: each record needs at least {MIN_RECORD_SAMPLES} samples")
        for name, row in zip(model.output_names, record.outputs):
            if not np.isfinite(row).any():
                raise InputError(f"{record.name}: column {name}", "no value",
                                 "every record of a fit over records must measure every sensor")


def fit_effect_over_records(model: ThermalModel, records: Sequence[Record], effect: str, criterion=None,
                            noise_K: float | None = None, before=None) -> EffectOverRecords:
    """Fit ``effect`` from the start of every record with one set of values (module docstring).

    Parameters
    ----------
    model : ThermalModel
        The model without the effect (calibrated on healthy data or not).
    records : sequence of Record
        The profiles (:func:`~genthermal.diagnose.multi_record.record_from_measurements`).
    effect : str
        A catalogue effect the model lacks; its parameters are fitted as ``diagnose`` fits them
        (:meth:`~genthermal.diagnose.catalogue.Catalogue.for_diagnosis`: the shapes within their
        plausible range), from their neutral value where it is 0 (off), else their typical one.
    criterion : optional
        ``delta(rss_after, rss_before, n, k)`` (default :class:`~genthermal.diagnose.criterion.BIC`;
        an error model's :class:`~genthermal.diagnose.error_model.WhitenedBIC` on its effective samples).
    noise_K : float, optional
        The error level of the tests, K (default: the sensor noise of the records,
        :func:`~genthermal.diagnose.search.noise_std` pooled as root mean variance).
    before : list of (float, int), optional
        Each record's sum of squared errors without the effect and its valid samples, when the
        caller has them (:func:`diagnose_over_records` runs the model once for every effect).

    Returns
    -------
    EffectOverRecords
    """
    from ..effects import get_effect
    from .catalogue import Catalogue
    from .discover import passes_tests

    check_records(model, records)
    criterion = BIC() if criterion is None else criterion
    registered = get_effect(effect)
    reason = registered.unavailable_reason(model)
    if reason:
        raise InputError("effect", effect, f"cannot be added to {model.name}: {reason}")
    entry = Catalogue.for_diagnosis()[effect]  # as diagnose: the shapes fitted within their plausible range
    # switched off where the neutral value is 0 (the fit may leave the effect off), else typical
    start = {p.name: p.neutral if p.neutral == 0 or p.typical is None else p.typical for p in entry.parameters}
    extended = model.with_effect(entry, **start)
    fit = fit_records(extended, records, list(start))  # positive values within fit_records' factor of the start
    before = [_rss(model, r) for r in records] if before is None else before
    after = [_rss(fit.model, r) for r in records]
    samples = [n for _, n in before]
    delta = sum(criterion.delta(max(a, 1e-300), max(b, 1e-300), n, 0) for (b, n), (a, _) in zip(before, after))
    delta += criterion.delta(1.0, 1.0, sum(samples), len(start))  # one penalty for the shared values
    if noise_K is None:
        noise_K = math.sqrt(np.nanmean([noise_std(r.outputs) ** 2 for r in records]))
    implausible = registered.implausible(dict(zip(fit.names, fit.values)))
    result = EffectOverRecords(effect, fit, [b for b, _ in before], [a for a, _ in after], samples, float(delta),
                               float(noise_K), False, implausible)
    evidence_limit = getattr(criterion, "evidence_limit", -10.0)
    result.significant = implausible is None and passes_tests(result.rmse_before, result.rmse_after, result.delta_ic,
                                                              result.noise_K, evidence_limit)
    return result


@dataclasses.dataclass
class DiagnosisOverRecords:
    """Every applicable effect fitted over the same records, best evidence first.

    Attributes
    ----------
    ranked : list of EffectOverRecords
    criterion : str
        The criterion's name.
    """

    ranked: list
    criterion: str

    @property
    def verdict(self) -> str:
        """The best significant effect, or ``"none"``."""
        return next((r.effect for r in self.ranked if r.significant), "none")

    @property
    def look_alikes(self) -> list:
        """Other significant effects within :data:`~genthermal.diagnose.discover.AMBIGUITY_BIC` of
        the verdict's evidence: these records cannot tell them from it."""
        from .discover import AMBIGUITY_BIC

        chosen = next((r for r in self.ranked if r.significant), None)
        if chosen is None:
            return []
        return [r.effect for r in self.ranked if r is not chosen and r.significant
                and r.delta_ic - chosen.delta_ic < AMBIGUITY_BIC]

    def to_dict(self) -> dict:
        """JSON document of ``genthermal diagnose --joint``."""
        return {"joint": True, "records": self.ranked[0].fit.records if self.ranked else [],
                "criterion": self.criterion, "verdict": self.verdict, "look_alikes": self.look_alikes,
                "ranked": [r.to_dict() for r in self.ranked]}


def diagnose_over_records(model: ThermalModel, records: Sequence[Record], effects: Sequence[str] | None = None,
                          error_model=None, progress=None) -> DiagnosisOverRecords:
    """Fit each of ``effects`` (default: every catalogue effect applicable to ``model``) over
    ``records`` (:func:`fit_effect_over_records`) and rank them by summed evidence.

    Parameters
    ----------
    model : ThermalModel
    records : sequence of Record
    effects : sequence of str, optional
    error_model : ErrorModel, optional
        The model's error on healthy records: the criterion is then its BIC on effective samples
        and the tests compare with its discrepancy floor (records of one sample period).
    progress : callable, optional
        Called with a line of text after each effect.
    """
    from ..effects import applicable_effects

    check_records(model, records)
    names = [e.name for e in applicable_effects(model)] if effects is None else list(effects)
    criterion, noise = BIC(), None
    if error_model is not None:
        steps = sorted({round(r.dt_s, 9) for r in records})
        if len(steps) > 1:
            raise InputError("records", ", ".join(r.name for r in records),
                             f"different sample periods ({', '.join(f'{s:g}' for s in steps)} s) under one error model")
        criterion, noise = error_model.criterion(steps[0]), error_model.floor_K
    before = [_rss(model, r) for r in records]  # the model without any effect: one run for every effect
    ranked = []
    for name in names:
        ranked.append(fit_effect_over_records(model, records, name, criterion, noise, before))
        if progress:
            progress(f"{name}: ΔIC {ranked[-1].delta_ic:.1f}, RMSE {ranked[-1].rmse_before:.3f} -> "
                     f"{ranked[-1].rmse_after:.3f} K")
    ranked.sort(key=lambda r: r.delta_ic)
    return DiagnosisOverRecords(ranked, getattr(criterion, "name", type(criterion).__name__))
