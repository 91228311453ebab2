"""Effects with an onset: a model that carries them becomes a sequence of models switched in time.

A diagnosed model may hold an effect that started during the record (a blockage at 1.1 h). The
model keeps the effect with its fitted values and records the onset in ``spec.onsets``; before the
onset the effect is at its neutral values, where it vanishes (every catalogue effect has one). So
the switched models differ only in parameter values and share their compiled functions.
"""

from __future__ import annotations

from .effects import CATALOGUE
from .model import ThermalModel


def onset_switches(model: ThermalModel, t0_s: float = 0.0) -> tuple[ThermalModel, list]:
    """The model a record starts with and the switches of its onsets.

    Parameters
    ----------
    model : ThermalModel
        A model whose ``spec.onsets`` lists (effect, onset s after the first sample).
    t0_s : float
        Time of the record's first sample, s; the switch times are ``t0_s + onset``.

    Returns
    -------
    (ThermalModel, list of (float, ThermalModel))
        The model before the first onset and ``switches`` for :func:`genthermal.simulate.simulate`;
        none of them carries onsets. A model without onsets gives ``(model, [])``.
    """
    onsets = sorted(model.spec.onsets, key=lambda item: item[1])
    if not onsets:
        return model, []
    final = model.with_onsets({})
    started: set[str] = set()
    models = []
    for effect, onset in [(None, None), *onsets]:
        if effect is not None:
            started.add(effect)
        neutral = {p.name: p.neutral for name, _ in onsets if name not in started
                   for p in CATALOGUE[name].parameters}
        models.append((onset, final.with_parameters(provenance="assumed", source="before the effect's onset",
                                                    **neutral) if neutral else final))
    return models[0][1], [(t0_s + onset, m) for onset, m in models[1:]]
