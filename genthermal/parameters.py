"""Named model parameters that carry their value, unit, bounds and provenance.

Every number that enters a thermal model is a :class:`Parameter`: the symbol used in the element
formulas, the value in SI units, where the value came from (a thesis table, the literature, an
assumption, a fit) and one line saying why. A :class:`ParameterSet` is an ordered, immutable
collection of them; it refuses a non-physical value (a negative length, a zero conductivity, a
negative mass flow) when it is built, with an error that names the parameter and the value.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from typing import Iterable, Iterator, Mapping

import sympy

from .errors import ParameterError

#: Allowed provenance categories, from best to worst known.
PROVENANCES = ("thesis", "literature", "fitted", "assumed")


@dataclasses.dataclass(frozen=True)
class Parameter:
    """One named model parameter.

    Parameters
    ----------
    name : str
        Symbol name used in the element formulas (``"L_s"``, ``"k_cr"``).
    value : float
        Value in the SI unit given by ``unit``.
    unit : str
        SI unit (``"m"``, ``"W/(m K)"``, ``"kg/s"``, ``"1"`` for dimensionless).
    provenance : str
        One of :data:`PROVENANCES`.
    source : str
        Where exactly (``"thesis Table 4.2"``) and, for assumed values, why this value.
    lower, upper : float
        Physical bounds; ``lower`` is exclusive when ``lower_inclusive`` is false.
    """

    name: str
    value: float
    unit: str
    provenance: str
    source: str
    lower: float = 0.0
    upper: float = math.inf
    lower_inclusive: bool = False

    def __post_init__(self):
        if self.provenance not in PROVENANCES:
            raise ParameterError(f"{self.name}.provenance", self.provenance,
                                 f"must be one of {', '.join(PROVENANCES)}")
        try:
            value = float(self.value)
        except (TypeError, ValueError):
            raise ParameterError(self.name, self.value, f"must be a number in {self.unit}") from None
        object.__setattr__(self, "value", value)
        self.check(value)

    def check(self, value: float) -> None:
        """Raise :class:`ParameterError` if ``value`` is outside this parameter's physical range."""
        if not math.isfinite(value):
            raise ParameterError(self.name, value, f"must be a finite number in {self.unit}")
        below = value < self.lower if self.lower_inclusive else value <= self.lower
        if below or value > self.upper:
            low = "[" if self.lower_inclusive else "("
            raise ParameterError(
                self.name, value,
                f"not physical: must lie in {low}{self.lower:g}, {self.upper:g}] {self.unit}")

    @property
    def symbol(self) -> sympy.Symbol:
        """The sympy symbol of this parameter: positive when its range is, else real."""
        if self.lower >= 0:
            return sympy.Symbol(self.name, positive=True)
        return sympy.Symbol(self.name, real=True)

    def replace(self, **changes) -> "Parameter":
        """Return a copy with ``changes`` applied (bounds re-checked)."""
        return dataclasses.replace(self, **changes)


class ParameterSet(Mapping[str, Parameter]):
    """An immutable, ordered collection of :class:`Parameter` keyed by name.

    Parameters
    ----------
    parameters : iterable of Parameter
        Names must be unique.
    """

    def __init__(self, parameters: Iterable[Parameter]):
        self._items: dict[str, Parameter] = {}
        for parameter in parameters:
            if parameter.name in self._items:
                raise ParameterError(parameter.name, parameter.value, "defined twice")
            self._items[parameter.name] = parameter

    def __getitem__(self, name: str) -> Parameter:
        try:
            return self._items[name]
        except KeyError:
            raise ParameterError("parameter", name, self._unknown_hint(name)) from None

    def __contains__(self, name) -> bool:
        return name in self._items

    def __iter__(self) -> Iterator[str]:
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def _unknown_hint(self, name: str) -> str:
        close = difflib.get_close_matches(name, list(self._items), n=3)
        hint = f" (did you mean {', '.join(close)}?)" if close else ""
        return f"unknown parameter{hint}"

    def value(self, name: str) -> float:
        """Return the value of parameter ``name`` in its SI unit."""
        return self[name].value

    def values(self) -> dict[str, float]:  # type: ignore[override]
        """Return ``{name: value}`` for every parameter."""
        return {name: p.value for name, p in self._items.items()}

    def symbols(self) -> dict[str, sympy.Symbol]:
        """Return ``{name: sympy symbol}`` for every parameter."""
        return {name: p.symbol for name, p in self._items.items()}

    def with_values(self, provenance: str = "fitted", source: str = "", **values: float) -> "ParameterSet":
        """Return a copy with new values for the named parameters.

        Parameters
        ----------
        provenance : str
            Provenance recorded for the changed values (default ``"fitted"``).
        source : str
            Why the values changed; defaults to the previous source.
        **values : float
            New values by parameter name. Unknown names and non-physical values are refused.
        """
        new = dict(self._items)
        for name, value in values.items():
            old = self[name]
            new[name] = old.replace(value=value, provenance=provenance,
                                    source=source or old.source)
        return ParameterSet(new.values())

    def with_parameters(self, *extra: Parameter) -> "ParameterSet":
        """Return a copy with ``extra`` parameters appended (names must be new)."""
        return ParameterSet([*self._items.values(), *extra])

    def table(self) -> "list[dict[str, object]]":
        """Return one row per parameter: name, value, unit, provenance, source."""
        return [
            {"name": p.name, "value": p.value, "unit": p.unit,
             "provenance": p.provenance, "source": p.source}
            for p in self._items.values()
        ]
