"""``genthermal cortex-m4 --out DIR``: the generated C cross-compiled for a bare-metal Cortex-M4F,
run under QEMU (``mps2-an386``) and compared state by state with the host simulation; with
``--flight`` also the onboard load manager in C against its Python reference.

Reference: docs/guide/cortex_m4.md and docs/guide/cli.md.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import InputError
from ._common import add_choice_argument, add_json_argument, add_model_arguments, add_out_argument, model_from_args
from ._common import positive_float
from ._vocabulary import PRECISIONS


def register(subparsers) -> None:
    """Add the ``cortex-m4`` sub-command."""
    parser = subparsers.add_parser(
        "cortex-m4", help="cross-compile the generated C for a Cortex-M4F and run it under QEMU",
        description="Build the model step, filter update and 1 h prediction for a bare-metal Cortex-M4F "
        "(gcc-arm-none-eabi, newlib, hard float), run a mission on QEMU's mps2-an386 board with "
        "semihosting, compare it with the host simulation and report sizes and instruction counts.")
    add_out_argument(parser, "folder", "the generated sources, objects, ELF files and link maps", required=True)
    add_model_arguments(parser, what="the model run on the target")
    parser.add_argument("--mission", default="thesis_fig_7_7", help="mission scenario (default thesis_fig_7_7)")
    add_choice_argument(parser, "--precision", PRECISIONS, default="double",
                        help="arithmetic of the target build (default double)")
    parser.add_argument("--tolerance", default="0.01",
                        help="largest state difference from the host simulation accepted, K (default 0.01)")
    parser.add_argument("--flight", help="also fly this two-generator fault scenario (e.g. blockage_large) "
                        "with the onboard manager in C")
    add_json_argument(parser, "the sizes, instruction counts and differences from the host (and the flight's)")
    parser.set_defaults(func=run)


def run(args) -> int:
    """Build, run, compare, report; the build folder appears whole or not at all."""
    from ..mission import load_mission
    from ..outputs import replacing_folder, report_json

    if args.precision not in PRECISIONS:
        raise InputError("--precision", args.precision, f"must be one of {', '.join(PRECISIONS)}")
    tolerance = positive_float("--tolerance", args.tolerance)
    model, mission = model_from_args(args), load_mission(args.mission)
    with replacing_folder(args.out) as build:
        report = _build_and_run(args, model, mission, tolerance, build)
    if args.json:
        report_json(args.json, report)
    return 1 if report.get("flight", {}).get("decisions_equal") is False else 0


def _build_and_run(args, model, mission, tolerance: float, build: Path) -> dict:
    """The body of :func:`run`, building in ``build`` (moved to ``--out`` at the end); returns the
    figures for ``--json``."""
    import numpy as np

    from ..embedded import toolchain
    from ..embedded.manager import blockage_flight, build_flight_program, fly_on_target, fly_reference
    from ..embedded.mission import build_mission_program, check_accuracy, run_mission
    from ..mission import load_mission
    from ..schedule.power_system import PowerSystem
    from ..simulate import simulate

    def shown(path) -> Path:  # where a file of the build will be once it is moved into place
        return Path(args.out) / Path(path).resolve().relative_to(build.resolve())

    inputs = mission.to_inputs(10.0)
    program = build_mission_program(model, inputs, str(build), args.precision)
    result = run_mission(program)
    host = simulate(model, inputs)[[f"T_{n}" for n in model.state_names]].to_numpy()[1:]
    sizes = toolchain.section_sizes(program.build.elf)
    flash = sizes["isr_vector"] + sizes["text"] + sizes["rodata"] - program.mission_data_bytes
    stack, _ = toolchain.worst_case_stack(program.build)
    print(f"{model.name} on {toolchain.MACHINE} (Cortex-M4F, {args.precision} precision): {mission.name}, "
          f"{program.n_steps} steps")
    error = check_accuracy(result, host, args.precision, tolerance)
    print(f"  largest state difference from the host simulation: {error:.3g} K (tolerance {tolerance:g} K)")
    print(f"  flash {flash} B (without the mission's {program.mission_data_bytes} B input table), "
          f"RAM {sizes.get('data', 0) + sizes['bss']} B, stack {result.stack_bytes} B used "
          f"({stack} B static bound without library routines), heap functions linked: {toolchain.heap_symbols(program.build) or 'none'}")
    counts = result.instructions
    print(f"  instructions: step {counts['step']:.0f}, filter update {counts['kalman_update']:.0f}, "
          f"1 h prediction {counts['predict']:.0f} (QEMU -icount; instructions, not cycles)")
    print(f"  wrote {shown(program.build.elf)} and {shown(program.build.link_map)}")
    report = {"model": model.name, "machine": toolchain.MACHINE, "precision": args.precision, "mission": mission.name,
              "steps": int(program.n_steps), "max_state_difference_K": float(error), "tolerance_K": tolerance,
              "flash_bytes": int(flash), "ram_bytes": int(sizes.get("data", 0) + sizes["bss"]),
              "stack_bytes_used": int(result.stack_bytes), "stack_bytes_static_bound": int(stack),
              "instructions": {key: float(value) for key, value in counts.items()},
              "elf": str(shown(program.build.elf))}
    if args.flight:
        system = PowerSystem.from_mission(load_mission(args.flight))
        design, settings, flight = blockage_flight(system)
        built = build_flight_program(design, settings, flight, str(build / "flight"))
        target, reference = fly_on_target(built), fly_reference(design, settings, flight)
        same = np.array_equal(target.flags, reference.flags)
        gap = np.max(np.abs(target.plant_winding_C - reference.plant_winding_C))
        print(f"{args.flight}: onboard manager in C, {len(target.flags)} samples flown; decisions "
              f"{'equal to' if same else 'DIFFERENT from'} the Python reference, temperatures within {gap:.3g} K")
        plant, switches = system.plant_switches(0)
        generator = plant.spec.interface.generator
        inputs = system.mission.to_inputs(settings.dt_s, generator)
        inputs[generator.coolant_input] = system.inlet_C(0, inputs["time_s"])
        unmanaged = simulate(plant, inputs, switches=switches)[generator.limited_sensor].max()
        peaks = ", ".join(f"{name} {peak:.2f} °C" for name, peak in zip(system.generator_names,
                                                                       target.plant_winding_C.max(axis=0)))
        print(f"  peak winding {peaks} (unmanaged {system.generator_names[0]}: {unmanaged:.1f} °C; limit "
              f"{system.limit_C:g} °C, planning limit {settings.limit_C:g} °C), "
              f"{target.flags[:, 0].sum() * settings.dt_s / 60:.0f} min of rest")
        print(f"  longest manager call {target.instructions['manager_max']:.3g} instructions, whole flight "
              f"{target.instructions['manager_total']:.3g}, stack {target.stack_bytes} B used")
        report["flight"] = {"scenario": args.flight, "samples": int(len(target.flags)), "decisions_equal": bool(same),
                            "max_temperature_difference_K": float(gap),
                            "rest_min": float(target.flags[:, 0].sum() * settings.dt_s / 60),
                            "manager_max_instructions": float(target.instructions["manager_max"])}
    return report
