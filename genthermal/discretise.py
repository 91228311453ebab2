"""Discrete-time steps of a ThermalModel with inputs held constant over each step (ZOH).

:func:`discretise` gives a :class:`DiscreteModel`: exact zero-order hold for the linear design
model, the exponential Runge-Kutta scheme ETD2RK (Cox & Matthews) for the nonlinear one, with an
optional forcing for the filters' disturbance heat flows. :func:`parametric_step` is the same step
with the parameters symbolic; :func:`phi_matrices`, :func:`symbolic_phi_function` and
:class:`ModalDecay` give the matrix exponential. This is the only place that integrates a model
over a step. Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import casadi as ca
import numpy as np

from .errors import InputError
from .model import ThermalModel


#: Taylor degree of the :math:`\varphi_2` series (truncation below 1e-15 at
#: :math:`\lVert A\rVert_1 \le 1`).
PHI_TAYLOR_DEGREE = 16
#: How much larger than at the nominal parameters :math:`\lVert hL(\theta)\rVert_1` may become
#: before the symbolic exponential's scaled norm exceeds 1 (a fit moves rates by far less).
PHI_NORM_HEADROOM = 1024.0
#: Block of the Paterson-Stockmeyer evaluation of the series (powers of A up to A^4).
_PS_BLOCK = 4


def phi_matrices(L: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return :math:`(e^{hL}, \\Gamma_1, \\Gamma_2)` for step ``h`` (s) by scaling and squaring.

    Parameters
    ----------
    L : numpy.ndarray
        State matrix, 1/s, (n_states × n_states).
    h : float
        Step length, s (>= 0).

    Returns
    -------
    tuple of numpy.ndarray
        :math:`e^{hL}` (dimensionless), :math:`\\Gamma_1` (s), :math:`\\Gamma_2` (s²).
    """
    if not (np.isfinite(h) and h >= 0):
        raise InputError("h_s", h, "the step length must be a number of seconds >= 0")
    L = np.asarray(L, dtype=float)
    doublings = _doublings(L, h, 1.0)
    tau = float(h) / 2.0 ** doublings
    D, G1, G2 = _series(L, tau, np.eye(L.shape[0]))
    for _ in range(doublings):
        D, G1, G2 = _doubled(D, G1, G2, tau)
        tau *= 2.0
    return np.eye(L.shape[0]) + D, G1, G2


def symbolic_phi_function(n_states: int, h: float, nominal_L: np.ndarray) -> ca.Function:
    """``(L) -> (E, Γ1, Γ2)`` for a symbolic ``L`` (scaling and squaring, see the module docstring),
    differentiable in whatever ``L`` depends on.

    An MX function calling two small SX blocks (the series, one doubling): their derivatives are
    built once however many doublings there are, so differentiating it stays cheap.

    Parameters
    ----------
    n_states : int
        Size of ``L``.
    h : float
        Step length, s (> 0).
    nominal_L : numpy.ndarray
        ``L`` (1/s) at the nominal parameters: sets the number of doublings (with
        :data:`PHI_NORM_HEADROOM`).
    """
    return _phi_function(int(n_states), float(h), _doublings(np.asarray(nominal_L), h, PHI_NORM_HEADROOM))


@functools.lru_cache(maxsize=64)
def _phi_function(n_states: int, h: float, doublings: int) -> ca.Function:
    """:func:`symbolic_phi_function` for ``doublings``; one instance per key, so that CasADi builds
    the derivatives of its blocks once for every simulator that uses it."""
    tau = h / 2.0 ** doublings
    L_block, identity = ca.SX.sym("L", n_states, n_states), ca.SX.eye(n_states)
    series = ca.Function("phi_series", [L_block], list(_series(L_block, tau, identity)))
    blocks = [ca.SX.sym(name, n_states, n_states) for name in ("D", "G1", "G2")] + [ca.SX.sym("tau")]
    doubling = ca.Function("phi_doubling", blocks, list(_doubled(*blocks)))
    L = ca.MX.sym("L", n_states, n_states)
    D, G1, G2 = series(L)
    for _ in range(doublings):
        D, G1, G2 = doubling(D, G1, G2, tau)
        tau *= 2.0
    return ca.Function("phi_matrices", [L], [ca.MX.eye(n_states) + D, G1, G2], ["L"], ["E", "G1", "G2"])


def _doublings(L: np.ndarray, h: float, headroom: float) -> int:
    """Doublings that bring :math:`\\lVert hL\\rVert_1 \\cdot` ``headroom`` to at most 1."""
    norm = float(np.max(np.sum(np.abs(L), axis=0))) * h * headroom
    return max(0, int(np.ceil(np.log2(norm)))) if norm > 1.0 else 0


def _series(L, tau: float, identity):
    """``(D, Γ1, Γ2)`` at step ``tau`` from the Taylor series of :math:`\\varphi_2(\\tau L)`
    (:math:`D = e^{\\tau L} - I`); ``L`` and ``identity`` both numpy arrays or both CasADi SX."""
    A = tau * L
    powers = [identity, A]  # Paterson-Stockmeyer: I..A^q, then Horner in A^q (q + m/q products)
    for _ in range(_PS_BLOCK - 1):
        powers.append(A @ powers[-1])
    coefficients = [1.0 / math.factorial(j + 2) for j in range(PHI_TAYLOR_DEGREE + 1)]
    blocks = [sum((c * powers[r] for r, c in enumerate(coefficients[i:i + _PS_BLOCK])), 0.0 * identity)
              for i in range(0, len(coefficients), _PS_BLOCK)]
    phi2 = blocks[-1]
    for block in reversed(blocks[:-1]):
        phi2 = block + powers[_PS_BLOCK] @ phi2
    phi1 = identity + A @ phi2
    return A @ phi1, tau * phi1, tau ** 2 * phi2


def _doubled(D, G1, G2, tau):
    """``(D, Γ1, Γ2)`` at step ``2 tau`` from those at ``tau`` (D = E - I is doubled without forming
    E: I + a small D would lose D's digits at every doubling)."""
    return 2.0 * D + D @ D, 2.0 * G1 + D @ G1, 2.0 * G2 + D @ G2 + tau * G1


@dataclasses.dataclass(frozen=True)
class ModalDecay:
    r"""Free response :math:`e^{hL}v = V e^{\Lambda h} V^{-1} v` at a step length ``h`` that may be
    a decision variable (the optimal scheduler's rest of free length).

    Attributes
    ----------
    eigenvalues : numpy.ndarray
        Real, negative eigenvalues :math:`\Lambda` of ``L``, 1/s.
    V, V_inv : numpy.ndarray
        Eigenvectors and their inverse.
    """

    eigenvalues: np.ndarray
    V: np.ndarray
    V_inv: np.ndarray

    @classmethod
    def of(cls, L: np.ndarray, name: str) -> "ModalDecay":
        """Decompose ``L`` (1/s) of the model called ``name``.

        Raises
        ------
        InputError
            Naming the model when ``L`` has complex or non-negative eigenvalues.
        """
        eigenvalues, V = np.linalg.eig(L)
        if np.max(np.abs(eigenvalues.imag)) > 0 or np.max(eigenvalues.real) >= 0:
            raise InputError("model", name, "the design model needs real, negative eigenvalues")
        return cls(eigenvalues.real, V.real, np.linalg.inv(V).real)

    def apply(self, v, h_s):
        """:math:`e^{h L} v` for a state deviation ``v`` (K) and step ``h_s`` (s), numbers or CasADi."""
        if isinstance(v, (ca.SX, ca.MX)) or isinstance(h_s, (ca.SX, ca.MX)):
            return ca.DM(self.V) @ (ca.exp(ca.DM(self.eigenvalues) * h_s) * (ca.DM(self.V_inv) @ v))
        return self.V @ (np.exp(self.eigenvalues * h_s) * (self.V_inv @ v))


@dataclasses.dataclass(frozen=True)
class DiscreteModel:
    """The discrete step of a model for one step length.

    Attributes
    ----------
    model : ThermalModel
    dt_s : float
        Step length, s.
    step : casadi.Function
        ``(x, u) -> x_next``, parameters fixed at the model's values.
    forced_step : casadi.Function
        ``(x, u, w) -> x_next`` with a rate ``w`` (K/s, n_states) added to dx/dt over the step.
    exact : bool
        True for the exact zero-order hold of an affine model.
    A, B, c : numpy.ndarray or None
        :math:`x^+ = Ax + Bu + c` for the exact (affine) case, else None; with loss floors, of the
        affine branch (equal to ``step`` wherever no floor is active).
    """

    model: ThermalModel
    dt_s: float
    step: ca.Function
    forced_step: ca.Function
    exact: bool
    A: np.ndarray | None
    B: np.ndarray | None
    c: np.ndarray | None

    _simulators: dict = dataclasses.field(default_factory=dict, repr=False, compare=False)

    def simulator(self, n_steps: int) -> ca.Function:
        """``(x0, U) -> X``: ``n_steps`` steps with U of shape (n_inputs, n_steps); X holds the
        states after each step (shape (n_states, n_steps)). Cached per horizon."""
        if n_steps not in self._simulators:
            self._simulators[n_steps] = self.step.mapaccum("simulate", n_steps)
        return self._simulators[n_steps]


def discretise(model: ThermalModel, dt_s: float) -> DiscreteModel:
    """Build the discrete step of ``model`` for step length ``dt_s``.

    Parameters
    ----------
    model : ThermalModel
    dt_s : float
        Step length in s (> 0).

    Returns
    -------
    DiscreteModel
    """
    if not (np.isfinite(dt_s) and dt_s > 0):
        raise InputError("dt_s", dt_s, "the step length must be a positive number of seconds")
    nx, nu = model.n_states, len(model.input_names)
    x, u, w = ca.SX.sym("x", nx), ca.SX.sym("u", nu), ca.SX.sym("w", nx)
    p = ca.DM(model.p0)
    L = _state_matrix(model, p)
    phis = tuple(ca.DM(m) for m in phi_matrices(np.asarray(L), dt_s))
    step, forced = _step_functions(x, u, w, step_expression(model, x, u, w, p, dt_s, phis))
    if not model.is_affine:
        return DiscreteModel(model, float(dt_s), step, forced, False, None, None, None)
    branch = model.functions["rhs_affine_branch"]
    B = np.asarray(ca.Function("B", [u], [ca.jacobian(branch(ca.SX.zeros(nx), u, p), u)])(0))
    c = np.asarray(branch(np.zeros(nx), np.zeros(nu), p)).ravel()
    E, G1 = (np.asarray(m) for m in phis[:2])
    return DiscreteModel(model, float(dt_s), step, forced, True, E, G1 @ B, G1 @ c)


@dataclasses.dataclass(frozen=True)
class ParametricStep:
    """The step of :func:`discretise` with symbolic parameters, exact in them; calibration
    differentiates it. In two parts, so that the matrix exponential, which depends on the
    parameters only, is computed once per trajectory: ``x_next`` uses the symbols ``phis``, whose
    values are ``exponential(state_matrix)``.

    Attributes
    ----------
    x_next : casadi.SX
        State after the step (°C), an expression of ``(x, u, p)`` and ``phis``.
    phis : tuple of casadi.SX
        Symbols of :math:`(e^{hL}, \\Gamma_1, \\Gamma_2)`, each (n_states × n_states).
    state_matrix : casadi.SX
        :math:`L(p)`, 1/s.
    exponential : casadi.Function
        ``(L) -> (E, Γ1, Γ2)``, :func:`symbolic_phi_function`.
    """

    x_next: ca.SX
    phis: tuple
    state_matrix: ca.SX
    exponential: ca.Function


def parametric_step(model: ThermalModel, x: ca.SX, u: ca.SX, p: ca.SX, dt_s: float) -> ParametricStep:
    """The step of :func:`discretise` with symbolic parameters ``p`` (see :class:`ParametricStep`).

    Parameters
    ----------
    model : ThermalModel
    x, u : casadi.SX
        State (°C) and input symbols.
    p : casadi.SX
        Parameter vector in the model's order (model units), any expression.
    dt_s : float
        Step length, s (> 0).
    """
    if not (np.isfinite(dt_s) and dt_s > 0):
        raise InputError("dt_s", dt_s, "the step length must be a positive number of seconds")
    n = model.n_states
    nominal_L = np.asarray(_state_matrix(model, ca.DM(model.p0)))
    phis = tuple(ca.SX.sym(name, n, n) for name in ("E", "G1", "G2"))
    return ParametricStep(step_expression(model, x, u, ca.SX.zeros(n), p, dt_s, phis), phis,
                          _state_matrix(model, p), symbolic_phi_function(n, dt_s, nominal_L))


def _state_matrix(model: ThermalModel, p):
    """:math:`L = \\partial f/\\partial x` at ``x = 0`` and the machine's linearisation inputs
    (``spec.interface.linearisation_inputs``, others 0) for parameters ``p`` (DM or SX)."""
    interface = getattr(model.spec, "interface", None)
    named = getattr(interface, "linearisation_inputs", None) or {}
    u = np.array([float(named.get(name, 0.0)) for name in model.input_names])
    return model.functions["jac_x"](ca.DM.zeros(model.n_states), ca.DM(u), p)


def step_expression(model: ThermalModel, x, u, w, p, dt_s: float, phis) -> ca.SX:
    """``x_next`` of one step (module docstring): exact ZOH for an affine model, ETD2RK otherwise.

    Parameters
    ----------
    model : ThermalModel
    x, u, w : casadi.SX
        State (°C), input and forcing (K/s) symbols.
    p : casadi.DM or casadi.SX
        Parameters (model units).
    dt_s : float
        Step length, s.
    phis : tuple
        :math:`(e^{hL}, \\Gamma_1, \\Gamma_2)` for ``L`` at ``p`` (DM or SX).
    """
    E, G1, G2 = phis
    nx = model.n_states
    rhs, jac_x = model.functions["rhs"], model.functions["jac_x"]
    f0 = rhs(ca.SX.zeros(nx), u, p)  # f(0, u)
    if model.is_affine:
        return E @ x + G1 @ (f0 + w)
    L = _state_matrix(model, p)
    if ca.depends_on(jac_x(x, u, p), x):  # not affine in x: generic N = f - Lx
        def N(state):
            return rhs(state, u, p) - L @ state + w
        a = E @ x + G1 @ N(x)
        return a + (G2 / dt_s) @ (N(a) - N(x))
    J_minus_L = _input_dependent_part(jac_x(ca.SX.zeros(nx), u, p), L, u)
    a = E @ x + G1 @ (J_minus_L @ x + f0 + w)
    return a + (G2 / dt_s) @ (J_minus_L @ (a - x))


def _input_dependent_part(J: ca.SX, L, u: ca.SX) -> ca.SX:
    """:math:`J(u) - L`, structurally zero wherever ``J`` does not depend on ``u`` (there the two
    are equal: with symbolic parameters the difference would otherwise not cancel)."""
    difference = ca.SX.zeros(*J.shape)
    for i in range(J.size1()):
        for j in range(J.size2()):
            if ca.depends_on(J[i, j], u):
                difference[i, j] = J[i, j] - L[i, j]
    return difference


def _step_functions(x, u, w, x_next) -> tuple[ca.Function, ca.Function]:
    """``step`` (x, u) at w = 0 and ``forced_step`` (x, u, w) from one expression."""
    forced = ca.Function("forced_step", [x, u, w], [x_next], ["x", "u", "w"], ["x_next"])
    unforced = ca.substitute(x_next, w, ca.SX.zeros(w.numel()))
    return ca.Function("step", [x, u], [unforced], ["x", "u"], ["x_next"]), forced


#: Largest step-doubling difference accepted for a filter step, K (see :func:`check_step_accuracy`).
STEP_TOLERANCE_K = 0.05


def check_step_accuracy(model: ThermalModel, dt_s: float, tolerance_K: float = STEP_TOLERANCE_K) -> float:
    """Check that ``model`` can be discretised at ``dt_s`` accurately enough for a filter.

    One step of ``dt_s`` is compared with two steps of ``dt_s / 2`` from the cold machine (every
    node at 20 °C) at the machine's rating point (``model.spec.interface.rated_inputs``; the
    thesis generator: rated current on every phase, the AVR's field current): the difference estimates the step's local error. The exact
    zero-order hold of an affine model has none; the exponential integrator of the nonlinear model
    differs by 1e-5 K at 10 s, 2e-3 K at 60 s, 0.16 K at 300 s (thesis generator).

    Returns
    -------
    float
        The step-doubling difference, K.

    Raises
    ------
    InputError
        Naming ``dt_s`` when it is not a positive number or the difference exceeds ``tolerance_K``.
    """
    step = model.discretise(dt_s).step
    half = model.discretise(dt_s / 2.0).step
    u = model.input_vector(**model.spec.interface.rated_inputs)
    x = np.full(model.n_states, 20.0)
    difference = float(np.max(np.abs(np.asarray(step(x, u)) - np.asarray(half(half(x, u), u)))))
    if difference > tolerance_K:
        raise InputError("dt_s", dt_s, f"{model.name} cannot be discretised accurately at this step: one step "
                         f"and two half steps differ by {difference:.3g} K at rated load (limit {tolerance_K:g} K); "
                         "use a shorter step")
    return difference
