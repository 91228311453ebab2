r"""Rewrite CasADi SX functions into the form their generated C is fastest in, values unchanged.

:func:`inline_floors` writes every ``fmax``/``fmin`` against a constant as a C ternary;
:func:`affine_with_floors` writes an affine step with loss floors as
:math:`x^+ = A x + B u + c + D \max(R u + r, 0)`. Both fall back to the original function wherever
the form does not apply. Method notes: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

_SELECTS = {ca.OP_FMAX: lambda a, b: ca.if_else(a > b, a, b), ca.OP_FMIN: lambda a, b: ca.if_else(a < b, a, b)}
_NOT_ELEMENTWISE = {ca.OP_CALL}


def _rebuild(function: ca.Function, on_extremum, reciprocals: bool = False):
    """Evaluate ``function``'s instructions on fresh SX symbols, ``on_extremum(op, a, b)`` giving the
    value of every ``fmax``/``fmin`` (and, with ``reciprocals``, a division by a non-zero constant
    as a multiplication); return (inputs, outputs) or None for an instruction this cannot replay."""
    inputs = [ca.SX.sym(function.name_in(i), function.sparsity_in(i)) for i in range(function.n_in())]
    outputs = [ca.SX(function.sparsity_out(i)) for i in range(function.n_out())]
    work = {}
    for k in range(function.n_instructions()):
        op, args, results = function.instruction_id(k), function.instruction_input(k), function.instruction_output(k)
        if op == ca.OP_INPUT:
            work[results[0]] = inputs[args[0]].nz[args[1]]
        elif op == ca.OP_OUTPUT:
            outputs[results[0]].nz[results[1]] = work[args[0]]
        elif op == ca.OP_CONST:
            work[results[0]] = ca.SX(function.instruction_constant(k))
        elif op in _NOT_ELEMENTWISE or len(results) != 1:
            return None
        elif op in _SELECTS:
            work[results[0]] = on_extremum(op, work[args[0]], work[args[1]])
        elif len(args) == 1:
            work[results[0]] = ca.SX.unary(op, work[args[0]])
        elif (reciprocals and op == ca.OP_DIV and work[args[1]].is_constant() and float(work[args[1]]) != 0.0
              and np.isfinite(1.0 / float(work[args[1]]))):
            work[results[0]] = work[args[0]] * ca.SX(1.0 / float(work[args[1]]))
        elif len(args) == 2:
            work[results[0]] = ca.SX.binary(op, work[args[0]], work[args[1]])
        else:
            return None
    return inputs, outputs


def inline_floors(function: ca.Function, reciprocals: bool = False) -> ca.Function:
    """``function`` with ``fmax``/``fmin`` against a constant as a select, common subexpressions merged.

    The select returns what C's ``fmax``/``fmin`` return for every input, NaN included (a comparison
    with NaN is false, so the constant is taken). An MX function, or one with calls, is returned as is.

    Parameters
    ----------
    function : casadi.Function
    reciprocals : bool
        Also divide by a constant as a multiplication by its reciprocal: a division costs a
        multiplication's 4-20 times (in software double precision on a Cortex-M4F, hundreds of
        instructions); the result may differ in the last bit.

    Returns
    -------
    casadi.Function
        Same name, inputs and outputs, equal values (to the last bit with ``reciprocals`` off).
    """
    if not function.is_a("SXFunction"):
        return function

    def extremum(op, a, b):
        if b.is_constant() and not np.isnan(float(b)):
            return _SELECTS[op](a, b)
        if a.is_constant() and not np.isnan(float(a)):
            return _SELECTS[op](b, a)
        return ca.fmax(a, b) if op == ca.OP_FMAX else ca.fmin(a, b)

    rebuilt = _rebuild(function, extremum, reciprocals)
    if rebuilt is None:
        return function
    inputs, outputs = rebuilt
    return ca.Function(function.name(), inputs, [ca.cse(o) for o in outputs], function.name_in(), function.name_out())


def affine_with_floors(step: ca.Function) -> ca.Function | None:
    """``step`` ``(x, u) -> x_next`` written as :math:`Ax + Bu + c + D\\max(Ru + r, 0)` (module docstring).

    Parameters
    ----------
    step : casadi.Function
        SX function of two dense column inputs and one dense column output.

    Returns
    -------
    casadi.Function or None
        Same name and argument names; None when ``step`` is not affine in (x, u) up to
        ``fmax``/``fmin`` of affine functions of ``u``.
    """
    if not step.is_a("SXFunction") or step.n_in() != 2 or step.n_out() != 1:
        return None
    extrema = []  # (symbol standing for the extremum, its sign s, a, b): value = a + s max(s (b - a), 0)

    def extremum(op, a, b):
        symbol = ca.SX.sym(f"m{len(extrema)}")
        extrema.append((symbol, 1.0 if op == ca.OP_FMAX else -1.0, a, b))
        return symbol

    rebuilt = _rebuild(step, extremum)
    if rebuilt is None:
        return None
    (x, u), (x_next,) = rebuilt
    m = ca.vertcat(*(e[0] for e in extrema)) if extrema else ca.SX(0, 1)
    a = ca.vertcat(*(e[2] for e in extrema)) if extrema else ca.SX(0, 1)
    b = ca.vertcat(*(e[3] for e in extrema)) if extrema else ca.SX(0, 1)
    everything = ca.vertcat(x, u, m)
    if ca.depends_on(ca.vertcat(a, b), ca.vertcat(x, m)):
        return None  # a floor of the state, or of another floor: not this form
    pieces = ca.vertcat(ca.densify(x_next), a, b)
    jacobian = ca.jacobian(pieces, everything)
    if ca.depends_on(jacobian, everything):
        return None
    at_zero = ca.substitute(pieces, everything, ca.SX.zeros(everything.numel()))
    numbers = ca.Function("affine", [everything], [jacobian, at_zero])
    J, offset = (np.asarray(v, dtype=float) for v in numbers(np.zeros(everything.numel())))
    nx, nu, nm = x.numel(), u.numel(), m.numel()
    n = x_next.numel()
    offset = offset.ravel()
    Jx, Ju, Jm = J[:n, :nx], J[:n, nx:nx + nu], J[:n, nx + nu:]
    Ja_u, a0 = J[n:n + nm, nx:nx + nu], offset[n:n + nm]
    Jb_u, b0 = J[n + nm:, nx:nx + nu], offset[n + nm:]
    sign = np.array([e[1] for e in extrema])
    A, B, c = Jx, Ju + Jm @ Ja_u, offset[:n] + Jm @ a0  # every extremum at its first argument
    R, r = sign[:, None] * (Jb_u - Ja_u), sign * (b0 - a0)  # excess: max(R u + r, 0), times s
    columns = {}
    for k in range(nm):
        key = (tuple(R[k]), float(r[k]))
        columns[key] = columns.get(key, np.zeros(n)) + sign[k] * Jm[:, k]
    kept = [(key, column) for key, column in columns.items() if np.any(column != 0.0)]
    x_out = ca.DM(A) @ x + ca.DM(B) @ u + ca.DM(c)
    for (row, constant), column in kept:
        excess = ca.dot(ca.DM(row), u) + constant
        x_out = x_out + ca.DM(column) * ca.if_else(excess > 0, excess, 0)
    return ca.Function(step.name(), [x, u], [x_out], step.name_in(), step.name_out())
