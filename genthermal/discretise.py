r"""Discrete-time steps of a ThermalModel with inputs held constant over each step (ZOH).

Write the model as :math:`\dot x = Lx + N(x,u)` with :math:`L = \partial f/\partial x` at
:math:`x = 0, u = 0` (the network without input-dependent terms). With
:math:`E = e^{hL}`, :math:`\Gamma_1 = \int_0^h e^{Ls}ds` and
:math:`\Gamma_2 = \int_0^h e^{L(h-s)}s\,ds`, all from one matrix exponential (Van Loan):

* **linear design model** (:math:`N` independent of :math:`x`): exact zero-order hold,
  :math:`x^+ = Ex + \Gamma_1 N(u)`, which is :math:`A_d x + B_d u + c_d` wherever no loss floor
  of the model is active (:class:`~genthermal.losses.LossFloor`: the design model's copper loss
  below 1.6 A; :math:`B_d, c_d` are those of the affine branch, which the schedulers plan on);
* **nonlinear model**: the second-order exponential Runge-Kutta scheme of Cox and Matthews
  (ETD2RK), exact for the linear part,
  :math:`a = Ex + \Gamma_1 N(x,u)`, :math:`x^+ = a + \Gamma_2 (N(a,u) - N(x,u))/h`.

When :math:`f` is affine in :math:`x` for fixed :math:`u` (temperature-dependent copper
resistance is), :math:`N(x,u) = (J(u) - L)x + f(0,u)` and :math:`J(u) - L` is non-zero only in the
rows of the winding nodes, so the correction costs a few multiplications.

The step also takes a *forcing* :math:`w` (K/s), a rate added to :math:`\dot x` and held over
the step (an unknown heat flow :math:`q` at node i is :math:`w_i = q/C_i`). It enters :math:`N`,
so the same scheme carries it: :math:`\Gamma_1 w` for both variants (it cancels in the ETD2RK
correction). :attr:`DiscreteModel.step` is :attr:`DiscreteModel.forced_step` at :math:`w = 0`;
the extended Kalman filter uses the forced step, so filter and simulation share one integrator.
"""

from __future__ import annotations

import dataclasses
import casadi as ca
import numpy as np
import scipy.linalg

from .errors import InputError
from .model import ThermalModel


def phi_matrices(L: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return :math:`(e^{hL}, \\Gamma_1, \\Gamma_2)` for step ``h`` (s) by one matrix exponential."""
    n = L.shape[0]
    M = np.zeros((3 * n, 3 * n))
    M[:n, :n] = L
    M[:n, n:2 * n] = np.eye(n)
    M[n:2 * n, 2 * n:] = np.eye(n)
    expM = scipy.linalg.expm(M * h)
    return expM[:n, :n], expM[:n, n:2 * n], expM[:n, 2 * n:]


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
    rhs = model.functions["rhs"]
    L = np.asarray(model.functions["jac_x"](np.zeros(nx), np.zeros(nu), p))
    E, G1, G2 = phi_matrices(L, dt_s)
    f0 = rhs(ca.SX.zeros(nx), u, p)  # f(0, u)
    if model.is_affine:
        branch = model.functions["rhs_affine_branch"]
        B = np.asarray(ca.Function("B", [u], [ca.jacobian(branch(ca.SX.zeros(nx), u, p), u)])(0))
        c = np.asarray(branch(np.zeros(nx), np.zeros(nu), p)).ravel()
        Ad, Bd, cd = E, G1 @ B, G1 @ c
        x_next = ca.DM(Ad) @ x + ca.DM(G1) @ (f0 + w)
        step, forced = _step_functions(x, u, w, x_next)
        return DiscreteModel(model, float(dt_s), step, forced, True, Ad, Bd, cd)
    jac_x = model.functions["jac_x"]
    if ca.depends_on(jac_x(x, u, p), x):  # not affine in x: generic N = f - Lx
        def N(state):
            return rhs(state, u, p) - ca.DM(L) @ state + w
        a = ca.DM(E) @ x + ca.DM(G1) @ N(x)
        x_next = a + ca.DM(G2 / dt_s) @ (N(a) - N(x))
    else:
        J_minus_L = jac_x(ca.SX.zeros(nx), u, p) - ca.DM(L)
        a = ca.DM(E) @ x + ca.DM(G1) @ (J_minus_L @ x + f0 + w)
        x_next = a + ca.DM(G2 / dt_s) @ (J_minus_L @ (a - x))
    step, forced = _step_functions(x, u, w, x_next)
    return DiscreteModel(model, float(dt_s), step, forced, False, None, None, None)


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
