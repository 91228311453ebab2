r"""A lumped-parameter thermal network: nodes, links, air streams and heat sources.

:class:`Network` is immutable data with sympy expressions (:class:`Node`, :class:`Link`,
:class:`AirStream`, :class:`HeatSource`): the energy balance of every node is
:math:`C_i \dot\theta_i` = conduction and convection (symmetric) + air streams entering it
(directed) + its heat sources. :meth:`Network.replace` returns a modified copy, which is how a
physical effect transforms a model; :mod:`genthermal.model` turns it into CasADi functions.
Thesis section 4.2; the energy balance: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
from typing import Iterable

import sympy

from .errors import InputError

NODE_KINDS = ("capacitive", "massless", "boundary")


@dataclasses.dataclass(frozen=True)
class Node:
    """A network node.

    Parameters
    ----------
    name : str
        Self-explaining identifier (``"stator_winding"``).
    kind : str
        ``"capacitive"`` (has heat capacity, becomes a state), ``"massless"`` (no heat capacity:
        an intermediate or surface node, or an air node) or ``"boundary"`` (temperature imposed by
        an input).
    capacitance : sympy.Expr or None
        Heat capacity in J/K (capacitive nodes only).
    role : str
        Free description used in reports (``"air"``, ``"intermediate"``, ``"solid"``, the input
        name for boundaries).
    """

    name: str
    kind: str
    capacitance: sympy.Expr | None = None
    role: str = ""

    def __post_init__(self):
        if self.kind not in NODE_KINDS:
            raise InputError(f"node {self.name}.kind", self.kind, f"must be one of {NODE_KINDS}")
        if (self.kind == "capacitive") != (self.capacitance is not None):
            raise InputError(f"node {self.name}.capacitance", self.capacitance,
                             "a capacitive node needs a capacitance and only a capacitive node has one")


@dataclasses.dataclass(frozen=True)
class Link:
    """A symmetric conduction or convection path between two nodes.

    Parameters
    ----------
    a, b : str
        Node names.
    resistance : sympy.Expr
        Thermal resistance in K/W (series elements are summed into one expression).
    label : str
        Where the formula comes from (``"eq. 4.4 + eq. 4.39"``).
    """

    a: str
    b: str
    resistance: sympy.Expr
    label: str = ""


@dataclasses.dataclass(frozen=True)
class AirStream:
    """A directed air stream carrying heat from ``upstream`` to ``downstream``.

    Parameters
    ----------
    upstream, downstream : str
        Node names; the stream adds :math:`c_{air}\\dot m(\\theta_{up} - \\theta_{down})` to the
        downstream node's balance and nothing to the upstream node's.
    resistance : sympy.Expr
        :math:`1/(c_{air}\\dot m)` in K/W (eq. 4.38).
    label : str
        Description.
    """

    upstream: str
    downstream: str
    resistance: sympy.Expr
    label: str = ""


@dataclasses.dataclass(frozen=True)
class HeatSource:
    """Heat injected into a node, in W.

    Parameters
    ----------
    node : str
        Receiving node.
    power : sympy.Expr
        Power in W as a sympy expression of parameter symbols, input symbols (``I_u``, ``I_exc``,
        ...) and node temperature symbols ``theta_<node>`` (°C).
    label : str
        Name of the loss (``"copper"``, ``"iron"``), used to report losses by kind.
    """

    node: str
    power: sympy.Expr
    label: str = ""


@dataclasses.dataclass(frozen=True)
class Network:
    """An immutable thermal network.

    Parameters
    ----------
    nodes : tuple of Node
    links : tuple of Link
    air_streams : tuple of AirStream
    heat_sources : tuple of HeatSource
    """

    nodes: tuple[Node, ...]
    links: tuple[Link, ...]
    air_streams: tuple[AirStream, ...] = ()
    heat_sources: tuple[HeatSource, ...] = ()

    def __post_init__(self):
        names = [n.name for n in self.nodes]
        duplicates = sorted({n for n in names if names.count(n) > 1})
        if duplicates:
            raise InputError("network.nodes", duplicates, "node names must be unique")
        known = set(names)
        for i, link in enumerate(self.links):
            for end in (link.a, link.b):
                if end not in known:
                    raise InputError(f"network.links[{i}]", end, "unknown node")
            if link.a == link.b:
                raise InputError(f"network.links[{i}]", link.a, "a link needs two different nodes")
        for i, stream in enumerate(self.air_streams):
            for end in (stream.upstream, stream.downstream):
                if end not in known:
                    raise InputError(f"network.air_streams[{i}]", end, "unknown node")
        for i, source in enumerate(self.heat_sources):
            if source.node not in known or self.node(source.node).kind == "boundary":
                raise InputError(f"network.heat_sources[{i}].node", source.node,
                                 "must be a capacitive or massless node")

    # --- queries --------------------------------------------------------------------------
    def node(self, name: str) -> Node:
        """Return the node called ``name``."""
        for node in self.nodes:
            if node.name == name:
                return node
        raise InputError("node", name, f"unknown node; known: {', '.join(n.name for n in self.nodes)}")

    def names(self, kind: str) -> list[str]:
        """Return the names of the nodes of ``kind`` in network order."""
        return [n.name for n in self.nodes if n.kind == kind]

    @property
    def state_names(self) -> list[str]:
        """Names of the capacitive nodes, i.e. the model states, in order."""
        return self.names("capacitive")

    def reduction_stages(self) -> dict[str, int]:
        """Node counts of thesis section 4.2.4: all internal nodes, after eliminating the
        intermediate (solid) massless nodes, and after eliminating the air nodes too."""
        internal = [n for n in self.nodes if n.kind != "boundary"]
        air = [n for n in internal if n.kind == "massless" and n.role == "air"]
        intermediate = [n for n in internal if n.kind == "massless" and n.role != "air"]
        return {"all_nodes": len(internal),
                "without_intermediate": len(internal) - len(intermediate),
                "states": len(internal) - len(intermediate) - len(air)}

    def temperature_symbol(self, node: str) -> sympy.Symbol:
        """The sympy symbol ``theta_<node>`` (°C) used in heat-source expressions."""
        self.node(node)
        return sympy.Symbol(f"theta_{node}", real=True)

    def links_between(self, a: str, b: str) -> list[Link]:
        """All links joining nodes ``a`` and ``b`` (either direction)."""
        return [l for l in self.links if {l.a, l.b} == {a, b}]

    # --- transformations ------------------------------------------------------------------
    def replace(self, **changes) -> "Network":
        """Return a copy with fields replaced (``links=...``, ``heat_sources=...``)."""
        return dataclasses.replace(self, **changes)

    def with_heat_sources(self, sources: Iterable[HeatSource]) -> "Network":
        """Return a copy with ``sources`` added to the existing heat sources."""
        return self.replace(heat_sources=self.heat_sources + tuple(sources))

    def scale_air_streams(self, factor: sympy.Expr) -> "Network":
        """Return a copy with every air mass flow multiplied by ``factor`` (resistances divided)."""
        streams = tuple(dataclasses.replace(s, resistance=s.resistance / factor)
                        for s in self.air_streams)
        return self.replace(air_streams=streams)

    def substitute_in_links(self, substitutions: dict) -> "Network":
        """Return a copy with ``substitutions`` (sympy symbol → expression) applied to every link
        resistance (e.g. a convection coefficient replaced by a flow-dependent expression)."""
        links = tuple(dataclasses.replace(l, resistance=l.resistance.subs(substitutions)) for l in self.links)
        return self.replace(links=links)

    def scale_links(self, a: str, b: str, conductance_factor: sympy.Expr) -> "Network":
        """Return a copy with the conductance of every link between ``a`` and ``b`` multiplied by
        ``conductance_factor``."""
        if not self.links_between(a, b):
            raise InputError("link", f"{a}--{b}", "no link joins these nodes")
        links = tuple(dataclasses.replace(l, resistance=l.resistance / conductance_factor)
                      if {l.a, l.b} == {a, b} else l for l in self.links)
        return self.replace(links=links)
