"""The three phase windings against each other: a persistent difference the model cannot make.

With one winding node per phase sensor (:mod:`~genthermal.diagnose.phase_winding`), the spread
residual of phase x, :math:`d_x = e_x - (e_y + e_z)/2` (e: model minus measurement), cancels the
error the three phases share (convection, losses, ambient, heat capacities: what a calibrated
model gets wrong on another mission). :class:`PhaseSpread` is its level on the healthy baseline
(10-min means); :meth:`PhaseSpread.test` compares a record's spread residual with it. The rule:
``docs/guide/evidence.md``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import InputError

#: A record's 10-min spread residual above this many times the baseline's is unexplained.
PHASE_SPREAD_OVER_FLOOR = 3.0
#: Averaging window of the spread residual, s: a persistent difference, not noise.
SPREAD_WINDOW_S = 600.0


def _spreads(residual: np.ndarray, names, columns, dt_s: float) -> np.ndarray | None:
    """10-min means of each phase's spread residual, (3, M), K; None without the three columns."""
    rows = [list(names).index(c) for c in columns if c in names]
    if len(columns) != 3 or len(rows) != 3:
        return None
    e = np.asarray(residual, dtype=float)[rows]
    window = max(int(round(SPREAD_WINDOW_S / dt_s)), 1)
    if e.shape[1] < 3 * window:
        return None
    spread = e - (e.sum(axis=0) - e) / 2.0
    spread = np.where(np.isfinite(spread), spread, 0.0)
    kernel = np.ones(window) / window
    return np.array([np.convolve(d, kernel, mode="valid") for d in spread])


@dataclasses.dataclass(frozen=True)
class PhaseSpread:
    """Level (RMS of the 10-min means, K) of each phase's spread residual on the healthy baseline.

    Attributes
    ----------
    columns : tuple of str
        The phase sensors (``T_winding_u/v/w``), in phase order.
    levels_K : tuple of float
        RMS of each phase's 10-min mean spread residual on the baseline, K.
    """

    columns: tuple
    levels_K: tuple

    @classmethod
    def from_residual(cls, residual: np.ndarray, names, columns, dt_s: float) -> "PhaseSpread | None":
        """Estimate from the baseline residual (n_sensors, N), K, rows named ``names``; None when
        the three phase ``columns`` are not fitted one by one."""
        means = _spreads(residual, names, columns, dt_s)
        if means is None:
            return None
        levels = tuple(float(np.sqrt(np.mean(m ** 2))) for m in means)
        if not all(level > 0 for level in levels):
            raise InputError("baseline", "phase sensors", "their spread residual is exactly zero: no floor for it")
        return cls(tuple(columns), levels)

    def test(self, residual: np.ndarray, names, dt_s: float) -> dict | None:
        """The record's spread residual against the baseline's (module docstring); None when the
        record's fit does not have the three phase sensors.

        Returns
        -------
        dict
            ``unexplained`` (some phase above :data:`PHASE_SPREAD_OVER_FLOOR` × its baseline level),
            ``per_phase`` (``rms_K``, ``floor_K``, ``ratio``), ``threshold`` and ``summary``.
        """
        means = _spreads(residual, names, self.columns, dt_s)
        if means is None:
            return None
        per_phase = {}
        for column, m, level in zip(self.columns, means, self.levels_K):
            rms = float(np.sqrt(np.mean(m ** 2)))
            per_phase[column] = {"rms_K": rms, "floor_K": level, "ratio": rms / level}
        worst = max(per_phase, key=lambda c: per_phase[c]["ratio"])
        unexplained = per_phase[worst]["ratio"] > PHASE_SPREAD_OVER_FLOOR
        summary = (f"The phase sensors disagree in a way the model does not make: {worst} against the other two "
                   f"phases {per_phase[worst]['rms_K']:.3f} K ({SPREAD_WINDOW_S / 60:.0f}-min means), "
                   f"{per_phase[worst]['ratio']:.1f}× its level on the healthy baseline: a heat source or path of "
                   "one phase that no effect found has.") if unexplained else ""
        return {"unexplained": bool(unexplained), "per_phase": per_phase, "threshold": PHASE_SPREAD_OVER_FLOOR,
                "summary": summary}

    def to_dict(self) -> dict:
        return {"columns": list(self.columns), "floor_K": list(self.levels_K), "window_s": SPREAD_WINDOW_S}
