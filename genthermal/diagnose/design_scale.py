r"""The size of an explanation as the machine's design sensors see it: phase sensors averaged.

With the phase-resolved winding view (:mod:`genthermal.diagnose.phase_winding`) every phase PT100
is fitted on its own. The residual sum of squares then splits as

.. math::
    \sum_{x\in\{u,v,w\}} r_x^2 = 3\,\bar r^{\,2} + \sum_x (r_x - \bar r)^2 ,

the common part :math:`\bar r` (what the design sensor, the mean of the three, reads) and the
phase spread. An effect common to all phases (a change of the frame cooling, a blockage) can only
remove common error; the spread keeps the noise of three single sensors and the error each phase
node makes from its own noisy phase current (1 % of :math:`I_x` is 2 % of :math:`I_x^2`, not
averaged over the phases). On every sensor, the practical tests of
:func:`~genthermal.diagnose.discover.passes_tests` (a 10 % RMSE reduction, half of the excess
over the noise explained) measure a common effect against that diluted scale, and one that the
same record read through the design sensors shows clearly can fail them.

:class:`DesignSensorScale` measures RMSEs and the noise on the design sensors: the phase rows of
the outputs replaced by their mean, every other sensor as it is. An explanation passes the
practical tests when it passes them on every sensor or on the design sensors; the evidence
(ΔBIC) is always that of every sensor, where a loss in one phase shows in the spread.
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
