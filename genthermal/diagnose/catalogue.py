"""The candidate effects a discovery searches: an immutable, ordered catalogue.

:data:`genthermal.effects.CATALOGUE` is the registry users add effects to by name (model files and
the command line look effects up there). A discovery does not read that registry while it runs: it
takes a :class:`Catalogue`, a frozen snapshot, and a caller who wants more (or fewer) candidates
builds a new one with :meth:`Catalogue.extended` or :meth:`Catalogue.without` — nothing global is
changed, so nothing has to be undone afterwards::

    from genthermal.diagnose import Catalogue, Discovery
    candidates = Catalogue.registered().extended(my_effect).without("frame_cooling_change")
    diagnosis = Discovery(candidates).fit(model, data)
"""

from __future__ import annotations

from typing import Iterable, Iterator, Mapping

from ..effects import CATALOGUE, Effect
from ..errors import InputError


class Catalogue(Mapping[str, Effect]):
    """An immutable mapping of effect name to :class:`~genthermal.effects.Effect`, in search order.

    Parameters
    ----------
    effects : iterable of Effect
        The candidate effects; names must be unique.

    Raises
    ------
    InputError
        When an entry is not an Effect or two effects share a name.
    """

    def __init__(self, effects: Iterable[Effect] = ()):
        entries: dict[str, Effect] = {}
        for effect in effects:
            if not isinstance(effect, Effect):
                raise InputError("candidates", repr(effect), "expected genthermal.effects.Effect objects")
            if effect.name in entries:
                raise InputError("candidates", effect.name, "two candidate effects have this name")
            entries[effect.name] = effect
        self._entries = entries

    @classmethod
    def registered(cls) -> "Catalogue":
        """A snapshot of the registry :data:`genthermal.effects.CATALOGUE` as it is now."""
        return cls(CATALOGUE.values())

    @classmethod
    def of(cls, candidates) -> "Catalogue":
        """``candidates`` as a Catalogue: a Catalogue, a mapping of name to Effect, a sequence of
        Effects, or a sequence of registered effect names."""
        if isinstance(candidates, Catalogue):
            return candidates
        if isinstance(candidates, Mapping):
            return cls(candidates.values())
        if isinstance(candidates, str):
            raise InputError("candidates", candidates, "expected a sequence of effects or names, not one string")
        registered = cls.registered()
        return cls(registered[c] if isinstance(c, str) else c for c in candidates)

    def __getitem__(self, name: str) -> Effect:
        try:
            return self._entries[name]
        except KeyError:
            raise InputError("effect", name, f"not among the candidates: {', '.join(self._entries)}") from None

    def __contains__(self, name) -> bool:
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self) -> str:
        return f"Catalogue({', '.join(self._entries)})"

    @classmethod
    def for_diagnosis(cls) -> "Catalogue":
        """The registered effects with their shape parameters fitted
        (:meth:`~genthermal.effects.Effect.with_shapes_fitted`): the default of a diagnosis."""
        return cls(effect.with_shapes_fitted() for effect in CATALOGUE.values())

    def extended(self, *effects: Effect) -> "Catalogue":
        """A new catalogue with ``effects`` appended (this one is unchanged)."""
        return Catalogue([*self._entries.values(), *effects])

    def without(self, *names: str) -> "Catalogue":
        """A new catalogue without the effects called ``names`` (each must be present)."""
        for name in names:
            self[name]  # raises InputError naming the candidates when absent
        return Catalogue(e for n, e in self._entries.items() if n not in names)

    def only(self, names: Iterable[str]) -> "Catalogue":
        """A new catalogue of the effects called ``names`` (each must be present), in this order."""
        return Catalogue(self[name] for name in names)

    def applicable(self, model) -> "Catalogue":
        """The effects ``model`` can still take (:meth:`~genthermal.effects.Effect.unavailable_reason`)."""
        return Catalogue(e for e in self._entries.values() if e.unavailable_reason(model) is None)
