"""Sensor trajectories of a model on measured inputs, differentiable in chosen parameters.

:class:`ParametricSimulator` steps the model with :func:`genthermal.discretise.parametric_step`
(the step ``simulate`` takes) with the fitted parameters symbolic, so trajectories equal
``simulate``'s to round-off and their Jacobians are exact; parameters may change at onsets
(regimes). :class:`Scaling` maps parameters to the decision variables of a fit. Method:
``docs/guide/methods.md``.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from typing import Mapping, Sequence

import casadi as ca
import numpy as np

from ..discretise import parametric_step
from ..errors import InputError
from ..model import ThermalModel


def _affine_parts(model: ThermalModel, p, x, u):
    """Return ``(J, f0)`` with dx/dt = J x + f0 (SX in u and p), for the steady state."""
    f = model.functions["rhs"](x, u, p)
    J = ca.jacobian(f, x)
    if ca.depends_on(J, x):
        raise InputError("model", model.name, "calibration needs a model affine in its state")
    return J, ca.substitute(f, x, ca.SX.zeros(x.numel()))


def _chunked_outputs(step: ca.Function, n_samples: int, x0: ca.MX, series: ca.MX, constants) -> ca.MX:
    r"""Outputs of ``n_samples`` steps of ``step`` ``(x, v, *constants) -> (x_next, y)`` from ``x0``,
    ``v`` the columns of ``series``, in chunks of about :math:`\sqrt N` steps.

    ``mapaccum`` repeats every input that is the same at each step (the parameter-only
    quantities, a few hundred numbers) once per step when the function is built and called; in
    chunks they are repeated about :math:`2\sqrt N` times instead of :math:`N`, which keeps the
    build time, the work memory and the derivatives' cost of a long trajectory from growing with
    them. The steps and their order are unchanged, so the outputs are the same.

    Returns
    -------
    tuple of casadi.MX
        The outputs (n_outputs × N) and the states at the chunk boundaries: column j is the state at
        sample ``(j + 1) * chunk_length(N)``.
    """
    chunk_length = _chunk_length(n_samples)
    n_chunks, tail = divmod(n_samples, chunk_length)
    x, v = ca.MX.sym("x", x0.numel()), ca.MX.sym("v", series.size1(), chunk_length)
    symbols = [ca.MX.sym(f"constant_{i}", c.sparsity()) for i, c in enumerate(constants)]
    states, outputs = step.mapaccum("chunk", chunk_length, [0], [0])(x, v, *symbols)
    chunk = ca.Function("chunk", [x, v, *symbols], [states[:, -1], outputs])
    states, Y = chunk.mapaccum("chunks", n_chunks, [0], [0])(x0, series[:, :n_chunks * chunk_length], *constants)
    if not tail:
        return Y, states
    _, Y_tail = step.mapaccum("tail", tail, [0], [0])(states[:, -1], series[:, n_chunks * chunk_length:], *constants)
    return ca.horzcat(Y, Y_tail), states


def _chunk_length(n_samples: int) -> int:
    """Steps per chunk of :func:`_chunked_outputs` for ``n_samples`` steps."""
    return max(1, math.isqrt(n_samples))


class ParametricSimulator:
    """Sensor trajectories of ``model`` on a fixed input series, exact in chosen parameters.

    Parameters
    ----------
    model : ThermalModel
        Must contain every parameter named in ``fitted`` and ``regimes``.
    dt_s : float
        Sample period of ``inputs``, s.
    inputs : numpy.ndarray
        Inputs, shape (n_inputs, N), zero-order hold.
    fitted : sequence of str
        Model parameters whose values are decision variables :math:`\\theta`.
    regimes : sequence of mapping, optional
        Parameter overrides per regime: name → a name in ``fitted`` (its value) or a number.
        Fitted parameters no regime mentions hold over the whole horizon. Default: one regime.

    Notes
    -----
    Numeric calls take ``theta`` (values in model units), ``x0_coefficients = (a, c)`` (see the
    module docstring) and ``indicator``, shape (n_regimes, N), one-hot per sample.
    """

    def __init__(self, model: ThermalModel, dt_s: float, inputs: np.ndarray,
                 fitted: Sequence[str] = (), regimes: Sequence[Mapping[str, str | float]] = ({},)):
        self.model, self.dt_s = model, float(dt_s)
        self.inputs = np.asarray(inputs, dtype=float)
        self.fitted, self.regimes = list(fitted), [dict(r) for r in regimes]
        self.n_samples = self.inputs.shape[1]
        for name in self.fitted + [n for r in self.regimes for n in r]:
            if name not in model.parameters:
                raise InputError("parameter", name, f"not a parameter of {model.name}")
        self._build()

    def _regime_parameters(self, theta, overrides):
        values = [ca.SX(v) for v in self.model.p0]
        names = self.model.parameter_names
        mentioned = {n for r in self.regimes for n in r}
        for j, name in enumerate(self.fitted):
            if name not in mentioned:
                values[names.index(name)] = theta[j]
        for name, source in overrides.items():
            values[names.index(name)] = theta[self.fitted.index(source)] if isinstance(source, str) \
                else ca.SX(float(source))
        return ca.vertcat(*values)

    def _build(self) -> None:
        model = self.model
        nx, nu, n_regimes = model.n_states, len(model.input_names), len(self.regimes)
        theta = ca.SX.sym("theta", len(self.fitted))
        x, u, s = ca.SX.sym("x", nx), ca.SX.sym("u", nu), ca.SX.sym("s", n_regimes)
        parameters = [self._regime_parameters(theta, r) for r in self.regimes]
        regime_steps = [parametric_step(model, x, u, p, self.dt_s) for p in parameters]
        outputs = [model.functions["outputs"](x, u, p) for p in parameters]
        x_next, y = ((sum((s[r] * parts[r] for r in range(n_regimes)), ca.SX(0)) if n_regimes > 1 else parts[0])
                     for parts in ([regime.x_next for regime in regime_steps], outputs))
        (x_next, y), symbols, parametric = ca.extract_parametric([x_next, y], theta, {"extract_trivial": True})
        e = ca.vertcat(*symbols) if symbols else ca.SX.zeros(0)
        phis = ca.vertcat(*[ca.vec(m) for regime in regime_steps for m in regime.phis])
        used = [i for i, depends in enumerate(ca.which_depends(x_next, phis, 1, False)) if depends]
        step = ca.Function("step", [x, ca.vertcat(u, s), e, phis[used]], [x_next, y])
        hoisted = ca.Function("hoisted", [theta], [ca.vertcat(*parametric) if parametric else ca.SX.zeros(0)])
        state_matrices = ca.Function("state_matrices", [theta], [regime.state_matrix for regime in regime_steps])
        J0, f00 = _affine_parts(model, parameters[0], x, u)
        steady = ca.Function("steady", [u, theta], [-ca.solve(J0, f00)])

        th, ac = ca.MX.sym("theta", len(self.fitted)), ca.MX.sym("x0_coefficients", 2)
        S = ca.MX.sym("indicator", n_regimes, self.n_samples)
        U = ca.MX.sym("inputs", nu, self.n_samples)
        x0 = ac[1] + ac[0] * (steady(U[:, 0], th) - U[model.input_names.index(model.spec.interface.coolant_input), 0])
        exponentials = ca.vertcat(*[ca.vec(m) for regime, L in zip(regime_steps, state_matrices.call([th]))
                                    for m in regime.exponential(L)])[used]  # the entries the step uses
        constants = ca.Function("constants", [th], [hoisted(th), exponentials])
        Y, boundary_states = _chunked_outputs(step, self.n_samples, x0, ca.vertcat(U, S), constants.call([th]))
        args = [th, ac, S, U]
        self._trajectory = ca.Function("trajectory", args, [Y], ["theta", "x0_coefficients", "indicator", "inputs"], ["y"])
        self._trajectory_and_states = ca.Function("trajectory_and_states", args, [Y, boundary_states])
        self._suffix_parts = (step, constants)
        self._suffixes: dict = {}  # suffix simulators per start sample, built on first use, shared by with_inputs
        self._last_run = None  # (x0_coefficients, indicator, theta-free samples, outputs, boundary states)
        self._theta_regimes = np.array([ca.depends_on(p, theta) for p in parameters], dtype=bool)
        self._jacobian_of = (args, Y, {"decision": ca.vertcat(th, ac), "theta": th})
        self._jacobians: dict = {}  # built on first use (most callers need one or none), shared by with_inputs
        self._steady = steady

    def _jacobian_function(self, wrt: str) -> ca.Function:
        """``(...) -> (Y, d vec(Y)/d wrt)`` for ``wrt`` "decision" (theta, a, c) or "theta"."""
        if wrt not in self._jacobians:
            args, Y, variables = self._jacobian_of
            self._jacobians[wrt] = ca.Function(f"trajectory_jac_{wrt}", args, [Y, ca.jacobian(ca.vec(Y), variables[wrt])])
        return self._jacobians[wrt]

    def _suffix_function(self, start: int) -> ca.Function:
        """``(theta, x_start, indicator, inputs) -> y`` for the samples from ``start`` on."""
        if start not in self._suffixes:
            step, constants = self._suffix_parts
            n, nu = self.n_samples - start, len(self.model.input_names)
            th, x_start = ca.MX.sym("theta", len(self.fitted)), ca.MX.sym("x_start", self.model.n_states)
            S, U = ca.MX.sym("indicator", len(self.regimes), n), ca.MX.sym("inputs", nu, n)
            Y, _ = _chunked_outputs(step, n, x_start, ca.vertcat(U, S), constants.call([th]))
            self._suffixes[start] = ca.Function(f"trajectory_from_{start}", [th, x_start, S, U], [Y])
        return self._suffixes[start]

    def theta_free_samples(self, indicator) -> int:
        """How many leading samples have outputs independent of ``theta`` under ``indicator``: those
        before the first sample of a regime that depends on it (none when the initial state does)."""
        if self._theta_regimes[0]:
            return 0
        depends = np.any(np.asarray(indicator)[self._theta_regimes] != 0, axis=0)
        return int(np.argmax(depends)) if depends.any() else self.n_samples

    def with_inputs(self, inputs: np.ndarray) -> "ParametricSimulator":
        """The same simulator (same model, parameters, regimes, period, length) on other inputs."""
        inputs = np.asarray(inputs, dtype=float)
        if inputs.shape != self.inputs.shape:
            raise InputError("inputs", inputs.shape, f"must have the shape {self.inputs.shape}")
        other = copy.copy(self)
        other.inputs, other._last_run = inputs, None
        return other

    def symbolic(self, theta, x0_coefficients, indicator, inputs=None):
        """The outputs as a CasADi expression of (possibly symbolic) arguments; ``inputs`` (shape
        (n_inputs, N), possibly symbolic, e.g. load moved between generators) replaces the series
        the simulator was built on."""
        return self._trajectory(theta, x0_coefficients, indicator, ca.DM(self.inputs) if inputs is None else inputs)

    def indicator(self, onsets: Sequence[int] = ()) -> np.ndarray:
        """One-hot regime indicator for regimes that start at sample indices ``onsets``.

        Regime 0 holds from sample 0; regime ``r`` (r ≥ 1) from ``onsets[r-1]`` on, later regimes
        winning. Shape (n_regimes, N).
        """
        current = np.zeros(self.n_samples, dtype=int)
        for r, onset in sorted(enumerate(onsets, start=1), key=lambda item: item[1]):
            current[int(onset):] = r
        S = np.zeros((len(self.regimes), self.n_samples))
        S[current, np.arange(self.n_samples)] = 1.0
        return S

    def _prefix_reusable(self, last, start: int, x0_coefficients: np.ndarray, indicator: np.ndarray) -> bool:
        """Whether ``last`` (the previous :meth:`outputs` call) holds this call's outputs and state up
        to sample ``start``: ``theta`` did not act there in either call, and both had the same
        initial state and regimes there."""
        return (last is not None and 0 < start < self.n_samples and start <= last[2]
                and np.array_equal(last[0], x0_coefficients) and np.array_equal(last[1][:, :start], indicator[:, :start]))

    def outputs(self, theta, x0_coefficients, indicator) -> np.ndarray:
        """Sensor temperatures (°C), shape (n_outputs, N).

        The samples before the first regime that depends on ``theta`` do not depend on it: when the
        previous call had the same initial state and the same regimes over them, its outputs there
        and its state at the last chunk boundary before them are reused, and only the rest of the
        horizon is simulated (the same steps from the same state, so the same numbers). An onset
        search fits the parameters at each trial onset with many calls that differ in ``theta`` only.
        """
        x0_coefficients = np.asarray(x0_coefficients, dtype=float).ravel()
        indicator = np.asarray(indicator, dtype=float)
        free = self.theta_free_samples(indicator)
        chunk = _chunk_length(self.n_samples)
        start = free // chunk * chunk
        last = self._last_run
        if self._prefix_reusable(last, start, x0_coefficients, indicator):
            suffix = self._suffix_function(start)(theta, last[4][:, start // chunk - 1],
                                                  indicator[:, start:], self.inputs[:, start:])
            return np.hstack([last[3][:, :start], np.asarray(suffix)])
        Y, states = (np.asarray(m) for m in self._trajectory_and_states(theta, x0_coefficients, indicator, self.inputs))
        self._last_run = (x0_coefficients, indicator.copy(), free, Y, states)
        return Y.copy()

    def outputs_and_jacobian(self, theta, x0_coefficients, indicator) -> tuple[np.ndarray, np.ndarray]:
        """Outputs and the exact Jacobian of ``vec(Y)`` (column-major: samples of output 0 and 1
        interleaved per sample) w.r.t. ``(theta, a, c)``, shape (n_outputs·N, n_theta + 2)."""
        Y, jac = self._jacobian_function("decision")(theta, x0_coefficients, indicator, self.inputs)
        return np.asarray(Y), np.asarray(jac)

    def outputs_and_theta_jacobian(self, theta, x0_coefficients, indicator) -> tuple[np.ndarray, np.ndarray]:
        """As :meth:`outputs_and_jacobian`, w.r.t. ``theta`` only (initial state held)."""
        Y, jac = self._jacobian_function("theta")(theta, x0_coefficients, indicator, self.inputs)
        return np.asarray(Y), np.asarray(jac)

    def steady_state(self, theta) -> np.ndarray:
        """Steady state (°C) under the first input sample."""
        return np.asarray(self._steady(self.inputs[:, 0], theta)).ravel()


@dataclasses.dataclass(frozen=True)
class Scaling:
    """Map between a parameter value and its scaled decision variable.

    ``kind == "log"``: :math:`z = \\ln(\\theta/\\theta_0)`; ``"linear"``: :math:`z = (\\theta-\\theta_0)/s`.
    """

    kind: str
    reference: float
    scale: float
    lower: float
    upper: float

    def value(self, z):
        """Physical value of the decision variable ``z`` (float or casadi expression); a float is
        kept within [lower, upper]: the round trip of a bound, ``reference + scale·(lower −
        reference)/scale``, can land an ulp outside it (an ``n_flow`` fitted to its bound 0 came back
        −4e-19, which the effect refuses)."""
        if isinstance(z, (ca.MX, ca.SX)):
            return self.reference * ca.exp(z) if self.kind == "log" else self.reference + self.scale * z
        value = self.reference * math.exp(z) if self.kind == "log" else self.reference + self.scale * z
        return min(max(value, self.lower), self.upper)

    def decision(self, value: float) -> float:
        """Scaled decision variable of ``value``."""
        if self.kind == "log":
            return math.log(value / self.reference)
        return (value - self.reference) / self.scale

    def bounds(self) -> tuple[float, float]:
        """Bounds of the decision variable."""
        return self.decision(self.lower), self.decision(self.upper)


def parameter_scaling(model: ThermalModel, name: str, start: float | None = None,
                      typical: float | None = None) -> Scaling:
    """Scaling and fit bounds of model parameter ``name`` from its physical range.

    Strictly positive parameters are fitted in log scale within [lower, upper] (an open lower
    bound at 0 becomes ``start/1000``, an infinite upper bound ``1000·start``); the others linearly
    with scale ``max(|start|, |typical|, (upper - lower)/20)``.
    """
    parameter = model.parameters[name]
    start = parameter.value if start is None else float(start)
    lower, upper = parameter.lower, parameter.upper
    if start > 0 and (lower > 0 or not parameter.lower_inclusive):
        low = lower * (1 + 1e-9) if lower > 0 else start / 1000.0
        high = upper if math.isfinite(upper) else start * 1000.0
        return Scaling("log", start, 1.0, max(low, start / 1000.0), min(high, start * 1000.0))
    span = (upper - lower) / 20.0 if math.isfinite(upper - lower) else 0.0
    scale = max(abs(start), abs(typical or 0.0), span) or 1.0
    low = lower if math.isfinite(lower) and lower > -1e8 else start - 1000.0 * scale
    high = upper if math.isfinite(upper) else start + 1000.0 * scale
    return Scaling("linear", start, scale, low, high)
