"""Sizes and costs of the generated C on a Cortex-M4F (QEMU mps2-an386), per model and precision.

Run ``python benchmarks/bench_embedded.py --json bench_embedded.json``; prints one JSON line per
(model, precision) and writes them. Each line comes from one program built and run by
:mod:`genthermal.embedded.mission`: the thesis Fig 7.7 mission (4 h at 10 s) through the model's
step, one Kalman filter update (design model, steady-state gain) and a 1 h prediction (360 steps).

* ``flash_bytes`` -- ``.isr_vector + .text + .rodata`` of the linked program without the mission's
  input table (start-up code, the program, the generated functions, libgcc and newlib routines);
* ``ram_bytes`` -- ``.data + .bss`` (static data; the generated functions need no work memory);
* ``stack_static_bytes`` -- deepest call path from reset, from ``-fstack-usage`` frames and the
  call graph, plus an interrupt's FPU frame; library routines excluded (``stack_unknown``);
* ``stack_measured_bytes`` -- deepest stack the run actually used (painted stack), all included;
* ``instructions_*`` -- instructions executed under ``qemu -icount`` (not cycles: QEMU does not model
  the pipeline; a Cortex-M4 needs at least one cycle per instruction);
* ``load_percent_at_100MHz_1cpi`` -- (filter update + 1 h prediction) every 10 s on a 100 MHz core
  at one cycle per instruction: a lower bound of the load; ``max_cpi_within_1_percent`` says how many
  cycles per instruction the 1 % target allows;
* ``max_error_vs_host_K`` -- largest state difference from the host Python simulation over 4 h.

Targets (issue 13): step + filter + 1 h prediction within 64 KB flash and 8 KB RAM; the 10 s cycle
below 1 % of a 100 MHz core.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

from genthermal.design import linear_design_model
from genthermal.embedded import toolchain
from genthermal.embedded.mission import build_mission_program, run_mission
from genthermal.machines import build_model
from genthermal.mission import load_mission
from genthermal.simulate import simulate

CYCLE_S = 10.0
CLOCK_HZ = 100e6


def measure(model, variant: str, precision: str, inputs, build_dir: Path) -> dict:
    """Build, run and measure one program."""
    program = build_mission_program(model, inputs, build_dir / variant, precision)
    run = run_mission(program)
    sizes = toolchain.section_sizes(program.build.elf)
    static_stack, unknown = toolchain.worst_case_stack(program.build)
    host = simulate(model, inputs)[[f"T_{n}" for n in model.state_names]].to_numpy()[1:]
    per_cycle = run.instructions["kalman_update"] + run.instructions["predict"]
    return {
        "benchmark": "cortex_m4", "machine": toolchain.MACHINE, "model": variant, "precision": precision,
        "flash_bytes": sizes["isr_vector"] + sizes["text"] + sizes["rodata"] - program.mission_data_bytes,
        "ram_bytes": sizes.get("data", 0) + sizes["bss"],
        "stack_static_bytes": static_stack, "stack_unknown": unknown, "stack_measured_bytes": run.stack_bytes,
        "heap_symbols": toolchain.heap_symbols(program.build),
        "instructions_step": round(run.instructions["step"]),
        "instructions_kalman_update": round(run.instructions["kalman_update"]),
        "instructions_predict_1h": round(run.instructions["predict"]),
        "load_percent_at_100MHz_1cpi": 100.0 * per_cycle / (CLOCK_HZ * CYCLE_S),
        "max_cpi_within_1_percent": 0.01 * CLOCK_HZ * CYCLE_S / per_cycle,
        "max_error_vs_host_K": float(np.max(np.abs(run.states - host))),
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="file to write the JSON lines to")
    args = parser.parse_args(argv)
    plant = build_model()
    models = {"nonlinear": plant, "linear": linear_design_model(plant)}
    inputs = load_mission("thesis_fig_7_7").to_inputs(10.0)
    lines = []
    with tempfile.TemporaryDirectory(prefix="bench-embedded-") as folder:
        for variant, model in models.items():
            for precision in ("double", "single"):
                result = measure(model, variant, precision, inputs, Path(folder) / precision)
                result["targets"] = {"flash_within_64KB": result["flash_bytes"] <= 65536,
                                     "ram_within_8KB": result["ram_bytes"] + result["stack_measured_bytes"] <= 8192,
                                     "cycle_below_1_percent_at_1cpi": result["load_percent_at_100MHz_1cpi"] < 1.0}
                lines.append(json.dumps(result))
                print(lines[-1], flush=True)
    if args.json:
        Path(args.json).write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
