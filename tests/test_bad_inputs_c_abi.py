"""Bad input to the generated C library: one table row per case (codegen/ABI.md).

A work buffer shorter than ``gt_work_size()`` is refused by every entry point before anything is
written; a NULL pointer and a negative step count are refused; a NaN measurement makes
``kalman_update`` skip that sensor exactly as the Python filter does.
"""

import ctypes

import numpy as np
import pytest

from genthermal.ccompile import find_compiler
from genthermal.errors import CompilerNotFoundError
from genthermal.estimation.kalman import KalmanFilter

OK, ERR_NULL_POINTER, ERR_BAD_ARGUMENT, ERR_WORK_TOO_SMALL = 0, 1, 2, 4
SENTINEL = -12345.0


@pytest.fixture(scope="module")
def kalman(design_model):
    return KalmanFilter(design_model, dt_s=10.0)


@pytest.fixture(scope="module")
def library(design_model, kalman):
    """The design model's library with the filter (the same sources as tests/test_kalman.py, so the
    compiled library comes from the cache)."""
    from genthermal.codegen import model_library

    try:
        find_compiler()
    except CompilerNotFoundError as exc:
        pytest.skip(f"no C compiler: {exc}")
    functions = {"kalman_update": kalman.update_function(), "predict_30": kalman.predict_function(30)}
    return model_library(design_model, dt_s=10.0, prefix="gtl", extra_functions=functions)


def _arrays(library, entry: str, n_steps: int = 3):
    """Input arrays (filled with plausible values) and output arrays (filled with SENTINEL)."""
    n, m = library.n_states, library.n_inputs
    x, u = np.full(n, 40.0), np.array([5.0, 5.0, 5.0, 0.8, 20.0, 20.0])
    if entry == "step":
        return [x, u], [np.full(n, SENTINEL)]
    if entry == "simulate":
        return [x, np.tile(u, (n_steps, 1))], [np.full((n_steps, n), SENTINEL)]
    if entry in ("rhs", "jac_x", "jac_u", "jac_p", "outputs"):
        shape = {"rhs": n, "jac_x": (n, n), "jac_u": (n, m), "jac_p": (n, library.n_params),
                 "outputs": library.n_outputs}[entry]
        return [x, u, None], [np.full(shape, SENTINEL)]
    signature = library.generated.extra_functions[[s.name for s in library.generated.extra_functions].index(entry)]
    inputs = [np.full(rows * cols, 30.0) for _, (rows, cols) in signature.inputs]
    return inputs, [np.full(rows * cols, SENTINEL) for _, (rows, cols) in signature.outputs]


def _call(library, entry, inputs, outputs, work, work_size, n_steps=3):
    pointers = [None if a is None else a.ctypes.data for a in inputs]
    if entry == "simulate":
        pointers = [pointers[0], pointers[1], n_steps]
    return library._entries[entry](*pointers, *(o.ctypes.data for o in outputs),
                                   None if work is None else work.ctypes.data, work_size)


ENTRIES = ["step", "simulate", "rhs", "jac_x", "jac_u", "jac_p", "outputs", "kalman_update", "predict_30"]

# (case, entry, work doubles relative to gt_work_size() or None for NULL, n_steps, expected status)
CASES = [
    *((f"{entry}: work one double short", entry, -1, 3, ERR_WORK_TOO_SMALL) for entry in ENTRIES),
    *((f"{entry}: work size 0", entry, "zero", 3, ERR_WORK_TOO_SMALL) for entry in ("step", "kalman_update")),
    *((f"{entry}: NULL work", entry, None, 3, ERR_NULL_POINTER) for entry in ("simulate", "outputs", "predict_30")),
    ("simulate: negative step count", "simulate", 0, -1, ERR_BAD_ARGUMENT),
    *((f"{entry}: exact work size", entry, 0, 3, OK) for entry in ENTRIES),
]


@pytest.mark.parametrize("entry, work_delta, n_steps, expected", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_entry_points_refuse_bad_arguments_without_writing(library, entry, work_delta, n_steps, expected):
    size = library._lib.gtl_work_size()
    inputs, outputs = _arrays(library, entry)
    if work_delta is None:
        work, work_size = None, size
    elif work_delta == "zero":
        work, work_size = np.zeros(max(size, 1)), 0
    else:
        work, work_size = np.zeros(max(size + work_delta, 1)), size + work_delta
    status = _call(library, entry, inputs, outputs, work, ctypes.c_size_t(max(work_size, 0)), n_steps)
    assert status == expected
    written = [np.any(o != SENTINEL) for o in outputs]
    assert all(written) if expected == OK else not any(written)


@pytest.mark.parametrize("measurement", [[80.0, 50.0], [np.nan, 50.0], [80.0, np.nan], [np.nan, np.nan],
                                         [np.inf, 50.0], [80.0, -np.inf]],
                         ids=["both", "winding missing", "iron missing", "none", "winding inf", "iron -inf"])
def test_c_kalman_update_skips_a_missing_measurement_as_python_does(library, kalman, measurement):
    x_pred = np.linspace(30.0, 60.0, library.n_states)
    u = np.array([5.0, 5.0, 5.0, 0.8, 20.0, 20.0])
    x_filtered, x_next = library.call("kalman_update", x_pred, u, np.array(measurement))
    expected = kalman.update(x_pred, None, np.where(np.isfinite(measurement), measurement, np.nan))
    assert np.all(np.isfinite(x_filtered)) and np.all(np.isfinite(x_next))
    np.testing.assert_allclose(x_filtered, expected.x, atol=1e-9)
    np.testing.assert_allclose(x_next, kalman.predict(expected.x, None, u)[0], atol=1e-9)
    if not np.isfinite(measurement).any():
        np.testing.assert_array_equal(x_filtered, x_pred)  # prediction only
