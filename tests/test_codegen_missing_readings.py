"""Generated filter updates ignore a missing reading whatever its value (codegen/ABI.md).

``gt_ekf_update`` takes ``measured[i] = 0`` as "sensor i was not read": its ``y[i]`` -- NaN,
infinity, a huge number -- must not reach the state, the covariance or the change test.
``gt_kalman_update`` has no flag: a non-finite ``y[i]`` is the missing reading. Both are checked
through ctypes against the Python filters and, with a small C driver, under valgrind's memcheck
(uninitialised reads, out-of-bounds access).
"""

import shutil
import subprocess

import numpy as np
import pytest

from genthermal.ccompile import compile_objects, find_compiler
from genthermal.errors import CompilerNotFoundError
from genthermal.estimation.ekf import ExtendedKalmanFilter
from genthermal.estimation.kalman import KalmanFilter

DT_S = 10.0
PREDICT_STEPS = 3
BAD_VALUES = [np.nan, -np.nan, np.inf, -np.inf, 1e308, -1e300, 0.0]
BAD_IDS = ["nan", "-nan", "inf", "-inf", "1e308", "-1e300", "zero"]


@pytest.fixture(scope="module")
def filters(design_model):
    return ExtendedKalmanFilter(design_model, DT_S), KalmanFilter(design_model, dt_s=DT_S)


@pytest.fixture(scope="module")
def generated(design_model, filters, tmp_path_factory):
    """Sources and loaded library of the design model with both filter updates."""
    from genthermal.ccompile import CompiledModel, compile_library
    from genthermal.codegen import generate_c

    try:
        find_compiler()
    except CompilerNotFoundError as exc:
        pytest.skip(f"no C compiler: {exc}")
    ekf, kalman = filters
    functions = {"ekf_update": ekf.update_function(), "kalman_update": kalman.update_function()}
    sources = generate_c(design_model, tmp_path_factory.mktemp("gtm"), DT_S, "gtm", functions)
    return sources, CompiledModel(compile_library(sources), sources)


def _ekf_inputs(ekf, design_model):
    nx = design_model.n_states
    disturbances = np.resize([8.0, -3.0, 5.0, 2.0, 6.0, -1.0, 1.0], len(ekf.disturbance_names))
    z = np.concatenate([np.linspace(40.0, 90.0, nx), disturbances])
    P = ekf.P0 * 0.3 + 0.01
    u = design_model.input_vector(6.0, 6.0, 6.0, 0.93, 22.0, 21.0)
    y = ekf.H @ z + ekf.e + np.array([0.4, -0.2])
    return z, P, u, y


@pytest.mark.parametrize("bad", BAD_VALUES, ids=BAD_IDS)
@pytest.mark.parametrize("missing", [0, 1], ids=["winding missing", "iron missing"])
def test_ekf_update_ignores_a_flagged_missing_reading_whatever_its_value(generated, filters, design_model,
                                                                         bad, missing):
    _, library = generated
    ekf, _ = filters
    z, P, u, y = _ekf_inputs(ekf, design_model)
    measured = np.ones(2)
    measured[missing] = 0.0
    reference = library.call("ekf_update", z, P, u, y, measured, np.zeros(2))
    y_bad = y.copy()
    y_bad[missing] = bad
    results = library.call("ekf_update", z, P, u, y_bad, measured, np.zeros(2))
    for got, expected in zip(results, reference):
        assert np.all(np.isfinite(got))
        np.testing.assert_array_equal(got, expected)  # bit for bit: the value is never read
    step = ekf.update(z, P, np.where(measured == 1, y, np.nan))  # the Python filter
    np.testing.assert_allclose(results[0], step.x, atol=1e-9)
    np.testing.assert_allclose(np.reshape(results[1], P.shape), step.P, atol=1e-9)
    assert float(np.ravel(results[5])[0]) == 0.0  # no change test with a sensor missing


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf], ids=["nan", "inf", "-inf"])
def test_ekf_update_skips_a_non_finite_reading_flagged_as_read(generated, filters, design_model, bad):
    _, library = generated
    ekf, _ = filters
    z, P, u, y = _ekf_inputs(ekf, design_model)
    y_bad = y.copy()
    y_bad[0] = bad
    results = library.call("ekf_update", z, P, u, y_bad, np.ones(2), np.zeros(2))
    reference = library.call("ekf_update", z, P, u, y, np.array([0.0, 1.0]), np.zeros(2))
    for got, expected in zip(results, reference):
        np.testing.assert_array_equal(got, expected)


@pytest.mark.parametrize("flag", [np.nan, 0.5, -1.0, 2.0], ids=["nan", "half", "negative", "two"])
def test_ekf_update_counts_a_flag_other_than_one_as_missing(generated, filters, design_model, flag):
    _, library = generated
    ekf, _ = filters
    z, P, u, y = _ekf_inputs(ekf, design_model)
    results = library.call("ekf_update", z, P, u, y, np.array([flag, 1.0]), np.zeros(2))
    reference = library.call("ekf_update", z, P, u, y, np.array([0.0, 1.0]), np.zeros(2))
    for got, expected in zip(results, reference):
        np.testing.assert_array_equal(got, expected)


def test_every_sensor_missing_is_prediction_only(generated, filters, design_model):
    _, library = generated
    ekf, _ = filters
    z, P, u, _ = _ekf_inputs(ekf, design_model)
    z_filtered, P_filtered, z_next, *_ = library.call("ekf_update", z, P, u, np.array([np.nan, np.inf]),
                                                      np.zeros(2), np.zeros(2))
    np.testing.assert_array_equal(z_filtered, z)
    np.testing.assert_allclose(np.reshape(P_filtered, P.shape), P, atol=1e-12)
    np.testing.assert_allclose(z_next, np.ravel(ekf.predict(z, P, u)[0]), atol=1e-9)


DRIVER = r"""
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "gtm.h"

#define NZ (GTM_N_STATES + %(n_disturbances)d)
#define NY GTM_N_OUTPUTS

static int all_finite(const double* v, int n)
{
    int i;
    for (i = 0; i < n; ++i) if (!isfinite(v[i])) return 0;
    return 1;
}

int main(void)
{
    static double z[NZ], P[NZ * NZ], z_f[NZ], P_f[NZ * NZ], z_n[NZ], P_n[NZ * NZ];
    double u[GTM_N_INPUTS] = {6.0, 6.0, 6.0, 0.93, 22.0, 21.0};
    double y[NY], measured[NY], mean[NY] = {0}, mean_next[NY], statistic, x_f[GTM_N_STATES], x_n[GTM_N_STATES];
    const double bad[] = {NAN, -NAN, INFINITY, -INFINITY, 1e308};
    double* work = malloc(gtm_work_size() * sizeof(double));  /* uninitialised on purpose */
    int i, j, k, failures = 0;
    for (i = 0; i < NZ; ++i) { z[i] = i < GTM_N_STATES ? 40.0 + i : 1.0; P[i * NZ + i] = 4.0; }
    for (k = 0; k < 5; ++k) for (j = 0; j < NY; ++j) {
        for (i = 0; i < NY; ++i) { y[i] = 60.0; measured[i] = 1.0; }
        y[j] = bad[k];
        measured[j] = 0.0;
        if (gtm_ekf_update(z, P, u, y, measured, mean, z_f, P_f, z_n, P_n, mean_next, &statistic, work,
                           gtm_work_size())) return 2;
        failures += !(all_finite(z_f, NZ) && all_finite(P_f, NZ * NZ) && all_finite(z_n, NZ)
                      && all_finite(P_n, NZ * NZ) && all_finite(mean_next, NY) && isfinite(statistic));
        if (gtm_kalman_update(z, u, y, x_f, x_n, work, gtm_work_size())) return 2;
        failures += !(all_finite(x_f, GTM_N_STATES) && all_finite(x_n, GTM_N_STATES));
    }
    free(work);
    printf("failures %%d\n", failures);
    return failures != 0;
}
"""


def test_missing_readings_under_valgrind(generated, filters, tmp_path):
    """A C program feeds NaN, infinities and a huge value as missing readings to both updates; memcheck
    reports no error and every result is finite."""
    valgrind = shutil.which("valgrind")
    if valgrind is None:
        pytest.skip("valgrind is not installed (apt-get install valgrind); the ctypes tests above still ran")
    sources, _ = generated
    ekf, _ = filters
    driver = tmp_path / "driver.c"
    driver.write_text(DRIVER % {"n_disturbances": len(ekf.disturbance_names)})
    program = tmp_path / "driver"
    objects = compile_objects(sources.sources, sources.headers)  # the library's, from the cache
    subprocess.run([*find_compiler(), "-O2", "-g", "-std=c99", "-I", str(sources.directory), "-o", str(program),
                    str(driver), *map(str, objects), "-lm"], check=True, capture_output=True, timeout=300)
    run = subprocess.run([valgrind, "--error-exitcode=99", "--track-origins=yes", "--leak-check=full",
                          str(program)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr[-3000:]
    assert "failures 0" in run.stdout
    assert "ERROR SUMMARY: 0 errors" in run.stderr
