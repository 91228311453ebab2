"""One Kalman filter update, linear and extended: generated C next to Python, side by side.

Run ``python benchmarks/bench_kalman.py --json bench_kalman.json``; prints JSON and writes it.

* ``c_update_ns`` -- ``gt_kalman_update`` (steady-state gain, 8 states, 2 sensors; the update and
  the one-step prediction) called in a C loop of one million iterations, compiled with the
  library's flags; timed inside the C program, so no Python call overhead is counted.
* ``python_update_ns`` -- :meth:`KalmanFilter.update` + :meth:`KalmanFilter.predict` in numpy
  (steady-state mode), median of repeats.
* ``casadi_update_ns`` -- the same CasADi function evaluated in-process with numpy arguments.
* ``ekf_c_update_ns`` -- ``gt_ekf_update`` (the extended Kalman filter on the nonlinear model with
  the disturbance states of :class:`ExtendedKalmanFilter`: ``ekf_states`` in the JSON, 15 for the
  thesis machine; full covariance, update and prediction with the exact Jacobian of the discrete
  step) in the same kind of C loop;
  ``ekf_python_update_ns`` --
  :meth:`ExtendedKalmanFilter.update` + :meth:`ExtendedKalmanFilter.predict`.

Target (issue): one filter update in generated C <= 1 µs.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from genthermal.ccompile import COMPILE_FLAGS, compile_objects, find_compiler
from genthermal.codegen import generate_c
from genthermal.design import linear_design_model
from genthermal.estimation.ekf import ExtendedKalmanFilter
from genthermal.estimation.ekf import embedded_functions as ekf_functions
from genthermal.estimation.kalman import KalmanFilter, embedded_functions
from genthermal.machines import build_model

ITERATIONS = 1_000_000
DRIVER = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <time.h>
#include "gt.h"
static double work[GT_WORK_SIZE];
int main(void)
{
    double x[8] = {40, 60, 58, 70, 69, 70, 35, 33}, u[6] = {5, 5, 5, 0.85, 20, 20}, y[2] = {70.2, 59.9};
    double filtered[8], next[8], checksum = 0.0;
    struct timespec start, stop;
    long k;
    clock_gettime(CLOCK_MONOTONIC, &start);
    for (k = 0; k < %(n)d; ++k) {
        gt_kalman_update(x, u, y, filtered, next, work, GT_WORK_SIZE);
        x[0] = next[0] - 1e-9 * (double)(k & 1);  /* keep the loop from being hoisted */
        checksum += next[3];
    }
    clock_gettime(CLOCK_MONOTONIC, &stop);
    printf("%%.6f %%.17g\n", ((stop.tv_sec - start.tv_sec) * 1e9 + (stop.tv_nsec - start.tv_nsec)) / %(n)d.0, checksum);
    return 0;
}
"""
EKF_DRIVER = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <time.h>
#include "gt.h"
#define NZ %(nz)d
static double work[GT_WORK_SIZE];
int main(void)
{
    double z[NZ] = {40, 60, 58, 70, 69, 70, 35, 33}, u[6] = {5, 5, 5, 0.85, 20, 20};
    double y[2] = {70.2, 59.9}, measured[2] = {1, 1}, mean[2] = {0, 0}, P[NZ * NZ] = {0};
    double zf[NZ], Pf[NZ * NZ], zn[NZ], Pn[NZ * NZ], mean_next[2], statistic;
    double checksum = 0.0;
    struct timespec start, stop;
    long k;
    for (k = 0; k < NZ; ++k) P[(NZ + 1) * k] = k < 8 ? 1.0 : 100.0;
    clock_gettime(CLOCK_MONOTONIC, &start);
    for (k = 0; k < %(n)d; ++k) {
        gt_ekf_update(z, P, u, y, measured, mean, zf, Pf, zn, Pn, mean_next, &statistic, work, GT_WORK_SIZE);
        z[0] = zn[0] - 1e-9 * (double)(k & 1);  /* keep the loop from being hoisted */
        checksum += zn[3] + Pn[0] + statistic;
    }
    clock_gettime(CLOCK_MONOTONIC, &stop);
    printf("%%.6f %%.17g\n", ((stop.tv_sec - start.tv_sec) * 1e9 + (stop.tv_nsec - start.tv_nsec)) / %(n)d.0, checksum);
    return 0;
}
"""


def c_update_ns(model, build: Path, extra_functions: dict, driver_source: str = DRIVER,
                iterations: int = ITERATIONS, sizes: dict | None = None) -> float:
    """Time one generated-C update (ns) in a compiled C loop; ``sizes`` fills the driver's other
    ``%(name)d`` fields (the EKF's state size ``nz``)."""
    generated = generate_c(model, build, dt_s=10.0, extra_functions=extra_functions)
    driver = build / "bench_driver.c"
    driver.write_text(driver_source % {"n": iterations, **(sizes or {})})
    program = build / "bench_driver"
    objects = compile_objects(generated.sources, generated.headers)  # cached, in parallel
    command = [*find_compiler(), *COMPILE_FLAGS, "-I", str(build), str(driver), *map(str, objects), "-o",
               str(program), "-lm"]
    subprocess.run(command, check=True)
    output = subprocess.run([str(program)], check=True, capture_output=True, text=True).stdout.split()
    return float(output[0])


def median_ns(function, repeats: int = 7, number: int = 2000) -> float:
    """Median over ``repeats`` of the mean time of ``number`` calls, ns."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(number):
            function()
        times.append((time.perf_counter() - start) / number * 1e9)
    return statistics.median(times)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="file to write the JSON to")
    args = parser.parse_args(argv)
    design = linear_design_model(build_model())
    kalman = KalmanFilter(design, dt_s=10.0)
    x = np.array([40, 60, 58, 70, 69, 70, 35, 33], dtype=float)
    u = np.array([5, 5, 5, 0.85, 20, 20], dtype=float)
    y = np.array([70.2, 59.9])

    def python_update():
        update = kalman.update(x, None, y)
        kalman.predict(update.x, None, u)

    casadi_update = kalman.update_function()
    with tempfile.TemporaryDirectory() as folder:
        c_ns = c_update_ns(design, Path(folder), embedded_functions(design, 10.0, 1))
    plant = build_model()
    ekf = ExtendedKalmanFilter(plant, dt_s=10.0)
    n_disturbances = len(ekf.disturbance_names)
    z = np.concatenate([x, np.resize([5.0, -2.0, 3.0, 1.0], n_disturbances)])
    P = np.diag([1.0] * len(x) + [100.0] * n_disturbances)

    def ekf_python_update():
        update = ekf.update(z, P, y)
        ekf.predict(update.x, update.P, u)

    with tempfile.TemporaryDirectory() as folder:
        ekf_c_ns = c_update_ns(plant, Path(folder), ekf_functions(plant, 10.0, 1), EKF_DRIVER, ITERATIONS // 10,
                                {"nz": len(ekf.state_names)})
    result = {
        "benchmark": "kalman_update", "states": design.n_states, "sensors": len(design.output_names),
        "c_update_ns": c_ns,
        "python_update_ns": median_ns(python_update),
        "casadi_update_ns": median_ns(lambda: casadi_update(x, u, y)),
    }
    result["python_over_c"] = result["python_update_ns"] / c_ns
    result.update({"ekf_states": len(ekf.state_names), "ekf_c_update_ns": ekf_c_ns,
                   "ekf_python_update_ns": median_ns(ekf_python_update, number=500)})
    result["ekf_python_over_c"] = result["ekf_python_update_ns"] / ekf_c_ns
    result["targets"] = {"c_update_within_1_us": c_ns <= 1000.0}
    text = json.dumps(result)
    print(text)
    if args.json:
        Path(args.json).write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
