r"""ARX models of one generator temperature driven by one input (thesis 5.3), fitted by least squares.

:func:`arx_fit` fits :math:`A(q)\,\tilde y(k) = B(q)\,u(k - n_k) + e(k)` (``na``, ``nb``, ``nk`` in
MATLAB's ``arx`` convention) with an optional output offset, integrated input (thesis eq. 5.9) and
constant term into an :class:`ArxModel`; :func:`simulation_scores` gives R² of the simulated
output and :func:`normalized_aic` MATLAB's normalised AIC. Method and the thesis's label swaps: ``docs/guide/methods.md``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import block_diag
from scipy.signal import lfilter, lfiltic

from ..errors import InputError


@dataclass(frozen=True, eq=False)
class ArxModel:
    """A fitted ARX model :math:`\\tilde y = q^{-n_k} B(q) / A(q)\\, u` (see the module docstring).

    Attributes
    ----------
    a : numpy.ndarray
        ``[1, a_1, ..., a_na]``, coefficients of A in powers of :math:`q^{-1}` (integrator included
        when ``integrated_input``).
    b : numpy.ndarray
        ``[b_0, ..., b_{nb-1}]``, coefficients of B.
    nk : int
        Input delay, samples.
    ts_s : float
        Sample time, s.
    y_offset : float
        Output level added to the model response, °C (0 when no offset was removed).
    integrated_input : bool
        True when fitted on the integrated input; ``a`` then contains the factor :math:`1 - q^{-1}`.
    loss_function : float
        V, mean squared one-step prediction error of the fit, K².
    aic : float
        :math:`\\ln V + 2 (n_a + n_b) / N` of the fit.
    constant : float
        Constant term :math:`c` of the fitted equation, K per sample (0 when not fitted).
    """

    a: np.ndarray
    b: np.ndarray
    nk: int
    ts_s: float = 10.0
    y_offset: float = 0.0
    integrated_input: bool = False
    loss_function: float = float("nan")
    aic: float = float("nan")
    constant: float = 0.0

    @property
    def structure(self) -> tuple[int, int, int]:
        """``(na, nb, nk)`` as fitted (the integrator of an integrated-input model not counted)."""
        return len(self.a) - 1 - int(self.integrated_input), len(self.b), self.nk

    def transfer_function(self) -> tuple[np.ndarray, np.ndarray]:
        """Return ``(num, den)`` in powers of :math:`z^{-1}`, zero-padded to the same length n + 1.

        :math:`G(z) = (\\mathrm{num}_0 + \\mathrm{num}_1 z^{-1} + \\dots) / (1 + \\mathrm{den}_1 z^{-1}
        + \\dots)` with ``num = [0]*nk + b``; multiplied by :math:`z^n` both are polynomials in z.
        """
        num = np.concatenate([np.zeros(self.nk), self.b])
        order = max(num.size, self.a.size)
        return np.pad(num, (0, order - num.size)), np.pad(self.a, (0, order - self.a.size))

    def simulate(self, u, y0: float | None = None, initial_output: float | None = None) -> np.ndarray:
        """Simulated output, °C: the model's response to ``u`` (and its constant term) plus a level.

        Parameters
        ----------
        u : array_like
            Input samples at the model's sample time (A, or A² for ``I_sq``).
        y0 : float, optional
            Output level added to the response, °C; default :attr:`y_offset`.
        initial_output : float, optional
            Measured output at the start of ``u``, °C: the model's past outputs are set to it
            (initialisation from the data). Default: from rest (past outputs at the level).
        """
        u = _finite_signal(u, "u")
        level = self.y_offset if y0 is None else float(y0)
        a_fit = self.fitted_denominator
        v = np.cumsum(u) if self.integrated_input else u
        num = np.concatenate([np.zeros(self.nk), self.b])
        order = max(num.size, a_fit.size) - 1
        state = None
        if initial_output is not None and order > 0:
            past = np.full(order, float(initial_output) - level)
            state = lfiltic(num, a_fit, past, np.zeros(order))
        with np.errstate(over="ignore", invalid="ignore"):
            response = lfilter(num, a_fit, v) if state is None else lfilter(num, a_fit, v, zi=state)[0]
            if self.constant:
                response = response + lfilter([self.constant], a_fit, np.ones_like(v))
        return level + response

    @property
    def fitted_denominator(self) -> np.ndarray:
        """A of the fitted equation: :attr:`a` without the integrator of an integrated-input model."""
        if not self.integrated_input:
            return self.a
        quotient, _ = np.polydiv(self.a, [1.0, -1.0])
        return quotient

    def predict_one_step(self, y, u) -> np.ndarray:
        """One-step-ahead prediction :math:`\\hat y(k) = y_{\\mathrm{offset}} + (1 - A(q)) \\tilde y(k)
        + q^{-n_k} B(q) u(k)`, °C, from measured outputs up to k-1 (before the record: at rest).

        Samples whose regressors include a missing (NaN) output are NaN.
        """
        y, u = _signal(y, "y"), _finite_signal(u, "u")
        _check_same_length(y, u)
        regressors = regression_matrix(y - self.y_offset, u, len(self.a) - 1, len(self.b), self.nk)
        return self.y_offset + regressors @ np.concatenate([self.a[1:], self.b]) + self._constant_per_sample()

    def _constant_per_sample(self) -> float:
        """The constant term as it acts on :attr:`a` (the integrator differences it away)."""
        return 0.0 if self.integrated_input else self.constant

    def to_state_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Controllable canonical form :math:`x(k+1) = A x(k) + B u(k)`,
        :math:`\\tilde y(k) = C x(k) + D u(k)` of the transfer function (the offset not included).

        With ``num, den`` from :meth:`transfer_function` (n = order):
        first row of A ``-den[1:]``, ones on the sub-diagonal, ``B = e_1``,
        ``C = num[1:] - num[0] den[1:]``, ``D = num[0]``. A fitted :attr:`constant` is not part of
        it (it acts as a constant input; see :meth:`simulate`).
        """
        num, den = self.transfer_function()
        order = den.size - 1
        state_matrix = np.zeros((order, order))
        state_matrix[0, :] = -den[1:]
        state_matrix[1:, :-1] = np.eye(order - 1)
        input_matrix = np.zeros((order, 1))
        input_matrix[0, 0] = 1.0
        output_matrix = (num[1:] - num[0] * den[1:]).reshape(1, order)
        return state_matrix, input_matrix, output_matrix, np.array([[num[0]]])


def regression_matrix(y, u, na: int, nb: int, nk: int) -> np.ndarray:
    """Rows :math:`\\varphi(k) = [-y(k-1), \\dots, -y(k-n_a), u(k-n_k), \\dots, u(k-n_k-n_b+1)]`
    for every sample k, with samples before the record taken as zero."""
    y, u = np.asarray(y, dtype=float), np.asarray(u, dtype=float)
    columns = [-_delayed(y, lag) for lag in range(1, na + 1)]
    columns += [_delayed(u, nk + lag) for lag in range(nb)]
    return np.column_stack(columns)


def arx_fit(y, u, na: int, nb: int, nk: int, integrate_input: bool = False, remove_offset: bool = True,
            ts_s: float = 10.0, constant_term: bool = False) -> ArxModel:
    """Fit an ARX model by linear least squares (:func:`numpy.linalg.lstsq`).

    Parameters
    ----------
    y : array_like
        Measured output, °C, at sample time ``ts_s``; NaN samples (no measurement) are left out of
        the regression.
    u : array_like
        Input on the same grid (finite), e.g. I_exc in A.
    na, nb, nk : int
        Number of A parameters (>= 1), number of B parameters (>= 1), delay in samples (>= 0).
    integrate_input : bool
        Fit on the integrated input and multiply the integrator back (thesis eqs 5.9, 5.14-5.17).
    remove_offset : bool
        Subtract the first measured output before fitting (thesis 5.3.2).
    ts_s : float
        Sample time, s (stored in the model).
    constant_term : bool
        Also fit a constant :math:`c` (see the module docstring): needed when the record does not
        start at rest, e.g. after a discard.

    Returns
    -------
    ArxModel
        Uses the regression rows k >= max(na, nk + nb - 1) whose output and regressors are measured.
    """
    _check_orders(na, nb, nk)
    y, u = _signal(y, "y"), _finite_signal(u, "u")
    _check_same_length(y, u)
    measured = np.flatnonzero(np.isfinite(y))
    if measured.size == 0:
        raise InputError("y", "all NaN", "the output has no measured sample")
    y_offset = float(y[measured[0]]) if remove_offset else 0.0
    fit_input = np.cumsum(u) if integrate_input else u
    regressors = regression_matrix(y - y_offset, fit_input, na, nb, nk)
    if constant_term:
        regressors = np.column_stack([regressors, np.ones(y.size)])
    target = y - y_offset
    rows = np.arange(y.size) >= max(na, nk + nb - 1)
    rows &= np.isfinite(target) & np.all(np.isfinite(regressors), axis=1)
    n_rows, n_parameters = int(rows.sum()), na + nb + int(constant_term)
    if n_rows <= n_parameters:
        raise InputError("y", f"{n_rows} usable samples",
                         f"too few measured samples for {n_parameters} parameters (na={na}, nb={nb}, nk={nk})")
    theta = np.linalg.lstsq(regressors[rows], target[rows], rcond=None)[0]
    loss = float(np.mean((target[rows] - regressors[rows] @ theta) ** 2))
    a = np.concatenate([[1.0], theta[:na]])
    if integrate_input:
        a = np.convolve(a, [1.0, -1.0])
    return ArxModel(a=a, b=theta[na:na + nb], nk=int(nk), ts_s=float(ts_s), y_offset=y_offset,
                    integrated_input=bool(integrate_input), loss_function=loss,
                    aic=normalized_aic(loss, n_parameters, n_rows),
                    constant=float(theta[-1]) if constant_term else 0.0)


def normalized_aic(loss_function: float, n_parameters: int, n_samples: int) -> float:
    """:math:`\\mathrm{AIC} = \\ln V + 2 d / N` (MATLAB ``selstruc`` / ``aic(..., 'nAIC')``)."""
    with np.errstate(divide="ignore"):
        return float(np.log(loss_function) + 2.0 * n_parameters / n_samples)


def r_squared(measured, modelled) -> float:
    """:math:`R^2 = 1 - \\sum e^2 / \\sum (y - \\bar y)^2` over the samples where ``measured`` is
    finite; ``-inf`` when the model output diverges."""
    measured, modelled = np.asarray(measured, dtype=float), np.asarray(modelled, dtype=float)
    keep = np.isfinite(measured)
    if keep.sum() < 2:
        raise InputError("y", f"{int(keep.sum())} measured samples", "need at least two to compute R²")
    error = measured[keep] - modelled[keep]
    if not np.all(np.isfinite(error)):
        return float("-inf")
    spread = np.sum((measured[keep] - measured[keep].mean()) ** 2)
    return float(1.0 - np.sum(error**2) / spread) if spread > 0 else float("nan")


def simulation_scores(model: ArxModel, y, u, y0: float | None = None,
                      initial_output: float | None = None) -> dict[str, float]:
    """Compare ``model.simulate(u, y0, initial_output)`` with measured ``y`` (NaN samples skipped).

    Returns
    -------
    dict
        ``R2`` (see :func:`r_squared`), ``rmse_K`` and ``max_abs_error_K`` of the simulated output.
    """
    y = _signal(y, "y")
    simulated = model.simulate(u, y0, initial_output)
    _check_same_length(y, simulated)
    error = (simulated - y)[np.isfinite(y)]
    return {"R2": r_squared(y, simulated), "rmse_K": float(np.sqrt(np.mean(error**2))),
            "max_abs_error_K": float(np.max(np.abs(error)))}


def block_diagonal_state_space(models) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Stack SISO models into one MIMO state space (thesis eqs 5.18-5.23).

    Model i contributes its own state block, input i and output i: A, B, C and D are the
    block-diagonal stacks of the models' :meth:`ArxModel.to_state_space` matrices. Outputs are
    deviations from each model's ``y_offset``.
    """
    blocks = [model.to_state_space() for model in models]
    if not blocks:
        raise InputError("models", [], "need at least one model to stack")
    return tuple(block_diag(*(block[i] for block in blocks)) for i in range(4))


def _delayed(values: np.ndarray, lag: int) -> np.ndarray:
    """``values`` delayed by ``lag`` samples, zeros before the record."""
    if lag == 0:
        return values.copy()
    return np.concatenate([np.zeros(min(lag, values.size)), values[: max(values.size - lag, 0)]])


def _signal(values, name: str) -> np.ndarray:
    array = np.asarray(values, dtype=float)
    if array.ndim != 1:
        raise InputError(name, f"shape {array.shape}", "expected a one-dimensional signal")
    return array


def _finite_signal(values, name: str) -> np.ndarray:
    array = _signal(values, name)
    bad = np.flatnonzero(~np.isfinite(array))
    if bad.size:
        raise InputError(f"{name}[{bad[0]}]", float(array[bad[0]]), "the input must be finite at every sample")
    return array


def _check_same_length(y: np.ndarray, u: np.ndarray) -> None:
    if y.size != u.size:
        raise InputError("u", f"{u.size} samples", f"the output has {y.size} samples; both must match")


def _check_orders(na, nb, nk) -> None:
    for name, value, smallest in (("na", na, 1), ("nb", nb, 1), ("nk", nk, 0)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < smallest:
            raise InputError(name, value, f"must be an integer >= {smallest}")
