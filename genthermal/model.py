"""ThermalModel: one network + one parameter set → CasADi functions every consumer shares.

:class:`ThermalModel` assembles the network (thesis eq. 4.44), eliminates the massless nodes
exactly (Schur complement) and keeps everything symbolic in the parameters, so its Jacobians with
respect to states, inputs and parameters are exact. Its discrete step is
:mod:`genthermal.discretise`. Guide: ``docs/guide/model.md``; the assembly: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np
import sympy

from .errors import InputError, ParameterError
from .losses import LossFloor, input_symbol
from .network import Network
from .parameters import ParameterSet

if TYPE_CHECKING:
    from .machines.interface import MachineInterface

#: Most network structures whose compiled CasADi functions are kept for reuse in one process
#: (:class:`StructureCache`). A flight with fault identification builds a few dozen models on a
#: handful of structures (nominal, each catalogue effect, the design variants); a robustness
#: sweep flies many such flights in one worker process.
STRUCTURE_CACHE_SIZE = 128

#: A steady state this far below the coldest boundary temperature (K) is the non-physical root of a
#: thermal runaway: the model has no heat sinks, and no loss cools a machine 50 K below its air.
COLDEST_STEADY_STATE_BELOW_K = 50.0

_CASADI_FUNCTIONS = {"log": ca.log, "exp": ca.exp, "sqrt": ca.sqrt, "Abs": ca.fabs,
                     "Max": ca.fmax, "Min": ca.fmin, "Heaviside": lambda v: ca.if_else(v >= 0, 1, 0),
                     "LossFloor": lambda v: ca.fmax(v, 0)}


#: Compiled evaluators of single sympy expressions: (expression, loss_floors) → (the symbols it
#: reads, function of them). Models derived from one another (an effect adds a heat source or
#: scales one link) share almost every expression, and writing each evaluator's source
#: (``sympy.lambdify``) is most of the cost of building a model; a cached evaluator builds the same
#: CasADi expression from the new model's symbols.
_EVALUATORS: dict = {}
#: Bound on the cached evaluators (the cache is emptied when it holds more).
_MAX_EVALUATORS = 20000


def _evaluator(expression, loss_floors: bool | None):
    """``(symbols, sympy.lambdify(symbols, expression))``, ``symbols`` the free symbols of
    ``expression`` by name: into CasADi functions (``loss_floors`` True or False, see
    :func:`to_casadi`) or, for ``None``, into numpy; cached (see :data:`_EVALUATORS`)."""
    key = (expression, loss_floors)
    if key not in _EVALUATORS:
        if len(_EVALUATORS) >= _MAX_EVALUATORS:
            _EVALUATORS.clear()
        if loss_floors is None:
            modules = ["numpy"]
        else:
            modules = [_CASADI_FUNCTIONS if loss_floors else {**_CASADI_FUNCTIONS, "LossFloor": lambda v: v}, "math"]
        symbols = tuple(sorted(expression.free_symbols, key=str))
        _EVALUATORS[key] = (symbols, sympy.lambdify(symbols, expression, modules=modules))
    return _EVALUATORS[key]


def to_casadi(expressions, symbols, values, loss_floors: bool = True):
    """Evaluate sympy ``expressions`` with ``symbols`` replaced by CasADi ``values``.

    Parameters
    ----------
    expressions : list of sympy.Expr
    symbols : list of sympy.Symbol
    values : list of casadi.SX
        Same length as ``symbols``.
    loss_floors : bool
        Apply :class:`~genthermal.losses.LossFloor` (True) or take it as the identity: the affine
        branch of a design model (False).

    Returns
    -------
    list of casadi.SX
        One per expression: what ``sympy.lambdify`` of the expression evaluates to, from an
        evaluator cached across models (:data:`_EVALUATORS`).
    """
    value_of = dict(zip(symbols, values))
    results = []
    for expression in expressions:
        used, evaluate = _evaluator(sympy.sympify(expression), bool(loss_floors))
        missing = [s for s in used if s not in value_of]
        if missing:
            raise InputError("expression", str(expression), f"reads {', '.join(map(str, missing))}, not given a value")
        results.append(evaluate(*(value_of[s] for s in used)))
    return [ca.SX(v) if not isinstance(v, ca.SX) else v for v in results]


@dataclasses.dataclass(frozen=True)
class ModelSpec:
    """What a ThermalModel needs beyond network and parameters.

    Attributes
    ----------
    name : str
        Machine name (``"genco_rf201a"``).
    interface : MachineInterface
        The machine's inputs, sensors, ratings, limits and roles
        (:class:`genthermal.machines.interface.MachineInterface`); consumers read them here.
    variant : str
        ``"nonlinear"`` (simulation model) or ``"linear"`` (design model).
    effects : tuple of str
        Names of the effects applied to this model, in order.
    onsets : tuple of (str, float)
        Effects that start during a record: (effect name, onset in s after the record's first
        sample). Before its onset such an effect is at its neutral values; see
        :func:`genthermal.onsets.onset_switches`, which :func:`genthermal.simulate.simulate` uses.
    machine_source : str
        How to build the machine again (a built-in or entry-point name, or the path of a machine
        file): model files record it. Default: ``name``.
    """

    name: str
    interface: "MachineInterface"
    variant: str = "nonlinear"
    effects: tuple = ()
    onsets: tuple = ()
    machine_source: str = ""

    @property
    def sensors(self) -> dict:
        """Output name → node name."""
        return self.interface.sensor_nodes

    @property
    def boundary_inputs(self) -> dict:
        """Boundary node → input name."""
        return dict(self.interface.boundary_inputs)

    @property
    def outlet_node(self) -> str | None:
        """Coolant node reported as the outlet sensor's column, or None."""
        return self.interface.outlet_node

    @property
    def rated_current_A(self) -> float:
        """Rated RMS current of the load-current inputs, A."""
        return float(self.interface.rated_current_A)

    @property
    def roles(self) -> dict:
        """:class:`~genthermal.machines.interface.Role` → the machine's value for it."""
        return self.interface.roles

    def structure(self) -> "ModelSpec":
        """The spec without its onsets: what the compiled functions depend on."""
        return dataclasses.replace(self, onsets=())


def kron_reduce(G: dict, r: dict, massless) -> list:
    r"""Eliminate massless nodes from the balance ``0 = sum_j G[k][j] theta_j + r[k]`` in place.

    Node by node (fewest couplings first, so the fill-in stays small), row ``k`` gives
    :math:`\theta_k = -(\sum_{j\ne k} G_{kj}\theta_j + r_k)/G_{kk}`, which is substituted into
    every row that couples to ``k``. This is the Schur complement computed with the network's
    sparsity (an 11-node symbolic ``solve`` fills in densely).

    Returns
    -------
    list of (k, row, diagonal, remainder)
        Elimination record for back-substitution, in elimination order.
    """
    remaining = set(massless)
    record = []
    while remaining:
        k = min(remaining, key=lambda node: (len(G[node]), node))
        remaining.remove(k)
        row = G.pop(k)
        diagonal = row.pop(k)
        remainder = r.pop(k)
        record.append((k, row, diagonal, remainder))
        for i, coupling in G.items():
            g_ik = coupling.pop(k, None)
            if g_ik is None:
                continue
            factor = g_ik / diagonal
            for j, g_kj in row.items():
                coupling[j] = coupling.get(j, 0) - factor * g_kj
            r[i] = r[i] - factor * remainder
    return record


class StructureCache:
    """Compiled CasADi functions by model structure, shared by every model of one process.

    The symbolic model depends on the network, the spec without its onsets and the parameter
    names and symbols, not on the parameter values (:meth:`ThermalModel.__init__`). Models made
    by :meth:`ThermalModel.with_network` (every effect, every design variant, every candidate of
    an identification) get a new network object each time; when it equals one already compiled,
    its functions are reused instead of compiled again (sympy printing, CasADi Jacobians: about
    0.3-1 s per model). At most ``size`` structures are kept, the least recently used dropped.

    Parameters
    ----------
    size : int
        Structures kept.
    """

    def __init__(self, size: int = STRUCTURE_CACHE_SIZE):
        if int(size) != size or size < 1:
            raise InputError("structure cache size", size, "must be an integer >= 1")
        self.size = int(size)
        self._entries: list[tuple[int, tuple, dict]] = []  # (hash of the network, key, functions), newest last
        self.hits = self.misses = 0

    @staticmethod
    def key(network: Network, spec: "ModelSpec", parameters: ParameterSet) -> tuple:
        """What the compiled functions depend on: network, spec without onsets, parameter names
        and symbols in order."""
        names = tuple(parameters)
        return network, spec.structure(), names, tuple(parameters[n].symbol for n in names)

    def shared(self, key: tuple) -> dict:
        """The dict of compiled functions for ``key`` (an empty one, kept, when it is new)."""
        network_hash = hash(key[0])
        for i, (known_hash, known, shared) in enumerate(self._entries):
            if known_hash == network_hash and known == key:
                self._entries.append(self._entries.pop(i))
                self.hits += 1
                return shared
        self.misses += 1
        shared: dict = {}
        self._entries.append((network_hash, key, shared))
        del self._entries[:-self.size]
        return shared


#: The process's :class:`StructureCache`.
STRUCTURES = StructureCache()
#: The reduced equations of each network, whatever sensors read it (:meth:`ThermalModel._symbolic`):
#: a model with one more sensor on the same network (a record's outlet sensor, fitted by a
#: diagnosis) compiles its functions again, but not its equations.
EQUATIONS = StructureCache()


class ThermalModel:
    """A thermal network with numeric parameters, compiled to CasADi functions.

    Parameters
    ----------
    network : Network
        Nodes, links, air streams, heat sources (sympy).
    parameters : ParameterSet
        Values (with provenance) of every symbol the network uses.
    spec : ModelSpec
        Sensors, boundary inputs and variant.

    Notes
    -----
    States :math:`x` are the capacitive node temperatures in °C (``state_names``); inputs
    :math:`u` are ``input_names``, the machine's inputs (``spec.interface.inputs``, with units); parameters :math:`p` are the values of
    ``parameters`` in order (``parameter_names``). Building the model checks every resistance,
    capacitance and mass flow for physical values and the reduced system for stability.
    """

    def __init__(self, network: Network, parameters: ParameterSet, spec: ModelSpec,
                 _share_from: "ThermalModel | None" = None):
        self.network = network
        self.parameters = parameters
        self.spec = spec
        self.state_names = network.state_names
        self.massless_names = network.names("massless")
        self.boundary_names = network.names("boundary")
        self.input_names = spec.interface.input_names
        self.parameter_names = list(parameters)
        self.output_names = list(spec.interface.output_names)
        self._discrete: dict = {}
        #: What the last calibration left for a filter on this model to start from
        #: (:class:`~genthermal.estimation.disturbance_prior.DisturbancePrior`), or None;
        #: set by :meth:`with_disturbance_prior`, dropped by every change of parameters or network.
        self.disturbance_prior = None
        # the symbolic model depends on network and parameter order only, not on the values:
        # a model that differs from another only in parameter values shares its CasADi functions,
        # and so does one on an equal network built again (StructureCache)
        same_structure = (_share_from is not None and _share_from.network is network
                          and _share_from.spec.structure() == spec.structure()
                          and _share_from.parameter_names == self.parameter_names)
        self._shared: dict = (_share_from._shared if same_structure else
                              STRUCTURES.shared(StructureCache.key(network, spec, parameters)))
        for output, node in spec.sensors.items():
            network.node(node)
        for node, name in spec.boundary_inputs.items():
            if network.node(node).kind != "boundary" or name not in self.input_names:
                raise InputError(f"boundary_inputs[{node!r}]", name, "must map a boundary node to an input")
        missing = set(self.boundary_names) - set(spec.boundary_inputs)
        if missing:
            raise InputError("boundary_inputs", sorted(missing), "boundary nodes without an input")
        self._check_physical()
        self._check_stable()

    # --- construction helpers --------------------------------------------------------------
    @property
    def name(self) -> str:
        """Machine name and variant, e.g. ``genco_rf201a (nonlinear)``."""
        return f"{self.spec.name} ({self.spec.variant})"

    @property
    def n_states(self) -> int:
        """Number of states (capacitive nodes)."""
        return len(self.state_names)

    @functools.cached_property
    def p0(self) -> np.ndarray:
        """Parameter values in ``parameter_names`` order."""
        return np.array([self.parameters.value(n) for n in self.parameter_names])

    def _shared_value(self, key: str, build):
        if key not in self._shared:
            self._shared[key] = build()
        return self._shared[key]

    def _element_values(self):
        """Labelled capacitance and resistance expressions and a numeric function of p for them."""
        net = self.network
        labelled = [(f"capacitance of node {n.name}", n.capacitance) for n in net.nodes if n.kind == "capacitive"]
        labelled += [(f"resistance of link {l.a}--{l.b} ({l.label})", l.resistance) for l in net.links]
        labelled += [(f"resistance of air stream {s.upstream}->{s.downstream} ({s.label})", s.resistance)
                     for s in net.air_streams]
        symbols = [self.parameters[n].symbol for n in self.parameter_names]
        evaluators = [_evaluator(sympy.sympify(expr), None) for _, expr in labelled]

        def evaluate(*values):
            value_of = dict(zip(symbols, values))
            return [function(*(value_of[s] for s in used)) for used, function in evaluators]

        return labelled, evaluate

    def heat_capacities(self) -> np.ndarray:
        """Heat capacity (J/K) of every state node, in ``state_names`` order, from the compiled
        element values (substituting the parameters into the sympy expressions takes about 1 s)."""
        labelled, evaluate = self._shared_value("elements", self._element_values)
        values = np.asarray(evaluate(*self.p0), dtype=float)
        by_node = {what[len("capacitance of node "):]: value for (what, _), value in zip(labelled, values)
                   if what.startswith("capacitance of node ")}
        return np.array([by_node[name] for name in self.state_names])

    def _check_physical(self) -> None:
        labelled, evaluate = self._shared_value("elements", self._element_values)
        values = np.asarray(evaluate(*self.p0), dtype=float)
        for (what, expr), value in zip(labelled, values):
            if not (np.isfinite(value) and value > 0):
                names = sorted(str(s) for s in expr.free_symbols)
                raise ParameterError(what, float(value),
                                     f"not physical (must be > 0); it depends on {', '.join(names)}")

    def _check_stable(self) -> None:
        A = self.jacobian_x(np.zeros(self.n_states), np.zeros(len(self.input_names)))
        worst = float(np.max(np.linalg.eigvals(A).real))
        if worst >= 0:
            raise ParameterError("network", worst, "the reduced system is not stable (largest eigenvalue "
                                 "real part >= 0): check the links to the boundaries")

    @property
    def _symbolic(self) -> dict:
        """SX expressions of the reduced model (built once per network structure)."""
        return self._shared_value("symbolic", self._build_symbolic)

    @property
    def _affine_branch(self) -> dict:
        """:attr:`_symbolic` with every loss floor taken as the identity (the same when there is none)."""
        if not any(source.power.has(LossFloor) for source in self.network.heat_sources):
            return self._symbolic
        return self._shared_value("affine_branch", lambda: self._build_symbolic(loss_floors=False))

    def _build_symbolic(self, loss_floors: bool = True) -> dict:
        """:meth:`_build_equations` (shared by the models of one network whatever their sensors,
        :data:`EQUATIONS`) with the sensor outputs ``y``."""
        key = (self.network, tuple(self.input_names), tuple(sorted(self.spec.boundary_inputs.items())),
               tuple(self.parameter_names), tuple(self.parameters[n].symbol for n in self.parameter_names))
        equations = EQUATIONS.shared(key)
        if loss_floors not in equations:
            equations[loss_floors] = self._build_equations(loss_floors)
        s = equations[loss_floors]
        index = {name: i for i, name in enumerate(s["internal"])}
        return {**s, "y": s["nodes"][[index[self.spec.sensors[o]] for o in self.output_names]]}

    def _build_equations(self, loss_floors: bool = True) -> dict:
        """SX state equations ``xdot`` and internal node temperatures ``nodes`` of (x, u, p), the
        total source heat ``heat``: every sensor-independent part of :attr:`_symbolic`."""
        net = self.network
        x = ca.SX.sym("x", self.n_states)
        u = ca.SX.sym("u", len(self.input_names))
        p = ca.SX.sym("p", len(self.parameter_names))
        internal = self.state_names + self.massless_names
        index = {name: i for i, name in enumerate(internal)}
        theta_internal = ca.SX.sym("theta", len(internal))  # placeholder for all internal temps
        symbols = [self.parameters[n].symbol for n in self.parameter_names]
        symbols += [input_symbol(n) for n in self.input_names]
        symbols += [net.temperature_symbol(n) for n in internal]
        values = [p[i] for i in range(p.numel())] + [u[i] for i in range(u.numel())]
        values += [theta_internal[i] for i in range(len(internal))]
        link_R = to_casadi([l.resistance for l in net.links], symbols, values)
        stream_R = to_casadi([s.resistance for s in net.air_streams], symbols, values)
        caps = to_casadi([net.node(n).capacitance for n in self.state_names], symbols, values)
        powers = to_casadi([s.power for s in net.heat_sources], symbols, values, loss_floors)

        # sparse conductance rows: G[i][j] (W/K) and the remainder r[i] = (G_b b + q)_i (W)
        G: dict[int, dict[int, ca.SX]] = {i: {} for i in range(len(internal))}
        r = {i: ca.SX(0) for i in range(len(internal))}

        def couple(row, column, g):
            if column in index:
                G[row][index[column]] = G[row].get(index[column], 0) + g
            else:
                boundary_input = self.spec.boundary_inputs[column]
                r[row] = r[row] + g * u[self.input_names.index(boundary_input)]

        for link, R in zip(net.links, link_R):
            for me, other in ((link.a, link.b), (link.b, link.a)):
                if me in index:
                    G[index[me]][index[me]] = G[index[me]].get(index[me], 0) - 1 / R
                    couple(index[me], other, 1 / R)
        for stream, R in zip(net.air_streams, stream_R):
            down = index[stream.downstream]
            G[down][down] = G[down].get(down, 0) - 1 / R
            couple(down, stream.upstream, 1 / R)
        nx = self.n_states
        q = ca.SX.zeros(len(internal))
        for source, power in zip(net.heat_sources, powers):
            q[index[source.node]] += power
        # heat sources may depend on state temperatures only: massless temperatures are unknown
        # until the elimination
        if ca.depends_on(q, theta_internal[nx:]):
            raise InputError("heat_sources", "theta of a massless node", "heat sources may depend on "
                             "capacitive node temperatures only")
        q = ca.substitute(q, theta_internal[:nx], x)
        for i in r:
            r[i] = r[i] + q[i]
        eliminated = kron_reduce(G, r, range(nx, len(internal)))
        xdot = ca.vertcat(*[(sum(G[i][j] * x[j] for j in G[i]) + r[i]) / caps[i] for i in range(nx)])
        theta = {i: x[i] for i in range(nx)}
        for k, row, diagonal, remainder in reversed(eliminated):
            theta[k] = -(sum(g * theta[j] for j, g in row.items()) + remainder) / diagonal
        nodes = ca.vertcat(*[theta[i] for i in range(len(internal))])
        return {"x": x, "u": u, "p": p, "xdot": xdot, "nodes": nodes, "heat": ca.sum1(q), "internal": internal}

    # --- CasADi functions ------------------------------------------------------------------
    @property
    def functions(self) -> dict[str, ca.Function]:
        """CasADi functions of the continuous model, all of ``(x, u, p)``.

        ``rhs`` → dx/dt (K/s); ``jac_x``, ``jac_u``, ``jac_p`` → its exact Jacobians;
        ``nodes`` → temperatures of all internal nodes (states then massless, °C); ``outputs`` →
        sensor temperatures (°C); ``heat`` → total heat injected by the sources (W).
        """
        return self._shared_value("functions", self._build_functions)

    def _build_functions(self) -> dict[str, ca.Function]:
        s = self._symbolic
        args, names = [s["x"], s["u"], s["p"]], ["x", "u", "p"]
        f = {
            "rhs": ca.Function("rhs", args, [s["xdot"]], names, ["xdot"]),
            "jac_x": ca.Function("jac_x", args, [ca.jacobian(s["xdot"], s["x"])], names, ["dxdot_dx"]),
            "jac_u": ca.Function("jac_u", args, [ca.jacobian(s["xdot"], s["u"])], names, ["dxdot_du"]),
            "jac_p": ca.Function("jac_p", args, [ca.jacobian(s["xdot"], s["p"])], names, ["dxdot_dp"]),
            "nodes": ca.Function("nodes", args, [s["nodes"]], names, ["theta"]),
            "outputs": ca.Function("outputs", args, [s["y"]], names, ["y"]),
            "heat": ca.Function("heat", args, [s["heat"]], names, ["power"]),
        }
        branch = self._affine_branch
        f["rhs_affine_branch"] = ca.Function("rhs_affine_branch", [branch["x"], branch["u"], branch["p"]],
                                             [branch["xdot"]], names, ["xdot"])
        return f

    @property
    def node_order(self) -> list[str]:
        """Names of the values returned by ``functions["nodes"]``."""
        return self._symbolic["internal"]

    def _call(self, name, x, u, p=None) -> np.ndarray:
        p = self.p0 if p is None else p
        return np.asarray(self.functions[name](x, u, p))

    def rhs(self, x, u, p=None) -> np.ndarray:
        """dx/dt in K/s at state ``x`` (°C) and input ``u``; ``p`` defaults to the model's values."""
        return self._call("rhs", x, u, p).ravel()

    def jacobian_x(self, x, u, p=None) -> np.ndarray:
        """Exact ∂(dx/dt)/∂x, shape (n_states, n_states), 1/s."""
        return self._call("jac_x", x, u, p)

    def node_temperatures(self, x, u, p=None) -> dict[str, float]:
        """Temperatures (°C) of every internal node, massless ones included."""
        return dict(zip(self.node_order, self._call("nodes", x, u, p).ravel()))

    def outputs(self, x, u, p=None) -> np.ndarray:
        """Sensor temperatures (°C) in ``output_names`` order."""
        return self._call("outputs", x, u, p).ravel()

    @functools.cached_property
    def is_affine(self) -> bool:
        """True when dx/dt is affine in (x, u) up to loss floors: the linear design model.

        Its only non-affine parts may be :class:`~genthermal.losses.LossFloor` terms (a linearised
        copper loss held at 0 W where its line goes negative, below 1.6 A for the thesis's design
        model); ``functions["rhs_affine_branch"]`` is dx/dt with the floors taken as the identity.
        """
        s, branch = self._symbolic, self._affine_branch
        J = ca.jacobian(branch["xdot"], ca.vertcat(branch["x"], branch["u"]))
        in_x = ca.jacobian(s["xdot"], s["x"])
        return not ca.depends_on(J, ca.vertcat(branch["x"], branch["u"])) and not ca.depends_on(
            in_x, ca.vertcat(s["x"], s["u"]))

    def steady_state(self, u, p=None, tol: float = 1e-12) -> np.ndarray:
        """Steady state x (°C) for constant input ``u``, by Newton's method on dx/dt = 0.

        Raises
        ------
        InputError
            If Newton's method does not converge in 50 iterations, or converges to temperatures far
            below the coolant and ambient (:data:`COLDEST_STEADY_STATE_BELOW_K`): the root of a
            thermal runaway, where the copper resistance :math:`R_0(1+\\alpha_{cu}\\theta)` vanishes.
        """
        u = np.asarray(u, dtype=float)
        x = np.full(self.n_states, float(u[self.input_names.index(self.spec.interface.ambient_input)]))
        for _ in range(50):
            step = np.linalg.solve(self.jacobian_x(x, u, p), self.rhs(x, u, p))
            x = x - step
            if np.max(np.abs(step)) < tol * max(1.0, np.max(np.abs(x))):
                return self._physical_steady_state(x, u)
        raise InputError("u", u.tolist(), "no steady state found (Newton did not converge)")

    def _physical_steady_state(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        coldest = min(float(u[self.input_names.index(name)]) for name in self.spec.boundary_inputs.values())
        if x.min() < coldest - COLDEST_STEADY_STATE_BELOW_K:
            raise InputError("steady state", f"{x.min():.4g} °C", f"is far below the coolant and ambient "
                             f"({coldest:g} °C): at this load the losses grow with temperature faster than the "
                             "cooling removes them (thermal runaway), so there is no physical steady state; "
                             "check the loss and cooling parameters (R0, h_*)")
        return x

    def discretise(self, dt_s: float):
        """The :class:`~genthermal.discretise.DiscreteModel` for step ``dt_s`` (s), cached."""
        from .discretise import discretise  # discretise builds on this module

        key = float(dt_s)
        if key not in self._discrete:
            self._discrete[key] = discretise(self, key)
        return self._discrete[key]

    # --- variants --------------------------------------------------------------------------
    def with_parameters(self, provenance: str = "fitted", source: str = "", **values) -> "ThermalModel":
        """Return the same model with new parameter values (checked for physical values)."""
        return ThermalModel(self.network, self.parameters.with_values(provenance, source, **values), self.spec,
                            _share_from=self)

    def with_onsets(self, onsets) -> "ThermalModel":
        """Return the same model whose effects ``onsets`` (effect name → s after the first sample
        of a record) start during the record; an empty mapping removes them.

        Raises
        ------
        InputError
            For an effect the model does not have or an onset that is not a time >= 0.
        """
        checked = []
        for effect, onset in dict(onsets).items():
            if effect not in self.spec.effects:
                raise InputError(f"onsets.{effect}", effect, f"not an effect of {self.name} "
                                 f"(effects: {', '.join(self.spec.effects) or 'none'})")
            try:
                onset = float(onset)
            except (TypeError, ValueError):
                raise InputError(f"onsets.{effect}", onset, "must be a time in s >= 0") from None
            if not (np.isfinite(onset) and onset >= 0):
                raise InputError(f"onsets.{effect}", onset, "must be a time in s >= 0")
            checked.append((effect, onset))
        model = ThermalModel(self.network, self.parameters, dataclasses.replace(self.spec, onsets=tuple(checked)),
                             _share_from=self)
        model.disturbance_prior = self.disturbance_prior  # onsets change when effects start, not what is lacking
        return model

    def with_disturbance_prior(self, prior) -> "ThermalModel":
        """Return the same model carrying ``prior``, the disturbance heat flows a calibration left
        (:class:`~genthermal.estimation.disturbance_prior.DisturbancePrior`, or None to remove it):
        an extended Kalman filter on the model starts from it. Model files keep it."""
        model = ThermalModel(self.network, self.parameters, self.spec, _share_from=self)
        model.disturbance_prior = prior
        return model

    def with_network(self, network: Network, parameters: ParameterSet | None = None,
                     **spec_changes) -> "ThermalModel":
        """Return a model on a transformed network (how effects and variants are made)."""
        return ThermalModel(network, parameters or self.parameters,
                            dataclasses.replace(self.spec, **spec_changes))

    def input_vector(self, *values, **named) -> np.ndarray:
        """Build an input vector u in ``input_names`` order.

        Parameters
        ----------
        *values : float
            Inputs in ``input_names`` order (units of ``spec.interface.inputs``).
        **named : float
            Inputs by name; an input given neither way takes its interface default (0 A, 20 °C).
        """
        if len(values) > len(self.input_names):
            raise InputError("input_vector", values, f"{self.name} has {len(self.input_names)} inputs "
                             f"({', '.join(self.input_names)})")
        unknown = sorted(set(named) - set(self.input_names))
        if unknown:
            raise InputError(f"input {unknown[0]}", named[unknown[0]], f"not an input of {self.name} "
                             f"({', '.join(self.input_names)})")
        given = dict(zip(self.input_names, values))
        twice = sorted(set(given) & set(named))
        if twice:
            raise InputError(f"input {twice[0]}", named[twice[0]], "given both by position and by name")
        merged = {**self.spec.interface.default_input_values(), **given, **named}
        return np.array([merged[name] for name in self.input_names], dtype=float)

    def with_effect(self, effect, **values) -> "ThermalModel":
        """Return this model with a catalogue effect added (see :mod:`genthermal.effects`).

        Parameters
        ----------
        effect : str or Effect
            Effect name (``"coolant_flow_reduction"``) or object.
        **values : float
            Values of the effect's parameters; defaults are the effect's neutral values.
        """
        from .effects import apply_effect  # effects build on this module

        return apply_effect(self, effect, **values)

    def __repr__(self) -> str:
        effects = f", effects: {', '.join(self.spec.effects)}" if self.spec.effects else ""
        return (f"ThermalModel({self.name}: {self.n_states} states, {len(self.massless_names)} massless "
                f"nodes eliminated, {len(self.parameter_names)} parameters{effects})")
