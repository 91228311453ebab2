"""A mission through the generated model on the emulated Cortex-M4F, in double or single precision.

:func:`build_mission_program` generates the model's C code with the filter and an n-step
prediction (:func:`genthermal.estimation.kalman.embedded_functions`), writes the mission inputs as
a constant table, and cross-compiles ``c/mission_target.c`` with only the generated functions it
calls (``step`` and the filter's ``kalman_update``). :func:`run_mission` runs it under QEMU and
reads back every state (exact IEEE bits), the instruction counts of one step, one filter update and
one prediction, the peak of that prediction and the deepest stack the run used.

The prediction is a loop of ``step`` calls that keeps the winding's peak, as an onboard manager
predicts: the generated n-step ``predict`` function holds the whole horizon in its work memory
(11 119 doubles, 87 KB, for 1 h at 10 s), more than a microcontroller's RAM.
"""

from __future__ import annotations

import dataclasses
import struct
from pathlib import Path

import numpy as np
import pandas as pd

from ..codegen import generate_c
from ..design import linear_design_model
from ..errors import InputError
from ..estimation.kalman import KalmanFilter
from ..model import ThermalModel
from . import toolchain

PRECISIONS = tuple(toolchain.PRECISION_FLAGS)
#: Generated functions the mission program calls.
CALLED_FUNCTIONS = ("step", "kalman_update")
#: What the program reports the cost of.
COSTS = ("step", "kalman_update", "predict")


@dataclasses.dataclass(frozen=True)
class MissionProgram:
    """A cross-compiled mission program (see :func:`build_mission_program`).

    Attributes
    ----------
    build : genthermal.embedded.toolchain.TargetBuild
    n_steps : int
        Steps of the mission it runs.
    predict_steps : int
        Horizon of the prediction it times, steps.
    mission_data_bytes : int
        Flash taken by the mission's input table (not part of the model).
    """

    build: toolchain.TargetBuild
    n_steps: int
    predict_steps: int
    mission_data_bytes: int


@dataclasses.dataclass(frozen=True)
class MissionRun:
    """What the emulated program printed.

    Attributes
    ----------
    states : numpy.ndarray
        (n_steps, n_states) state after every step, °C (float64; exact copies of the target's values).
    instructions : dict
        ``step``, ``kalman_update``: instructions of one call; ``predict``: of the whole prediction.
    predicted_peak_C : float
        Winding peak of the timed prediction, °C.
    stack_bytes : int
        Deepest stack the run used, bytes (start-up code included).
    """

    states: np.ndarray
    instructions: dict
    predicted_peak_C: float
    stack_bytes: int


def build_mission_program(model: ThermalModel, inputs: pd.DataFrame, out_dir, precision: str = "double",
                          dt_s: float = 10.0, predict_steps: int = 360) -> MissionProgram:
    """Generate and cross-compile the mission program.

    Parameters
    ----------
    model : ThermalModel
        Model of the step; the filter and prediction run on its linear design model.
    inputs : pandas.DataFrame
        The mission, ``Mission.to_inputs(dt_s)``: a row per step, columns the model inputs.
    out_dir : path-like
        Build directory (generated sources, objects, ELF, link map).
    precision : {"double", "single"}
        Arithmetic of the generated functions.
    dt_s : float
        Step, s.
    predict_steps : int
        Horizon of the timed prediction (default 360 = 1 h at 10 s).

    Raises
    ------
    InputError
        Unknown precision or inputs without the model's columns.
    genthermal.embedded.toolchain.TargetToolchainError
        No cross toolchain.
    """
    if precision not in PRECISIONS:
        raise InputError("precision", precision, f"must be one of {', '.join(PRECISIONS)}")
    missing = [name for name in model.input_names if name not in inputs]
    if missing:
        raise InputError("inputs", missing, "missing input columns of the model")
    toolchain.check_toolchain()
    out_dir = Path(out_dir)
    design = model if model.is_affine else linear_design_model(model)
    if not (int(predict_steps) == predict_steps and predict_steps >= 1):
        raise InputError("predict_steps", predict_steps, "must be a whole number of steps >= 1")
    generated = generate_c(model, out_dir / "generated", dt_s=dt_s,
                           extra_functions={"kalman_update": KalmanFilter(design, dt_s).update_function()})
    U = inputs[list(model.input_names)].to_numpy(dtype=float)
    data = out_dir / "mission_data.c"
    data.write_text("/* mission inputs, one row of A and degC per step (generated) */\n"
                    f"const int mission_n_rows = {len(U)};\nconst double mission_inputs[] = {{\n"
                    + ",\n".join(", ".join(repr(float(v)) for v in row) for row in U) + "\n};\n")
    sources = [generated.directory / f"{generated.prefix}_casadi_{name}.c" for name in CALLED_FUNCTIONS]
    built = toolchain.build([toolchain.support_file("mission_target.c"), data], [generated.directory],
                            out_dir / precision, "mission", precision, sources,
                            defines=[f"GT_PREDICT_STEPS={int(predict_steps)}",
                                     f"GT_WINDING_STATE={winding_state(model)}"])
    return MissionProgram(built, len(U) - 1, int(predict_steps), 8 * U.size)


class PrecisionError(InputError):
    """The target's arithmetic misses the accuracy asked for."""


def check_accuracy(run: MissionRun, host_states: np.ndarray, precision: str, tolerance_K: float) -> float:
    """Largest state difference between the target and the host (K); raise if above ``tolerance_K``.

    Raises
    ------
    PrecisionError
        Naming the precision, the difference reached and the tolerance.
    """
    error = float(np.max(np.abs(run.states - host_states)))
    if not error <= tolerance_K:
        raise PrecisionError("precision", precision, f"the target's states differ from the host simulation by "
                             f"{error:.3g} K, more than the tolerance {tolerance_K:g} K; use double precision "
                             "or accept a larger tolerance")
    return error


def winding_state(model: ThermalModel) -> int:
    """Index of the state the winding sensor measures (the sensor the generator role protects)."""
    return model.state_names.index(model.spec.sensors[model.spec.interface.generator.limited_sensor])


def run_mission(program: MissionProgram, timeout_s: float = 600.0) -> MissionRun:
    """Run the mission program under QEMU and decode what it printed."""
    output = toolchain.run(program.build.elf, timeout_s)
    code = "d" if program.build.precision == "double" else "f"
    width = struct.calcsize(code)
    states, costs = [], {}
    for line in output.splitlines():
        kind, *fields = line.split()
        if kind == "x":
            states.append([struct.unpack(f">{code}", bytes.fromhex(f))[0] for f in fields])
            if any(len(f) != 2 * width for f in fields):
                raise toolchain.TargetRunError(f"unexpected value width in {line!r}")
        elif kind == "cost":
            costs[fields[0]] = int(fields[1])
        elif kind == "peak":
            peak = struct.unpack(f">{code}", bytes.fromhex(fields[0]))[0]
    if len(states) != program.n_steps:
        raise toolchain.TargetRunError(f"the target printed {len(states)} states, expected {program.n_steps}")
    counts = {name: toolchain.instructions(costs[name]) for name in COSTS}
    return MissionRun(np.array(states), counts, peak, costs["stack"])
