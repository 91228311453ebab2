"""The FMU export checked by FMPy: validation, simulation against genthermal, directional derivatives.

Run ``python benchmarks/bench_fmu.py --json bench_fmu.json``; prints one JSON line per model
variant. For the FMU of the nonlinear and of the linear design model (``genthermal.fmu``):

* ``fmpy_validation`` -- the problems FMPy's ``validate_fmu`` reports (empty: none);
* ``max_error_K_<interface>`` -- largest difference of the sensor outputs over the thesis Fig 7.7
  mission (4 h, outputs every 10 s) between FMPy's simulation (model exchange: CVode at relative
  tolerance 1e-10; co-simulation: the FMU's own integrator) and genthermal's: the exact zero-order
  hold for the linear model, the ETD2RK step at 0.5 s (converged to ~1e-8 K) for the nonlinear one;
* ``max_error_K_vs_default_step`` -- the same against genthermal's default 10 s ETD2RK step;
* ``fmpy_seconds_<interface>`` -- wall time of the FMPy simulation;
* ``export_seconds`` -- generate, compile and zip (compiled objects cached).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import fmpy
import numpy as np
from fmpy.validation import validate_fmu

from genthermal.design import linear_design_model
from genthermal.fmu import export_fmu, piecewise_constant_input
from genthermal.machines import build_model
from genthermal.mission import load_mission
from genthermal.simulate import simulate

MISSION = "thesis_fig_7_7"


def measure(variant: str, model, folder: Path) -> dict:
    start = time.perf_counter()
    path = export_fmu(model, folder / f"{variant}.fmu").path
    result = {"benchmark": "fmu", "model": variant, "export_seconds": time.perf_counter() - start,
              "fmpy_validation": validate_fmu(str(path))}
    inputs = load_mission(MISSION).to_inputs(10.0)
    default = simulate(model, inputs)
    reference = default if variant == "linear" else simulate(model, load_mission(MISSION).to_inputs(0.5)).iloc[::20]
    x0 = {f"x_{n}": float(inputs["T_ambient"].iloc[0]) for n in model.state_names}
    grid = inputs["time_s"].to_numpy()
    for kind in ("ModelExchange", "CoSimulation"):
        start = time.perf_counter()
        flown = fmpy.simulate_fmu(str(path), fmi_type=kind, stop_time=grid[-1], output_interval=10.0,
                                  input=piecewise_constant_input(inputs, model.input_names), start_values=x0,
                                  relative_tolerance=1e-10, output=list(model.output_names))
        result[f"fmpy_seconds_{kind}"] = time.perf_counter() - start
        errors = [np.abs(np.interp(grid, flown["time"], flown[o]) - reference[o].to_numpy()) for o in model.output_names]
        result[f"max_error_K_{kind}"] = float(np.max(errors))
        default_errors = [np.abs(np.interp(grid, flown["time"], flown[o]) - default[o].to_numpy())
                          for o in model.output_names]
        result[f"max_error_K_vs_default_step_{kind}"] = float(np.max(default_errors))
    result["targets"] = {"fmpy_validation_clean": not result["fmpy_validation"],
                         "fmu_equals_genthermal_within_1e-6_K": max(result["max_error_K_ModelExchange"],
                                                                    result["max_error_K_CoSimulation"]) <= 1e-6}
    return result


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="file to write the JSON lines to")
    args = parser.parse_args(argv)
    plant = build_model()
    lines = []
    with tempfile.TemporaryDirectory(prefix="bench-fmu-") as folder:
        for variant, model in (("nonlinear", plant), ("linear", linear_design_model(plant))):
            lines.append(json.dumps(measure(variant, model, Path(folder))))
            print(lines[-1], flush=True)
    if args.json:
        Path(args.json).write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
