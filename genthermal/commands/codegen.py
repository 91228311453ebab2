"""``genthermal codegen --out DIR [--model NAME|FILE] [--dt 10]``: C code of the model behind a
stable ABI, an example program and its Makefile, and ``libgt.so`` compiled from them.

Reference: docs/guide/embedded.md and docs/guide/cli.md.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import InputError
from ._common import add_json_argument, add_model_arguments, add_out_argument, model_from_args, positive_float

#: Longest prediction horizon compiled into C, steps (the generated code grows with it; 24 h at 10 s).
MAX_PREDICT_STEPS = 8640
#: Files of ``codegen/`` copied next to the generated sources so that ``make -C DIR`` works.
COMPANION_FILES = ("example_mission.c", "Makefile", "ABI.md")


def register(subparsers) -> None:
    """Add the ``codegen`` sub-command."""
    parser = subparsers.add_parser(
        "codegen", help="generate C code of the model and compile it",
        description="Write C sources of the model's discrete step, right-hand side, Jacobians and "
        "outputs behind a stable ABI (see ABI.md), an example program and its Makefile, and compile "
        "a shared library with the system C compiler. Without a C compiler the sources are still written "
        "and the command exits with code 2, saying why nothing was compiled.")
    add_out_argument(parser, "folder", "the C sources, gt.h, ABI.md, the example program, its Makefile and the "
                     "compiled libgt.so", required=True)
    parser.add_argument("--dt", default="10", help="step of gt_step and gt_simulate in s (default 10)")
    parser.add_argument("--no-kalman", dest="kalman", action="store_false",
                        help="leave out the filters: the extended Kalman filter on the model (gt_ekf_update, "
                        "gt_ekf_predict) and the thesis Kalman filter on its linear design model "
                        "(gt_kalman_update, gt_predict), included by default")
    parser.add_argument("--predict-steps", default="180",
                        help="horizon of <prefix>_predict and <prefix>_ekf_predict in steps (default 180: 30 min "
                        "at 10 s)")
    add_model_arguments(parser)
    add_json_argument(parser, "what was generated (model, step, method, entry points, files, library)")
    parser.set_defaults(func=run)


def run(args) -> int:
    """Generate, copy the companion files, compile; print what was written."""
    import shutil

    from ..ccompile import CompilerNotFoundError
    from ..codegen import generate_c
    from ..design import linear_design_model
    from ..estimation.ekf import embedded_functions as ekf_functions
    from ..estimation.kalman import embedded_functions
    from ..outputs import replacing_folder
    from ..resources import TEMPLATE_DIR, shipped_file

    dt = positive_float("--dt", args.dt)
    model = model_from_args(args)
    out = Path(args.out)
    extra = None
    if args.kalman:
        steps = positive_float("--predict-steps", args.predict_steps)
        if steps > MAX_PREDICT_STEPS:
            raise InputError("--predict-steps", args.predict_steps, f"at most {MAX_PREDICT_STEPS} steps (the "
                             "generated code grows with the horizon); predict further by calling it again")
        design = model if model.is_affine else linear_design_model(model)
        extra = {**embedded_functions(design, dt_s=dt, predict_steps=steps),
                 **ekf_functions(model, dt_s=dt, predict_steps=steps)}
    missing_compiler = None
    with replacing_folder(out, stale_patterns=("gt_casadi_*.c",)) as build:
        generated = generate_c(model, build, dt_s=dt, extra_functions=extra)
        companions = [Path(shutil.copyfile(shipped_file(TEMPLATE_DIR / name), build / name))
                      for name in COMPANION_FILES]
        try:
            library = compile_library(generated, build)
        except CompilerNotFoundError as error:  # the sources are useful without the library
            missing_compiler = error
    step = "exact zero-order hold" if generated.exact else "exponential integrator (ETD2RK)"
    print(f"{model.name}: C code with dt = {dt:g} s ({step}) in {out}")
    for signature in generated.extra_functions:
        print(f"  extra entry point gt_{signature.name}")
    for path in (*generated.headers, *generated.sources, *companions):
        print(f"  wrote {path.name}")
    if missing_compiler is not None:
        raise missing_compiler
    print(f"  wrote {library.name} (callers provide {generated.work_size} double(s) of work memory)")
    print(f"build the example program with: make -C {out}")
    if args.json:
        from ..outputs import report_json

        report_json(args.json, {"model": model.name, "dt_s": dt, "exact_zero_order_hold": bool(generated.exact),
                                "entry_points": [f"gt_{s.name}" for s in generated.extra_functions],
                                "files": [p.name for p in (*generated.headers, *generated.sources, *companions)],
                                "library": str(out / library.name), "work_doubles": int(generated.work_size)})
    return 0


def compile_library(generated, build):
    """:func:`genthermal.ccompile.compile_library`, imported only when a build runs (a module-level name,
    so that a test can replace it)."""
    from ..ccompile import compile_library as compile_sources

    return compile_sources(generated, build)
