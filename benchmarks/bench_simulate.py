"""Side by side: how fast and how close the ways of simulating a 4-hour mission at 1 s are.

Run ``python benchmarks/bench_simulate.py --json bench_simulate.json``; prints JSON and writes it.

Methods, one process, the thesis Fig. 7.7 mission (4 h) sampled every 1 s (14 400 steps), each
timed as the median of several repeats (inputs prepared beforehand, outputs preallocated where the
method allows):

* ``c_linear`` / ``c_nonlinear`` -- generated C ``gt_simulate`` through ctypes
  (:class:`genthermal.ccompile.CompiledModel`), exact zero-order hold / ETD2RK step;
* ``casadi_linear`` / ``casadi_nonlinear`` -- CasADi in-process, ``DiscreteModel.simulator(N)``;
* ``scipy_bdf_*`` / ``scipy_rk45_*`` -- ``scipy.integrate.solve_ivp`` on a numpy right-hand side,
  segment by segment over the constant-input pieces, rtol = atol = 1e-8. Linear model:
  ``A x + B u + c`` with A, B, c from the model's exact Jacobians. Nonlinear model: the right-hand
  side is affine in x for a fixed input (copper resistance linear in temperature), so on each
  piece ``f(x) = J(u) x + f(0, u)`` exactly, with ``J(u)`` and ``f(0, u)`` from the CasADi
  functions (checked: ``jac_x`` does not depend on x);
* ``floor_linear`` -- a plain hand-written C loop ``x <- A x + B u + c + D max(-(R u + r), 0)`` with
  the same A, B, c as the exact linear step and the model's loss floors, compiled here with the
  library's flags: the floor for any 8-state step.

``max_abs_diff_K`` compares every method with the BDF solution of the same model,
``max_abs_diff_from_python_step_K`` the C library and the floor with the model's own step in
CasADi. The floor applies the design model's copper-loss floors (a loss line held at 0 W below
1.6 A, :class:`~genthermal.losses.LossFloor`, read from the model's sympy heat sources), so it
computes what the generated step computes. The three C methods are timed in turn in every round
(``interleaved_times``), and ``c_over_floor`` is the median of the per-round ratios.
``instructions_callgrind`` counts the instructions each C method executes over the mission
(valgrind's callgrind, only inside the timed function; absent without valgrind): the same on every
run, so the ``*_instructions_*`` targets do not depend on the machine's load.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np
import sympy
from scipy.integrate import solve_ivp

from genthermal.ccompile import COMPILE_FLAGS, find_compiler
from genthermal.codegen import generate_c, model_library
from genthermal.design import linear_design_model
from genthermal.losses import LossFloor, input_symbol
from genthermal.machines import build_model
from genthermal.mission import load_mission

MISSION = "thesis_fig_7_7"
DT_S = 1.0
TOLERANCE = 1e-8
FLOOR_SOURCE = r"""
#define NX %(nx)d
#define NU %(nu)d
#define NF %(nf)d
void floor_simulate(const double* restrict A, const double* restrict B, const double* restrict c,
                    const double* restrict R, const double* restrict r, const double* restrict D,
                    const double* restrict x0, const double* restrict U, int n_steps, double* restrict X)
{
    int k, i, j;
    for (k = 0; k < n_steps; ++k) {
        const double* x = k ? X + (k - 1) * NX : x0;
        const double* u = U + k * NU;
        double* next = X + k * NX;
        for (i = 0; i < NX; ++i) {
            double sum = c[i];
            for (j = 0; j < NX; ++j) sum += A[i * NX + j] * x[j];
            for (j = 0; j < NU; ++j) sum += B[i * NU + j] * u[j];
            next[i] = sum;
        }
        for (j = 0; j < NF; ++j) {  /* loss floors: the line of loss j is held at 0 W below its zero */
            double excess = -r[j];
            for (i = 0; i < NU; ++i) excess -= R[j * NU + i] * u[i];
            if (excess > 0.0)
                for (i = 0; i < NX; ++i) next[i] += D[i * NF + j] * excess;
        }
    }
}
"""


def loss_floors(model, discrete) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(R, r, D) of the model's loss floors, from its sympy heat sources: floor j holds the loss line
    ``R[j] u + r[j]`` (a :class:`~genthermal.losses.LossFloor`) at 0 W, which adds ``D[:, j]`` times
    ``max(-(R[j] u + r[j]), 0)`` to the affine step ``A x + B u + c``. ``D[:, j]`` is measured on the
    model's own step at the rating with floor j's currents at 0 A."""
    atoms = sorted(set().union(*(s.power.atoms(LossFloor) for s in model.network.heat_sources)), key=str)
    values = {model.parameters[n].symbol: model.parameters[n].value for n in model.parameter_names}
    inputs = [input_symbol(n) for n in model.input_names]
    lines = [sympy.Poly(atom.args[0].subs(values), *inputs) for atom in atoms]
    R = np.array([[float(line.coeff_monomial(v)) for v in inputs] for line in lines]).reshape(len(atoms), len(inputs))
    r = np.array([float(line.coeff_monomial(1)) for line in lines])
    rated = model.input_vector(**model.spec.interface.rated_inputs)
    x = np.full(model.n_states, 60.0)
    D = np.zeros((model.n_states, len(atoms)))
    for j in range(len(atoms)):
        u = np.where(R[j] != 0.0, 0.0, rated)
        excess = -(R @ u + r)
        if not (excess[j] > 0 and np.all(np.delete(excess, j) <= 0)):
            raise SystemExit(f"cannot isolate loss floor {atoms[j]}: the floor needs its own measurement point")
        affine = discrete.A @ x + discrete.B @ u + discrete.c
        D[:, j] = (np.asarray(discrete.step(x, u)).ravel() - affine) / excess[j]
    return R, r, D


def median_time(function, repeats: int) -> float:
    """Median wall time of ``function()`` over ``repeats`` calls (after one warm-up call), s."""
    function()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def compile_floor(nx: int, nu: int, nf: int, directory: Path):
    """Compile the hand-written loop into a shared library and return its ctypes function."""
    source = directory / "floor.c"
    source.write_text(FLOOR_SOURCE % {"nx": nx, "nu": nu, "nf": max(nf, 1)})
    library = directory / "libfloor.so"
    subprocess.run([*find_compiler(), "-shared", *COMPILE_FLAGS, "-o", str(library), str(source)], check=True)
    function = ctypes.CDLL(str(library)).floor_simulate
    function.restype = None
    function.argtypes = [ctypes.c_void_p] * 8 + [ctypes.c_int, ctypes.c_void_p]
    return function


DRIVER_SOURCE = r"""
#include <stdio.h>
#include <stdlib.h>
#include "%(prefix)s.h"
void floor_simulate(const double* A, const double* B, const double* c, const double* R, const double* r,
                    const double* D, const double* x0, const double* U, int n_steps, double* X);

static double* load(FILE* file, size_t count)
{
    double* values = malloc(count * sizeof(double));
    if (!values || fread(values, sizeof(double), count, file) != count) exit(3);
    return values;
}

int main(int argc, char** argv)
{
    const int n = %(n_steps)d, nx = %(nx)d, nu = %(nu)d, nf = %(nf)d;
    FILE* file = argc == 3 ? fopen(argv[2], "rb") : NULL;
    double *x0, *U, *A, *B, *c, *R, *r, *D, *X = malloc((size_t)n * nx * sizeof(double));
    double* work = malloc((%(prefix)s_work_size() + 1) * sizeof(double));
    int status = 0;
    if (!file || !X || !work) return 2;
    x0 = load(file, nx); U = load(file, (size_t)n * nu); A = load(file, nx * nx); B = load(file, nx * nu);
    c = load(file, nx); R = load(file, nf * nu); r = load(file, nf); D = load(file, nx * nf);
    if (argv[1][0] == 'c') status = %(prefix)s_simulate(x0, U, n, X, work, %(prefix)s_work_size());
    else floor_simulate(A, B, c, R, r, D, x0, U, n, X);
    printf("%%.17g\n", X[(size_t)(n - 1) * nx]);
    return status;
}
"""


def instruction_counts(models: dict, arrays: list, n_steps: int, nf: int, directory: Path) -> dict | None:
    """Instructions executed by each model's ``gt_simulate`` over the mission and by the floor loop,
    counted by valgrind's callgrind (``--toggle-collect``: inside that function only); None without
    valgrind. Deterministic, unlike wall time on a shared machine."""
    valgrind = shutil.which("valgrind")
    if valgrind is None:
        return None
    data = directory / "inputs.bin"
    data.write_bytes(b"".join(np.ascontiguousarray(a, dtype=float).tobytes() for a in
                              (arrays[6], arrays[7], *arrays[:6])))
    counts = {}
    for variant, model in models.items():
        prefix = f"count_{variant}"
        generated = generate_c(model, directory / prefix, DT_S, prefix)
        driver = directory / f"{prefix}_driver.c"
        driver.write_text(DRIVER_SOURCE % {"prefix": prefix, "n_steps": n_steps, "nx": model.n_states,
                                           "nu": len(model.input_names), "nf": nf})
        program = directory / f"{prefix}_driver"
        subprocess.run([*find_compiler(), *COMPILE_FLAGS, "-I", str(generated.directory), "-o", str(program),
                        str(driver), str(directory / "floor.c"), *map(str, generated.sources), "-lm"], check=True)
        entries = {f"c_{variant}": ("c", f"{prefix}_simulate")}
        if variant == "linear":
            entries["floor_linear"] = ("floor", "floor_simulate")
        for key, (mode, function) in entries.items():
            out = directory / f"{key}.callgrind"
            subprocess.run([valgrind, "--tool=callgrind", f"--callgrind-out-file={out}", f"--toggle-collect={function}",
                            str(program), mode, str(data)], check=True, capture_output=True)
            summary = [line for line in out.read_text().splitlines() if line.startswith(("summary:", "totals:"))]
            counts[key] = int(summary[0].split()[1])
    return counts


def constant_pieces(U: np.ndarray) -> list[tuple[int, int]]:
    """(first, end) step indices of the runs of identical input rows."""
    changes = np.flatnonzero(np.any(np.diff(U, axis=0) != 0.0, axis=1)) + 1
    bounds = [0, *changes.tolist(), len(U)]
    return list(zip(bounds[:-1], bounds[1:]))


def affine_pieces(model, U: np.ndarray, pieces) -> list[tuple[np.ndarray, np.ndarray]]:
    """(J, f0) with f(x, u) = J x + f0 on every constant-input piece (exact: checked)."""
    x = ca.SX.sym("x", model.n_states)
    if ca.depends_on(model.functions["jac_x"](x, U[0], model.p0), x):
        raise SystemExit("the right-hand side is not affine in x: use model.rhs for scipy instead")
    zero = np.zeros(model.n_states)
    return [(model.jacobian_x(zero, U[a]), model.rhs(zero, U[a])) for a, _ in pieces]


def scipy_simulate(method: str, x0, pieces, affine, dt: float) -> np.ndarray:
    """States after every step, integrating f = J x + f0 piece by piece with ``solve_ivp``."""
    states, x = [], np.asarray(x0, dtype=float)
    for (first, end), (J, f0) in zip(pieces, affine):
        t_eval = np.arange(first + 1, end + 1) * dt
        options = {"jac": J} if method == "BDF" else {}
        solution = solve_ivp(lambda t, y, J=J, f0=f0: J @ y + f0, (first * dt, end * dt), x, method=method,
                             t_eval=t_eval, rtol=TOLERANCE, atol=TOLERANCE, **options)
        states.append(solution.y.T)
        x = solution.y[:, -1]
    return np.vstack(states)


def interleaved_times(functions: dict, rounds: int) -> dict:
    """Wall times (s) of every function in ``functions``, called in turn in each of ``rounds`` rounds
    (after one warm-up round), so that load on the machine hits them alike."""
    for function in functions.values():
        function()
    times = {name: [] for name in functions}
    for _ in range(rounds):
        for name, function in functions.items():
            start = time.perf_counter()
            function()
            times[name].append(time.perf_counter() - start)
    return times


def run(repeats: int) -> dict:
    """Measure every method; return the JSON-ready results."""
    plant = build_model()
    models = {"linear": linear_design_model(plant), "nonlinear": plant}
    inputs = load_mission(MISSION).to_inputs(DT_S)
    U = np.ascontiguousarray(inputs[list(plant.input_names)].to_numpy()[:-1])
    n_steps, x0 = len(U), np.full(plant.n_states, U[0, plant.input_names.index("T_ambient")])
    pieces = constant_pieces(U)
    median_s, differences, against_model, results = {}, {}, {}, {}
    fast, outputs = {}, {}
    with tempfile.TemporaryDirectory() as scratch:
        for variant, model in models.items():  # the C methods: timed side by side below
            compiled = model_library(model, dt_s=DT_S, prefix=f"bench_{variant}")
            outputs[f"c_{variant}"] = X = np.empty((n_steps, model.n_states))
            fast[f"c_{variant}"] = lambda compiled=compiled, X=X: compiled.simulate(x0, U, out=X)
        linear = models["linear"]
        discrete = linear.discretise(DT_S)
        R, r, D = loss_floors(linear, discrete)
        if not len(r):  # no floor: one that never acts keeps the loop's shape
            R, r, D = np.zeros((1, len(linear.input_names))), np.zeros(1), np.zeros((linear.n_states, 1))
        arrays = [np.ascontiguousarray(m) for m in (discrete.A, discrete.B, discrete.c, R, r, D, x0, U)]
        floor = compile_floor(linear.n_states, len(linear.input_names), len(r), Path(scratch))
        outputs["floor_linear"] = X_floor = np.empty((n_steps, linear.n_states))
        fast["floor_linear"] = lambda: floor(*(a.ctypes.data for a in arrays), n_steps, X_floor.ctypes.data)
        times = interleaved_times(fast, repeats * 10)
        instructions = instruction_counts(models, arrays, n_steps, len(r), Path(scratch))
    median_s.update({name: statistics.median(t) for name, t in times.items()})
    c_over_floor = {v: float(np.median(np.array(times[f"c_{v}"]) / np.array(times["floor_linear"]))) for v in models}
    for variant, model in models.items():
        results["c"] = outputs[f"c_{variant}"]
        if variant == "linear":
            results["floor"] = outputs["floor_linear"]
        simulator = model.discretise(DT_S).simulator(n_steps)
        median_s[f"casadi_{variant}"] = median_time(lambda: simulator(x0, U.T), repeats)
        results["casadi"] = np.asarray(simulator(x0, U.T)).T
        affine = affine_pieces(model, U, pieces)
        for method in ("BDF", "RK45"):
            key = f"scipy_{method.lower()}"
            median_s[f"{key}_{variant}"] = median_time(lambda: scipy_simulate(method, x0, pieces, affine, DT_S),
                                                       max(repeats // 2, 1))
            results[key] = scipy_simulate(method, x0, pieces, affine, DT_S)
        against_model[variant] = {k: float(np.max(np.abs(results[k] - results["casadi"])))
                                  for k in ("c", "floor") if k in results}
        reference = results.pop("scipy_bdf")
        differences[variant] = {k: float(np.max(np.abs(v - reference))) for k, v in results.items()}
        results.clear()
    ratios = {
        "c_over_floor": c_over_floor,
        "c_over_floor_instructions": instructions and {
            v: instructions[f"c_{v}"] / instructions["floor_linear"] for v in models},
        "scipy_bdf_over_c": {v: median_s[f"scipy_bdf_{v}"] / median_s[f"c_{v}"] for v in models},
        "casadi_over_c": {v: median_s[f"casadi_{v}"] / median_s[f"c_{v}"] for v in models},
    }
    worst = max(max(d.values()) for d in differences.values())
    return {
        "mission": MISSION, "duration_h": n_steps * DT_S / 3600.0, "dt_s": DT_S, "n_steps": n_steps,
        "input_pieces": len(pieces), "repeats": repeats, "compiler": find_compiler(),
        "flags": " ".join(COMPILE_FLAGS), "loss_floors_in_floor": int(np.count_nonzero(np.any(D != 0, axis=0))),
        "scipy_rhs": {"linear": "numpy J x + f(0,u) per constant-input piece, exact (A, B, c with the loss floors)",
                      "nonlinear": "numpy J(u) x + f(0,u) per constant-input piece, exact (f affine in x)"},
        "median_s": median_s, "ratios": ratios, "max_abs_diff_K": differences,
        "max_abs_diff_from_python_step_K": against_model,
        "instructions_callgrind": instructions,
        "instructions_per_step": instructions and {k: v / n_steps for k, v in instructions.items()},
        "targets": {**({} if not instructions else {
                        "c_linear_instructions_within_3x_floor":
                            instructions["c_linear"] <= 3.0 * instructions["floor_linear"],
                        "c_nonlinear_instructions_within_6x_floor":
                            instructions["c_nonlinear"] <= 6.0 * instructions["floor_linear"]}),
                    "c_linear_within_3x_floor": ratios["c_over_floor"]["linear"] <= 3.0,
                    "c_nonlinear_within_6x_floor": ratios["c_over_floor"]["nonlinear"] <= 6.0,
                    "c_at_least_100x_faster_than_scipy_bdf": min(ratios["scipy_bdf_over_c"].values()) >= 100.0,
                    "floor_equals_the_model_within_1e-9_K": against_model["linear"]["floor"] <= 1e-9,
                    "c_equals_python_within_1e-9_K": max(d["c"] for d in against_model.values()) <= 1e-9,
                    "methods_agree_within_0.01_K": worst <= 0.01},
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", required=True, help="file to write the results to")
    parser.add_argument("--repeats", type=int, default=7, help="repeats of the slow methods (C: 10x)")
    args = parser.parse_args(argv)
    results = run(args.repeats)
    text = json.dumps(results, indent=2)
    Path(args.json).write_text(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
