r"""Sensor trajectories of a model on measured inputs, differentiable in chosen parameters.

Every genthermal model is affine in its state for a fixed input and parameter vector,
:math:`\dot x = J(u,p)\,x + f_0(u,p)`, with sensor outputs :math:`y = C(u,p)\,x + d(u,p)`.
:class:`ParametricSimulator` integrates it over each sample interval :math:`h` (inputs held,
zero-order hold) with the L-stable, stiffly accurate two-stage SDIRK method
(:math:`\gamma = 1 - 1/\sqrt2`, sub-steps of at most 30 s),

.. math::
    k_1 = M^{-1}(Jx + f_0), \quad k_2 = M^{-1}\big(J(x + (1-\gamma)h k_1) + f_0\big), \quad
    x^+ = x + h\big((1-\gamma)k_1 + \gamma k_2\big), \qquad M = I - \gamma h J,

keeping the fitted parameters :math:`\theta` symbolic (the stiff modes of 2-30 s are damped; the
error against the exact zero-order hold is below 1 mK at 10 s and 5 mK at 30 s on the shipped
missions). Everything that depends on :math:`\theta` only (conductances, capacitances, the elimination of the massless nodes) is
extracted from the step by ``casadi.extract_parametric`` and evaluated once per trajectory, so a
4-hour run at 10 s costs about 15 ms and its exact Jacobian :math:`\partial y/\partial\theta`
(forward AD through ``mapaccum``) a few times that.

Parameters can change at an onset: the simulator takes *regimes* (parameter overrides) and a
one-hot indicator per sample saying which regime holds — the semantics of
:func:`genthermal.simulate.simulate` with ``switches``: the regime of sample k propagates the state
from k to k+1 and gives the outputs at k.

Initial state
-------------
:math:`x_0 = c\,\mathbf 1 + a\,(x_{ss}(u_0,\theta) - T_{inlet,0}\mathbf 1)`: a blend of a uniformly
soaked machine at temperature :math:`c` and the steady state under the first input. ``(a, c)``
are two nuisance unknowns fitted with the parameters (started from the values that reproduce the
first measured winding and iron temperatures, :func:`genthermal.diagnose.compare.initial_state`).

Fitted parameters are scaled (:class:`Scaling`): strictly positive ones as
:math:`z = \ln(\theta/\theta_0)`, the others as :math:`z = (\theta - \theta_0)/s`, within
their physical bounds.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from typing import Mapping, Sequence

import casadi as ca
import numpy as np

from ..errors import InputError
from ..model import ThermalModel

#: Largest integration sub-step, s.
MAX_SUBSTEP_S = 30.0
_GAMMA = 1.0 - 1.0 / math.sqrt(2.0)


def _lu_solver(M):
    """Return ``solve(b)`` for the SX matrix ``M`` by LU without pivoting (M is diagonally dominant:
    :math:`I - \\gamma h J` with J a conductance matrix scaled by capacitances)."""
    n = M.size1()
    U = [[M[i, j] for j in range(n)] for i in range(n)]
    L = [[None] * n for _ in range(n)]
    for k in range(n):
        for i in range(k + 1, n):
            L[i][k] = U[i][k] / U[k][k]
            for j in range(k + 1, n):
                U[i][j] = U[i][j] - L[i][k] * U[k][j]
    inverse_pivot = [1 / U[k][k] for k in range(n)]

    def solve(b):
        y = [b[i] for i in range(n)]
        for i in range(n):
            for k in range(i):
                y[i] = y[i] - L[i][k] * y[k]
        for i in reversed(range(n)):
            for j in range(i + 1, n):
                y[i] = y[i] - U[i][j] * y[j]
            y[i] = y[i] * inverse_pivot[i]
        return ca.vertcat(*y)
    return solve


def _affine_parts(model: ThermalModel, p, x, u):
    """Return ``(J, f0, C, d)`` with dx/dt = J x + f0 and y = C x + d (SX in u and p)."""
    zero = ca.SX.zeros(x.numel())
    f = model.functions["rhs"](x, u, p)
    y = model.functions["outputs"](x, u, p)
    J, C = ca.jacobian(f, x), ca.jacobian(y, x)
    if ca.depends_on(J, x) or ca.depends_on(C, x):
        raise InputError("model", model.name, "calibration needs a model affine in its state")
    return J, ca.substitute(f, x, zero), C, ca.substitute(y, x, zero)


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
        parts = [_affine_parts(model, self._regime_parameters(theta, r), x, u) for r in self.regimes]
        J, f0, C, d = (sum((s[r] * parts[r][i] for r in range(n_regimes)), ca.SX(0)) if n_regimes > 1
                       else parts[0][i] for i in range(4))
        n_sub = max(1, math.ceil(self.dt_s / MAX_SUBSTEP_S - 1e-9))
        h = self.dt_s / n_sub
        solve = _lu_solver(ca.SX.eye(nx) - _GAMMA * h * J)
        x_next = x
        for _ in range(n_sub):
            k1 = solve(J @ x_next + f0)
            k2 = solve(J @ (x_next + (1 - _GAMMA) * h * k1) + f0)
            x_next = x_next + h * ((1 - _GAMMA) * k1 + _GAMMA * k2)
        y = C @ x + d
        (x_next, y), symbols, parametric = ca.extract_parametric([x_next, y], theta, {"extract_trivial": True})
        e = ca.vertcat(*symbols) if symbols else ca.SX.zeros(0)
        step = ca.Function("step", [x, ca.vertcat(u, s), e], [x_next, y])
        hoisted = ca.Function("hoisted", [theta], [ca.vertcat(*parametric) if parametric else ca.SX.zeros(0)])
        J0, f00 = parts[0][0], parts[0][1]
        steady = ca.Function("steady", [u, theta], [-ca.solve(J0, f00)])

        th, ac = ca.MX.sym("theta", len(self.fitted)), ca.MX.sym("x0_coefficients", 2)
        S = ca.MX.sym("indicator", n_regimes, self.n_samples)
        U = ca.MX.sym("inputs", nu, self.n_samples)
        x0 = ac[1] + ac[0] * (steady(U[:, 0], th) - U[model.input_names.index(model.spec.interface.coolant_input), 0])
        _, Y = step.mapaccum("trajectory", self.n_samples, [0], [0])(x0, ca.vertcat(U, S), hoisted(th))
        decision = ca.vertcat(th, ac)
        args = [th, ac, S, U]
        self._trajectory = ca.Function("trajectory", args, [Y], ["theta", "x0_coefficients", "indicator", "inputs"], ["y"])
        self._with_jacobian = ca.Function("trajectory_jac", args, [Y, ca.jacobian(ca.vec(Y), decision)])
        self._with_theta_jacobian = ca.Function("trajectory_jac_theta", args, [Y, ca.jacobian(ca.vec(Y), th)])
        self._steady = steady

    def with_inputs(self, inputs: np.ndarray) -> "ParametricSimulator":
        """The same simulator (same model, parameters, regimes, period, length) on other inputs."""
        inputs = np.asarray(inputs, dtype=float)
        if inputs.shape != self.inputs.shape:
            raise InputError("inputs", inputs.shape, f"must have the shape {self.inputs.shape}")
        other = copy.copy(self)
        other.inputs = inputs
        return other

    def symbolic(self, theta, x0_coefficients, indicator):
        """The outputs as a CasADi expression of (possibly symbolic) arguments."""
        return self._trajectory(theta, x0_coefficients, indicator, ca.DM(self.inputs))

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

    def outputs(self, theta, x0_coefficients, indicator) -> np.ndarray:
        """Sensor temperatures (°C), shape (n_outputs, N)."""
        return np.asarray(self._trajectory(theta, x0_coefficients, indicator, self.inputs))

    def outputs_and_jacobian(self, theta, x0_coefficients, indicator) -> tuple[np.ndarray, np.ndarray]:
        """Outputs and the exact Jacobian of ``vec(Y)`` (column-major: samples of output 0 and 1
        interleaved per sample) w.r.t. ``(theta, a, c)``, shape (n_outputs·N, n_theta + 2)."""
        Y, jac = self._with_jacobian(theta, x0_coefficients, indicator, self.inputs)
        return np.asarray(Y), np.asarray(jac)

    def outputs_and_theta_jacobian(self, theta, x0_coefficients, indicator) -> tuple[np.ndarray, np.ndarray]:
        """As :meth:`outputs_and_jacobian`, w.r.t. ``theta`` only (initial state held)."""
        Y, jac = self._with_theta_jacobian(theta, x0_coefficients, indicator, self.inputs)
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
        """Physical value of the decision variable ``z`` (float or casadi expression)."""
        if self.kind == "log":
            return self.reference * (ca.exp(z) if isinstance(z, (ca.MX, ca.SX)) else math.exp(z))
        return self.reference + self.scale * z

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
