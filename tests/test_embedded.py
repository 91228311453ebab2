"""The generated C on the emulated Cortex-M4F: double precision equals the host to rounding (1e-9 K),
single precision stays within 0.01 K over 4 h, no heap, bounded stack, and clear errors."""

import numpy as np
import pytest

from genthermal.design import linear_design_model
from genthermal.embedded import toolchain
from genthermal.embedded.mission import (PrecisionError, build_mission_program, check_accuracy, run_mission,
                                         winding_state)
from genthermal.errors import InputError
from genthermal.estimation.kalman import KalmanFilter
from genthermal.mission import load_mission
from genthermal.simulate import simulate


@pytest.fixture(scope="module")
def cross_toolchain():
    try:
        toolchain.check_toolchain()
    except toolchain.TargetToolchainError as exc:
        pytest.skip(f"Cortex-M toolchain not installed: {exc}")


@pytest.fixture(scope="module")
def mission_inputs():
    """The thesis Fig 7.7 mission, 4 h at 10 s."""
    return load_mission("thesis_fig_7_7").to_inputs(10.0)


@pytest.fixture(scope="module")
def runs(cross_toolchain, plant_model, mission_inputs, tmp_path_factory):
    """The mission program of the nonlinear model in both precisions, built and run on QEMU."""
    root = tmp_path_factory.mktemp("cortex_m4")
    programs = {p: build_mission_program(plant_model, mission_inputs, root, p) for p in ("double", "single")}
    return {p: (program, run_mission(program)) for p, program in programs.items()}


def _host_states(model, inputs):
    reference = simulate(model, inputs)
    return reference[[f"T_{name}" for name in model.state_names]].to_numpy()[1:]


def test_double_precision_on_the_target_equals_the_host_simulation(runs, plant_model, mission_inputs):
    states = runs["double"][1].states
    host = _host_states(plant_model, mission_inputs)
    assert states.shape == host.shape == (1440, 8)
    assert np.max(np.abs(states - host)) < 1e-9
    assert host.max() > 60.0  # the mission heats the machine


def test_filter_update_and_prediction_on_the_target_equal_the_host(runs, plant_model, mission_inputs):
    run = runs["double"][1]
    x, u = run.states[-1], mission_inputs[list(plant_model.input_names)].to_numpy()[-2]
    winding = winding_state(plant_model)
    y = np.full(2, x[winding] + 0.5)  # the measurement mission_target.c feeds the filter
    filtered, _ = KalmanFilter(linear_design_model(plant_model)).update_function()(x, u, y)
    step, state = plant_model.discretise(10.0).step, np.asarray(filtered).ravel()
    peak = state[winding]
    for _ in range(360):
        state = np.asarray(step(state, u)).ravel()
        peak = max(peak, state[winding])
    assert abs(run.predicted_peak_C - peak) < 1e-9


def test_single_precision_error_over_four_hours_is_below_a_hundredth_of_a_kelvin(runs, plant_model, mission_inputs):
    host = _host_states(plant_model, mission_inputs)
    error = check_accuracy(runs["single"][1], host, "single", 0.01)
    assert error > 1e-6  # really single precision
    with pytest.raises(PrecisionError, match=r"precision = 'single'.*more than the tolerance 1e-06 K"):
        check_accuracy(runs["single"][1], host, "single", 1e-6)


def test_no_heap_and_a_small_bounded_stack(runs):
    for program, run in runs.values():
        assert toolchain.heap_symbols(program.build) == []
        frames = toolchain.stack_usage(program.build)  # raises on an unbounded frame
        assert frames["main"] > 0 and max(frames.values()) < 1024
        assert 0 < run.stack_bytes < 2048
    assert runs["single"][1].instructions["step"] < runs["double"][1].instructions["step"] / 10  # FPU vs soft double


def test_the_heap_check_finds_malloc(cross_toolchain, tmp_path):
    source = tmp_path / "uses_heap.c"
    source.write_text("#include <stdlib.h>\n#include <stddef.h>\nstatic char heap[256];\nstatic size_t used;\n"
                      "void* _sbrk(ptrdiff_t n) { void* p = heap + used; used += (size_t)n; return p; }\n"
                      "int main(void) { double* p = malloc(8 * sizeof *p); int ok = p != NULL; free(p); return !ok; }\n")
    built = toolchain.build([source], [], tmp_path / "out", "uses_heap", "double")
    assert {"malloc", "free"} <= set(toolchain.heap_symbols(built))
    assert toolchain.run(built.elf, timeout_s=60) == ""


def test_bad_precision_and_missing_toolchain_are_named(plant_model, mission_inputs, tmp_path, monkeypatch):
    with pytest.raises(InputError, match="precision"):
        build_mission_program(plant_model, mission_inputs, tmp_path, precision="half")
    monkeypatch.setattr(toolchain.shutil, "which", lambda name: None)
    with pytest.raises(toolchain.TargetToolchainError, match="apt-get install gcc-arm-none-eabi"):
        build_mission_program(plant_model, mission_inputs, tmp_path, precision="double")
    assert list(tmp_path.iterdir()) == []


def test_cli_names_a_bad_precision(tmp_path, capsys):
    from genthermal.cli import main

    assert main(["cortex-m4", "--out", str(tmp_path / "build"), "--precision", "half"]) == 2
    err = capsys.readouterr().err
    assert "--precision" in err and "'half'" in err and "Traceback" not in err
    assert not (tmp_path / "build").exists()
