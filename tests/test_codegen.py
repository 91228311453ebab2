"""Generated C against the CasADi model: entry points, simulation, example program, reentrancy,
ABI rules, and the paths without a compiler.

Both libraries are compiled once per session, concurrently, into a temporary cache.
"""

import concurrent.futures
import io
import re
import shutil
import subprocess
from pathlib import Path

import casadi as ca
import numpy as np
import pandas as pd
import pytest

from genthermal import ccompile
from genthermal.ccompile import CompiledModel, compile_library, compile_objects, find_compiler
from genthermal.cli import main
from genthermal.codegen import forbidden_constructs, generate_c
from genthermal.resources import TEMPLATE_DIR
from genthermal.errors import CompilerNotFoundError, InputError
from genthermal.mission import load_mission
from genthermal.simulate import simulate

STRICT_FLAGS = ["-O2", "-std=c99", "-Wall", "-Wextra", "-Werror"]


@pytest.fixture(scope="session", autouse=True)
def session_cache(tmp_path_factory):
    """Compiled objects and libraries go to a per-session cache directory."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("GENTHERMAL_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))
        yield


def _extra_functions(design_model):
    """A 5-step prediction (MX, matrix input) and a function with matrix inputs and outputs."""
    step = design_model.discretise(10.0).step
    x, U = ca.MX.sym("x", 8), ca.MX.sym("U", 6, 5)
    predict = ca.Function("predict", [x, U], [step.mapaccum(5)(x, U)], ["x", "U"], ["X"])
    M, v = ca.SX.sym("M", 3, 2), ca.SX.sym("v", 2)
    transform = ca.Function("transform", [M, v], [M @ v, M.T], ["M", "v"], ["Mv", "Mt"])
    return {"predict": predict, "transform": transform}


@pytest.fixture(scope="session")
def libraries(plant_model, design_model, tmp_path_factory):
    """Generated sources and loaded libraries: nonlinear ``gt``, linear ``gtl`` with extras."""
    try:
        find_compiler()
    except CompilerNotFoundError as exc:
        pytest.skip(f"no C compiler: {exc}")
    root = tmp_path_factory.mktemp("generated")
    generated = {
        "nonlinear": generate_c(plant_model, root / "gt", 10.0, "gt"),
        "linear": generate_c(design_model, root / "gtl", 10.0, "gtl", _extra_functions(design_model)),
    }
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        paths = dict(zip(generated, pool.map(compile_library, generated.values())))
    return {key: (generated[key], CompiledModel(paths[key], generated[key])) for key in generated}


@pytest.fixture(scope="session")
def mission_inputs():
    """The thesis Fig. 7.7 mission (4 h) sampled every 10 s."""
    return load_mission("thesis_fig_7_7").to_inputs(10.0)


def _model(variant, plant_model, design_model):
    return plant_model if variant == "nonlinear" else design_model


def _relative_error(got, expected):
    expected = np.asarray(expected, dtype=float).reshape(np.shape(got))
    return np.max(np.abs(got - expected)) / max(np.max(np.abs(expected)), 1e-300)


@pytest.mark.parametrize("variant", ["nonlinear", "linear"])
def test_entry_points_equal_casadi(variant, libraries, plant_model, design_model):
    model = _model(variant, plant_model, design_model)
    compiled = libraries[variant][1]
    step = model.discretise(10.0).step
    rng = np.random.default_rng(7)
    for _ in range(5):
        x = rng.uniform(-20.0, 160.0, model.n_states)
        u = np.concatenate([rng.uniform(0.0, 9.0, 4), rng.uniform(-40.0, 50.0, 2)])
        p = model.p0 * rng.uniform(0.8, 1.2, model.p0.size)
        for name in ("rhs", "jac_x", "jac_u", "jac_p", "outputs"):
            expected = model.functions[name](x, u, p)
            assert _relative_error(getattr(compiled, name)(x, u, p), expected) < 1e-12, name
        assert _relative_error(compiled.rhs(x, u), model.rhs(x, u)) < 1e-12  # p = NULL: defaults
        assert _relative_error(compiled.step(x, u), step(x, u)) < 1e-12
    assert compiled.state_names == tuple(model.state_names)
    assert compiled.parameter_names == tuple(model.parameter_names)
    np.testing.assert_array_equal(compiled.default_params, model.p0)
    assert compiled.dt_s == 10.0


@pytest.mark.parametrize("variant", ["nonlinear", "linear"])
def test_simulate_equals_python_simulation(variant, libraries, plant_model, design_model, mission_inputs):
    model = _model(variant, plant_model, design_model)
    reference = simulate(model, mission_inputs)
    U = mission_inputs[list(model.input_names)].to_numpy()
    x0 = np.full(model.n_states, U[0, -1])
    X = libraries[variant][1].simulate(x0, U[:-1])
    states = reference[[f"T_{name}" for name in model.state_names]].to_numpy()
    assert np.max(np.abs(X - states[1:])) < 1e-9
    assert states.max() > 60.0  # the mission heats the machine: the comparison is not trivial


def test_extra_functions_are_called_with_row_major_arrays(libraries, design_model):
    generated, compiled = libraries["linear"]
    assert [s.name for s in generated.extra_functions] == ["predict", "transform"]
    assert generated.extra_functions[1].outputs == (("Mv", (3, 1)), ("Mt", (2, 3)))
    rng = np.random.default_rng(3)
    x, U = rng.uniform(20.0, 90.0, 8), rng.uniform(0.0, 8.0, (6, 5))
    expected = np.asarray(design_model.discretise(10.0).simulator(5)(x, U))
    assert np.max(np.abs(compiled.call("predict", x, U) - expected)) < 1e-9
    M, v = np.arange(6.0).reshape(3, 2), np.array([1.0, -2.0])
    product, transposed = compiled.call("transform", M, v)
    np.testing.assert_array_equal(product, M @ v)
    np.testing.assert_array_equal(transposed, M.T)
    with pytest.raises(InputError, match="expected 6 values"):
        compiled.call("transform", M[:2], v)


def _library_objects(generated):
    """Cached objects of the CasADi sources (compiled with the library: cache hits)."""
    return [str(o) for o in compile_objects(generated.casadi_sources, generated.headers)]


def test_example_program_compiles_strictly_and_matches_python(libraries, plant_model, mission_inputs,
                                                              tmp_path):
    generated = libraries["nonlinear"][0]
    compiler = find_compiler()
    casadi_sources = [str(s) for s in generated.casadi_sources]
    subprocess.run([*compiler, *STRICT_FLAGS, "-Wno-unused-parameter", "-fsyntax-only", *casadi_sources],
                   check=True)
    program = tmp_path / "example_mission"
    subprocess.run([*compiler, *STRICT_FLAGS, f"-I{generated.directory}", "-o", str(program),
                    str(TEMPLATE_DIR / "example_mission.c"), str(generated.abi_source),
                    *_library_objects(generated), "-lm"], check=True)
    mission_csv = tmp_path / "mission.csv"
    mission_inputs.to_csv(mission_csv, index=False)
    run = subprocess.run([str(program), str(mission_csv)], capture_output=True, text=True, check=True)
    result = pd.read_csv(io.StringIO(run.stdout))
    reference = simulate(plant_model, mission_inputs)
    columns = [f"T_{name}" for name in plant_model.state_names]
    assert list(result.columns) == ["time_s", *columns]
    np.testing.assert_array_equal(result["time_s"], reference["time_s"])
    assert np.max(np.abs(result[columns].to_numpy() - reference[columns].to_numpy())) < 1e-9
    wrong_step = tmp_path / "wrong_step.csv"
    mission_inputs.iloc[::2].to_csv(wrong_step, index=False)
    refused = subprocess.run([str(program), str(wrong_step)], capture_output=True, text=True)
    assert refused.returncode != 0 and "the model steps by 10 s" in refused.stderr


THREADED_PROGRAM = r"""
#include <pthread.h>
#include <stdio.h>
#include "gt.h"
#include "gtl.h"
#define N_STEPS %(n_steps)d
#define REPEATS 20
static const double inputs[N_STEPS * 6] = {%(inputs)s};
typedef struct { int linear; int status; double X[N_STEPS * 8]; } job_t;
static void* run(void* argument)
{
    job_t* job = argument;
    double work[GT_WORK_SIZE > GTL_WORK_SIZE ? GT_WORK_SIZE : GTL_WORK_SIZE];
    double x0[8] = {20, 20, 20, 20, 20, 20, 20, 20};
    double again[N_STEPS * 8];
    int r, i;
    job->status = job->linear ? gtl_simulate(x0, inputs, N_STEPS, job->X, work, sizeof work / sizeof *work)
                              : gt_simulate(x0, inputs, N_STEPS, job->X, work, sizeof work / sizeof *work);
    for (r = 0; r < REPEATS; ++r) {
        job->status |= job->linear ? gtl_simulate(x0, inputs, N_STEPS, again, work, sizeof work / sizeof *work)
                                   : gt_simulate(x0, inputs, N_STEPS, again, work, sizeof work / sizeof *work);
        for (i = 0; i < N_STEPS * 8; ++i) if (again[i] != job->X[i]) job->status |= 16;
    }
    return NULL;
}
int main(void)
{
    static job_t jobs[4];
    pthread_t threads[4];
    int j, i;
    for (j = 0; j < 4; ++j) { jobs[j].linear = j %% 2; pthread_create(&threads[j], NULL, run, &jobs[j]); }
    for (j = 0; j < 4; ++j) pthread_join(threads[j], NULL);
    for (j = 0; j < 4; ++j) {
        printf("%%d", jobs[j].status);
        for (i = 0; i < N_STEPS * 8; ++i) printf(",%%.17g", jobs[j].X[i]);
        printf("\n");
    }
    return 0;
}
"""


def test_two_models_in_one_program_run_independently_in_threads(libraries, plant_model, design_model,
                                                                 mission_inputs, tmp_path):
    U = mission_inputs[list(plant_model.input_names)].to_numpy()[:360]
    source = tmp_path / "two_models.c"
    source.write_text(THREADED_PROGRAM % {"n_steps": len(U), "inputs": ", ".join(f"{v:.17g}" for v in U.ravel())})
    program = tmp_path / "two_models"
    nonlinear, linear = libraries["nonlinear"][0], libraries["linear"][0]
    subprocess.run([*find_compiler(), *STRICT_FLAGS, "-pthread", f"-I{nonlinear.directory}",
                    f"-I{linear.directory}", "-o", str(program), str(source), str(nonlinear.abi_source),
                    str(linear.abi_source), *_library_objects(nonlinear), *_library_objects(linear), "-lm"],
                   check=True)
    rows = subprocess.run([str(program)], capture_output=True, text=True, check=True).stdout.split()
    x0 = np.full(8, 20.0)
    for job, row in enumerate(rows):
        status, *values = row.split(",")
        model = design_model if job % 2 else plant_model
        expected = np.asarray(model.discretise(10.0).simulator(len(U))(x0, U.T)).T
        assert status == "0"
        assert np.max(np.abs(np.array(values, dtype=float).reshape(len(U), 8) - expected)) < 1e-9


def test_two_libraries_loaded_at_once_interleave_correctly(libraries, plant_model, design_model):
    compiled = {key: value[1] for key, value in libraries.items()}
    steps = {"nonlinear": plant_model.discretise(10.0).step, "linear": design_model.discretise(10.0).step}
    states = {key: np.full(8, 20.0) for key in compiled}
    u = plant_model.input_vector(7.0, 7.0, 7.0, 1.0, 20.0, 20.0)
    for _ in range(50):
        for key in compiled:
            expected = np.asarray(steps[key](states[key], u)).ravel()
            states[key] = compiled[key].step(states[key], u)
            assert np.max(np.abs(states[key] - expected)) < 1e-9
    assert abs(states["nonlinear"] - states["linear"]).max() > 0.1  # two different models


def test_generated_and_abi_code_has_no_mutable_static_data_or_heap(libraries):
    for generated, _ in libraries.values():
        for path in (*generated.sources, *generated.headers):
            text = path.read_text()
            assert forbidden_constructs(text) == [], path.name
            code = re.sub(r"/\*.*?\*/", "", text, flags=re.DOTALL)
            for line in code.splitlines():
                if re.match(r"\s*static\b", line):  # constant tables and functions only
                    assert re.match(r"\s*static\s+const\b", line) or "(" in line, (path.name, line)
            assert not re.search(r"\b(malloc|calloc|realloc|free)\s*\(", code), path.name


def test_forbidden_constructs_are_found():
    source = "static const int table[2] = {1, 2};\nstatic double w[4];\nstatic int calls = 0;\n" \
             "static int f(int a) { return a; }\nvoid g(void) { double* p = malloc(8); free(p); }\n"
    assert forbidden_constructs(source) == ["static double w[4];", "static int calls = 0;",
                                            "void g(void) { double* p = malloc(8); free(p); }"]


@pytest.fixture
def no_compiler(monkeypatch):
    """Hide every C compiler from the lookup."""
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setattr(ccompile.shutil, "which", lambda *args, **kwargs: None)


def test_without_compiler_the_error_says_what_is_missing_and_what_still_works(no_compiler, plant_model,
                                                                            tmp_path):
    generated = generate_c(plant_model, tmp_path, prefix="gt")
    with pytest.raises(CompilerNotFoundError) as error:
        compile_library(generated)
    message = str(error.value)
    assert "no C compiler found" in message and "cc" in message and "gcc" in message
    assert "Python/CasADi path" in message and "apt-get install gcc" in message


def test_cli_without_compiler_writes_sources_and_exits_2(no_compiler, tmp_path, capsys):
    assert main(["codegen", "--out", str(tmp_path)]) == 2
    captured = capsys.readouterr()
    assert "no C compiler found" in captured.err and "Traceback" not in captured.err
    assert "wrote gt.h" in captured.out
    assert (tmp_path / "gt.c").is_file() and (tmp_path / "gt_casadi_step.c").is_file()
    assert not list(tmp_path.glob("libgt.*"))


def test_cli_codegen_writes_sources_library_and_example(libraries, tmp_path, capsys):
    assert main(["codegen", "--out", str(tmp_path), "--dt", "10"]) == 0
    out = capsys.readouterr().out
    for name in ("gt.h", "gt.c", "gt_casadi.h", "gt_casadi_step.c", "gt_casadi_jac_p_row.c",
                 "example_mission.c", "Makefile", "ABI.md"):
        assert (tmp_path / name).is_file() and f"wrote {name}" in out
    header = (tmp_path / "gt.h").read_text()
    # the EKF of the model and the linear filter of its design model come along
    for entry in ("gt_kalman_update", "gt_predict", "gt_ekf_update", "gt_ekf_predict"):
        assert f"int {entry}(" in header and f"extra entry point {entry}" in out
    library = next(tmp_path.glob("libgt.*"))
    loaded = CompiledModel(library, libraries["nonlinear"][0])
    assert loaded.n_states == 8 and loaded.dt_s == 10.0


def test_ctrl_c_during_codegen_leaves_no_partial_files(tmp_path, monkeypatch, capsys):
    import genthermal.commands.codegen as codegen_command

    def interrupted(generated, out_dir):
        assert (Path(out_dir) / "gt_casadi_step.c").is_file()  # the sources are written, the library is not
        raise KeyboardInterrupt

    monkeypatch.setattr(codegen_command, "compile_library", interrupted)
    out = tmp_path / "code"
    assert main(["codegen", "--out", str(out), "--no-kalman"]) == 130
    assert list(tmp_path.iterdir()) == []
    out.mkdir()
    (out / "gt.h").write_text("the previous header")
    assert main(["codegen", "--out", str(out), "--no-kalman", "--force"]) == 130
    assert [p.name for p in tmp_path.iterdir()] == ["code"]
    assert {p.name: p.read_text() for p in out.iterdir()} == {"gt.h": "the previous header"}
    assert "interrupted" in capsys.readouterr().err


def test_cli_rejects_bad_step(tmp_path, capsys):
    assert main(["codegen", "--out", str(tmp_path), "--dt", "-1"]) == 2
    assert "--dt" in capsys.readouterr().err
    assert main(["codegen", "--out", str(tmp_path), "--predict-steps", "0"]) == 2
    assert "--predict-steps" in capsys.readouterr().err


def test_compilation_errors_quote_the_compiler(tmp_path):
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler")
    broken = tmp_path / "broken.c"
    broken.write_text("int f(void) { return undeclared_name; }\n")
    with pytest.raises(ccompile.CompilationError, match="undeclared_name"):
        compile_objects([broken])
