r"""Information criteria that score a candidate explanation against the model without it.

With :math:`N` valid sensor samples, residual sums of squares :math:`RSS` before and after and
:math:`k` fitted parameters (onsets included), for Gaussian errors of unknown variance

.. math::
    \Delta\mathrm{BIC} = N\ln\frac{RSS_{after}}{RSS_{before}} + k\ln N, \qquad
    \Delta\mathrm{AIC} = N\ln\frac{RSS_{after}}{RSS_{before}} + 2k .

A candidate is evidence-worthy when the change is below the criterion's ``evidence_limit``
(-10: "very strong" evidence for BIC, Kass & Raftery 1995; "essentially no support" for the
model without the effect for AIC, Burnham & Anderson 2002, sec. 2.6). A criterion is any object
with ``name``, ``evidence_limit`` and ``delta(rss_after, rss_before, n, k)``.

References
----------
Kass, R. E., Raftery, A. E. (1995). Bayes factors. J. Am. Stat. Assoc. 90(430), 773-795.
Burnham, K. P., Anderson, D. R. (2002). Model Selection and Multimodel Inference, 2nd ed. Springer.
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
