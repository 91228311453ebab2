"""The size of an explanation as the machine's design sensors see it: phase sensors averaged.

With one winding node per phase, an effect common to all phases can only remove the common part
of the phase errors, so its practical size is diluted by the phase spread.
:class:`DesignSensorScale` measures RMSEs and noise with the phase rows replaced by their mean: an
explanation passes the practical tests on every sensor or on the design sensors; its evidence is
always that of every sensor. Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Sequence

import numpy as np

from ..errors import InputError
from .search import noise_std


def design_readings(outputs: np.ndarray, output_names: Sequence[str], phase_columns: Sequence[str]) -> np.ndarray:
    """``outputs`` (n_outputs, N) with the rows named in ``phase_columns`` replaced by one row,
    their mean (first, NaN where no phase has a sample), followed by the other rows in order."""
    outputs = np.atleast_2d(np.asarray(outputs, dtype=float))
    names = list(output_names)
    if outputs.shape[0] != len(names):
        raise InputError("outputs", outputs.shape, f"expected {len(names)} rows, one per output {names}")
    missing = [c for c in phase_columns if c not in names]
    if missing or len(phase_columns) < 2:
        raise InputError("phase_columns", list(phase_columns), f"need at least two of the outputs {names}")
    phases = [names.index(c) for c in phase_columns]
    others = [i for i in range(len(names)) if i not in phases]
    valid = np.isfinite(outputs[phases])
    counts = valid.sum(axis=0)
    with np.errstate(invalid="ignore"):
        mean = np.where(counts > 0, np.where(valid, outputs[phases], 0.0).sum(axis=0) / np.maximum(counts, 1), np.nan)
    return np.vstack([mean[None, :], outputs[others]])


@dataclasses.dataclass(frozen=True)
class DesignSensorScale:
    """RMSE and noise of a search's record on its design sensors (module docstring).

    Attributes
    ----------
    output_names : tuple of str
        The sensors fitted (rows of every ``predicted`` array given to :meth:`rmse`).
    phase_columns : tuple of str
        The phase sensors averaged into one design sensor.
    measured : numpy.ndarray
        The record on the design sensors, °C, (n_design, N).
    noise : float
        Sensor noise of the design sensors estimated from the record alone
        (:func:`~genthermal.diagnose.search.noise_std`), K.
    rmse_before : float
        RMSE on the design sensors of the model without the candidates (the search's
        ``predicted_before``), K.
    """

    output_names: tuple
    phase_columns: tuple
    measured: np.ndarray
    noise: float
    rmse_before: float

    @classmethod
    def of(cls, search, phase_columns: Sequence[str]) -> "DesignSensorScale":
        """The scale of a fitted :class:`~genthermal.diagnose.search.EffectSearch` whose outputs
        include ``phase_columns``."""
        names = tuple(search.output_names)
        measured = design_readings(search.series.outputs, names, phase_columns)
        scale = cls(names, tuple(phase_columns), measured, noise_std(measured), math.nan)
        return dataclasses.replace(scale, rmse_before=scale.rmse(search.predicted_before))

    def rmse(self, predicted: np.ndarray) -> float:
        """RMSE (K) of ``predicted`` (n_outputs, N), °C, on the design sensors."""
        residual = design_readings(predicted, self.output_names, self.phase_columns) - self.measured
        valid = np.isfinite(residual)
        if not valid.any():
            raise InputError("predicted", "no valid sample", "the design sensors have no sample to compare")
        return float(math.sqrt(np.mean(residual[valid] ** 2)))
