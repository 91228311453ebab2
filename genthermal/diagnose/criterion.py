r"""Information criteria that score a candidate explanation against the model without it.

:class:`BIC` and :class:`AIC` give :math:`\Delta = N\ln(RSS_{after}/RSS_{before}) + k\ln N` (BIC) or
:math:`+ 2k` (AIC) and an ``evidence_limit`` of -10 (Kass & Raftery 1995; Burnham & Anderson 2002,
sec. 2.6). A criterion is any object with ``name``, ``evidence_limit`` and
``delta(rss_after, rss_before, n, k)``. Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import math

from ..errors import InputError


def _check(rss_after: float, rss_before: float, n: int, k: int) -> None:
    if not (rss_before > 0 and rss_after > 0):
        raise InputError("rss", (rss_after, rss_before), "residual sums of squares must be > 0 (K²)")
    if n <= k:
        raise InputError("n", n, f"need more samples than fitted parameters ({k})")


@dataclasses.dataclass(frozen=True)
class BIC:
    """Bayesian information criterion (the default).

    Attributes
    ----------
    evidence_limit : float
        A candidate needs ΔBIC below this (default -10, "very strong" evidence).
    """

    evidence_limit: float = -10.0
    name: str = "BIC"

    def delta(self, rss_after: float, rss_before: float, n: int, k: int) -> float:
        """ΔBIC of a change from ``rss_before`` to ``rss_after`` (K²) with ``k`` more parameters
        over ``n`` samples."""
        _check(rss_after, rss_before, n, k)
        return n * math.log(rss_after / rss_before) + k * math.log(n)


@dataclasses.dataclass(frozen=True)
class AIC:
    """Akaike information criterion (penalises parameters less than BIC on long records).

    Attributes
    ----------
    evidence_limit : float
        A candidate needs ΔAIC below this (default -10).
    """

    evidence_limit: float = -10.0
    name: str = "AIC"

    def delta(self, rss_after: float, rss_before: float, n: int, k: int) -> float:
        """ΔAIC of a change from ``rss_before`` to ``rss_after`` (K²) with ``k`` more parameters
        over ``n`` samples."""
        _check(rss_after, rss_before, n, k)
        return n * math.log(rss_after / rss_before) + 2 * k
