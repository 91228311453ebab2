"""The open search as the diagnosis' next step: when the catalogue leaves the residual unexplained.

:func:`open_followup` searches the generic library of heat flows and conductance changes
(:func:`~genthermal.diagnose.open_search.heat_flow_library`) on the model as calibrated on the
baseline, with the same error model and criterion (single terms with their onsets): on top of the
catalogue's nearest effects (kept from their onsets, refitted with each term), and in place of
each nearest effect among the terms that act where it acts; the better of these by the criterion
is reported. It returns the JSON section ``open_search`` of ``genthermal diagnose``: each
significant term's node group, form, size, onset, text and the Python code that keeps it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .catalogue import Catalogue
from .discover import misfit_of
from .open_search import CONDUCTANCES, _form_and_group, conductance_role, describe_term, effect_code, heat_flow_library


def _group_and_form(effect_name: str) -> tuple[str, str]:
    if effect_name.startswith("conductance_"):
        role, coefficients = conductance_role(effect_name)
        return CONDUCTANCES[role], "conductance factor" + (f" of {coefficients[0]}" if coefficients else "")
    if effect_name.startswith("loss_theta_") or effect_name.startswith("loss_I2_"):
        kind, label = ("loss_theta", effect_name[len("loss_theta_"):]) if effect_name.startswith("loss_theta_") \
            else ("loss_I2", effect_name[len("loss_I2_"):])
        return label, kind
    form, group = _form_and_group(effect_name)
    return group, form


def _search(discovery, diagnosis, data, dt_s, candidates: Catalogue, kept: list):
    """The open search's fit of ``candidates`` on top of the found effects ``kept``."""
    follow = discovery.with_settings(candidates=candidates, iterate=False, sensor_faults=False,
                                     design_experiment=False,
                                     fitter=dataclasses.replace(discovery.fitter, pairs=False, onset_profiles=False))
    follow._error_model = diagnosis.error_model
    return follow.fit(diagnosis.model, data, dt_s=dt_s, found=kept)


def _score(result, reference_rmse: float, criterion) -> float:
    """The criterion of ``result``'s final model (all its effects' values and onsets counted)
    against a model of RMSE ``reference_rmse``, K, on the same samples."""
    n = int(np.isfinite(result.series.outputs).sum())
    k = sum(len(f.values) + 1 for f in result.found)
    return criterion.delta(result.iterations[-1].rmse_after ** 2 * n, reference_rmse ** 2 * n, n, k)


def open_followup(discovery, diagnosis, data, dt_s=None) -> dict:
    """Search the open library on ``diagnosis.model`` (the calibrated model) against ``data``.

    Parameters
    ----------
    discovery : Discovery
        The discovery that made ``diagnosis`` (its fitter, progress and error model are reused).
    diagnosis : Diagnosis
        The catalogue's diagnosis (its residual unexplained); its found effects are the nearest
        catalogue effects.
    data : MeasurementData
        The record.
    dt_s : float, optional
        Resampling period, s.

    Returns
    -------
    dict
        ``ran``, ``on_top_of`` (the nearest catalogue effects kept), ``in_place_of`` (the one
        replaced, or None), ``terms`` (``term``, ``group``, ``form``, ``params``, ``onset_s``,
        ``text``, ``code``), ``rmse_before``, ``rmse_after``, ``verdict``, ``unexplained`` after
        the terms.
    """
    library = Catalogue.of(list(heat_flow_library(diagnosis.model).values()))
    nearest = [diagnosis.catalogue[f.effect] for f in diagnosis.found]
    options = [(None, _search(discovery, diagnosis, data, dt_s, library.extended(*nearest), diagnosis.found))]
    for effect in nearest:
        # the same change in another form: a term of the parts and inputs the nearest effect acts on
        forms = [e for e in library.values() if misfit_of(e, effect)]
        kept = [f for f in diagnosis.found if f.effect != effect.name]
        if forms:
            others = [e for e in nearest if e is not effect]
            options.append((effect.name, _search(discovery, diagnosis, data, dt_s,
                                                 Catalogue.of(forms).extended(*others), kept)))
    criterion = discovery.criterion if diagnosis.error_model is None else \
        diagnosis.error_model.criterion(diagnosis.series.dt_s)
    scores = [_score(result, diagnosis.iterations[0].rmse_before, criterion) for _, result in options]
    replaced, result = options[min(range(len(options)), key=scores.__getitem__)]
    kept = [f.effect for f in diagnosis.found if f.effect != replaced]
    terms = []
    for found in (f for f in result.found if f.effect not in kept):
        group, form = _group_and_form(found.effect)
        name = "found_" + found.effect.replace("heat_", "")
        terms.append({"term": found.effect, "group": group, "form": form, "params": found.values,
                      "onset_s": found.onset_s, "text": describe_term(found, library),
                      "code": effect_code(found, library, name)})
    first = result.iterations[0]
    return {"ran": True, "library_size": len(library), "on_top_of": kept, "in_place_of": replaced, "terms": terms,
            "verdict": result.verdict, "rmse_before": first.rmse_before, "rmse_after": result.iterations[-1].rmse_after,
            "unexplained": result.unexplained, "ranked": [c.to_dict() for c in first.ranked[:5]]}
