"""The open search as the diagnosis' next step: when the catalogue leaves the residual unexplained.

:func:`open_followup` searches the generic library of heat flows and conductance changes
(:func:`~genthermal.diagnose.open_search.heat_flow_library`) in place of the catalogue, on the
model as calibrated on the baseline, with the same error model and criterion, single terms with
their onsets: an alternative to the catalogue's findings, not a term on top of them (a model with
the findings applied would hold them from the first sample, not from their onsets). It returns the JSON section ``open_search`` of ``genthermal diagnose``: each
significant term with its node group, form, size, onset, plain-language text and the Python code
that keeps it as an effect.
"""

from __future__ import annotations

import dataclasses

from .catalogue import Catalogue
from .open_search import CONDUCTANCES, _form_and_group, describe_term, effect_code, heat_flow_library


def _group_and_form(effect_name: str) -> tuple[str, str]:
    if effect_name.startswith("conductance_"):
        role = effect_name[len("conductance_"):]
        return CONDUCTANCES.get(role, role), "conductance factor"
    if effect_name.startswith("loss_theta_") or effect_name.startswith("loss_I2_"):
        kind, label = ("loss_theta", effect_name[len("loss_theta_"):]) if effect_name.startswith("loss_theta_") \
            else ("loss_I2", effect_name[len("loss_I2_"):])
        return label, kind
    form, group = _form_and_group(effect_name)
    return group, form


def open_followup(discovery, diagnosis, data, dt_s=None) -> dict:
    """Search the open library on ``diagnosis.model`` (the calibrated model) against ``data``.

    Parameters
    ----------
    discovery : Discovery
        The discovery that made ``diagnosis`` (its fitter, progress and error model are reused).
    diagnosis : Diagnosis
        The catalogue's diagnosis (its residual unexplained).
    data : MeasurementData
        The record.
    dt_s : float, optional
        Resampling period, s.

    Returns
    -------
    dict
        ``ran``, ``terms`` (``term``, ``group``, ``form``, ``params``, ``onset_s``, ``text``,
        ``code``), ``rmse_before``, ``rmse_after``, ``verdict``, ``unexplained`` after the terms.
    """
    model = diagnosis.model
    library = Catalogue.of(list(heat_flow_library(model).values()))
    follow = discovery.with_settings(candidates=library, iterate=False, sensor_faults=False,
                                     design_experiment=False,
                                     fitter=dataclasses.replace(discovery.fitter, pairs=False, onset_profiles=False))
    follow._error_model = diagnosis.error_model
    result = follow.fit(model, data, dt_s=dt_s)
    terms = []
    for found in result.found:
        group, form = _group_and_form(found.effect)
        name = "found_" + found.effect.replace("heat_", "")
        terms.append({"term": found.effect, "group": group, "form": form, "params": found.values,
                      "onset_s": found.onset_s, "text": describe_term(found, library),
                      "code": effect_code(found, library, name)})
    first = result.iterations[0]
    return {"ran": True, "library_size": len(library), "terms": terms, "verdict": result.verdict,
            "rmse_before": first.rmse_before, "rmse_after": result.iterations[-1].rmse_after,
            "unexplained": result.unexplained,
            "ranked": [c.to_dict() for c in first.ranked[:5]]}
