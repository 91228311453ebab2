"""How a discovery fits its candidates: single effects with their onsets, then pairs jointly.

:class:`OnsetFitter` is the ``fitter`` part of :class:`~genthermal.diagnose.discovery.Discovery`:
the single-effect search of :mod:`genthermal.diagnose.search` and the joint pair search of
:mod:`genthermal.diagnose.joint`, with the settings a caller may change.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

from ..errors import InputError
from .joint import PAIR_POOL, PairSearch
from .search import Candidate, EffectSearch


@dataclasses.dataclass(frozen=True)
class OnsetFitter:
    """Settings of the effect and onset fits.

    Attributes
    ----------
    pairs : bool
        In the first round, when the best single effect leaves a residual that is not noise, fit
        pairs of effects jointly (values and both onsets).
    pair_pool : int
        Pairs are formed among this many best single effects (and the best with each other one).
    """

    pairs: bool = True
    pair_pool: int = PAIR_POOL

    def __post_init__(self):
        if int(self.pair_pool) != self.pair_pool or self.pair_pool < 2:
            raise InputError("pair_pool", self.pair_pool, "must be an integer >= 2")

    def singles(self, search: EffectSearch) -> list[Candidate]:
        """Every candidate the search's model can take, fitted with its onset; best first."""
        names = search.candidates()
        return search.rank(names) if names else []

    def joint(self, search: EffectSearch, singles: list[Candidate],
              progress: Callable[[int, int, str], None] | None = None) -> list:
        """Pairs of ``singles`` fitted jointly (:class:`~genthermal.diagnose.joint.PairSearch`); best first."""
        return PairSearch(search).rank(singles, self.pair_pool, progress=progress)
