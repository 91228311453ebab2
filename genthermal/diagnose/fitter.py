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
    workers : int
        Processes that fit candidates and pairs side by side (forked,
        :mod:`genthermal.diagnose.parallel`; same results as 1). Workers build their own models
        and simulators, which a Discovery's memo then does not keep: use 1 to fit many records of
        one model, the number of cores for one record.
    pair_starts : tuple of (str, float, str, float)
        Warm starts: when given, only these pairs are fitted, from these onsets (effect, onset s,
        effect, onset s), refined locally (:meth:`~genthermal.diagnose.joint.PairSearch.refit`);
        e.g. the pairs a fit of the same record on other sensors found.
    onset_profiles : bool
        Refine the onsets of the first round's verdict on their profile (the other values and the
        initial state refitted at each onset) and report the interval of onsets the data allow
        (:mod:`genthermal.diagnose.onset_profile`).
    """

    pairs: bool = True
    pair_pool: int = PAIR_POOL
    workers: int = 1
    pair_starts: tuple = ()
    onset_profiles: bool = True

    def __post_init__(self):
        if int(self.pair_pool) != self.pair_pool or self.pair_pool < 2:
            raise InputError("pair_pool", self.pair_pool, "must be an integer >= 2")
        if int(self.workers) != self.workers or self.workers < 1:
            raise InputError("workers", self.workers, "must be an integer >= 1")
        for start in self.pair_starts:
            if (len(start) != 4 or not all(isinstance(start[i], str) for i in (0, 2))
                    or not all(isinstance(start[i], (int, float)) and start[i] >= 0 for i in (1, 3))):
                raise InputError("pair_starts", start, "each must be (effect, onset s >= 0, effect, onset s >= 0)")

    def singles(self, search: EffectSearch) -> list[Candidate]:
        """Every candidate the search's model can take, fitted with its onset; best first."""
        names = search.candidates()
        return search.rank(names, self.workers) if names else []

    def joint(self, search: EffectSearch, singles: list[Candidate],
              progress: Callable[[int, int, str], None] | None = None) -> list:
        """Pairs of ``singles`` fitted jointly (:class:`~genthermal.diagnose.joint.PairSearch`), or
        only those of :attr:`pair_starts` from their onsets; best first."""
        if self.pair_starts:
            return PairSearch(search).refit(singles, self.pair_starts, self.workers, progress)
        return PairSearch(search).rank(singles, self.pair_pool, progress=progress, workers=self.workers)
