"""FMI 2.0 FMU of a ThermalModel for model exchange and co-simulation, from the generated C.

:func:`export_fmu` writes one ``.fmu`` holding ``modelDescription.xml``
(:mod:`genthermal.fmu.model_description`), the generated C library behind the FMI 2.0 functions
of ``fmi2_wrapper.c`` compiled for this platform, and the sources to build it elsewhere.
Co-simulation integrates with adaptive Dormand-Prince 5(4) (:data:`ATOL_K`, :data:`RTOL`);
directional derivatives are exact. The file is moved into place only when complete. Guide:
``docs/guide/embedded.md``.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
import uuid
import zipfile
from importlib import resources
from pathlib import Path

import casadi as ca
import numpy as np

from .. import __version__
from ..ccompile import COMPILE_FLAGS, CompilationError, compile_objects, find_compiler
from ..codegen import generate_c
from ..errors import InputError
from ..model import ThermalModel
from .model_description import STATE_START_C, FmuError, description_xml, variables

__all__ = ["export_fmu", "piecewise_constant_input", "FmuError", "FmuExport", "ATOL_K", "RTOL"]

#: Co-simulation error tolerances per internal step: absolute (K) and relative.
ATOL_K = 1e-10
RTOL = 1e-12
#: C symbol prefix of the generated library inside the FMU (hidden: only fmi2* symbols are exported).
PREFIX = "gtfmu"
_FLAGS = (*COMPILE_FLAGS, "-fvisibility=hidden")
_WRAPPER_FLAGS = (*_FLAGS, "-Wall", "-Wextra", "-Werror", "-Wno-unused-parameter")


class FmuExport:
    """What :func:`export_fmu` wrote.

    Attributes
    ----------
    path : pathlib.Path
        The ``.fmu`` file.
    model_identifier : str
        Name of the binary and of the model in ``modelDescription.xml``.
    guid : str
    platform : str
        FMI platform folder of the binary (``linux64``, ``darwin64``).
    n_variables : int
    """

    def __init__(self, path, model_identifier, guid, platform, n_variables):
        self.path, self.model_identifier, self.guid = Path(path), model_identifier, guid
        self.platform, self.n_variables = platform, n_variables

    def __repr__(self) -> str:
        return f"FmuExport({self.path.name}: {self.model_identifier}, {self.n_variables} variables, {self.platform})"


def fmi_platform() -> str:
    """The FMI 2.0 platform folder of this machine's binaries.

    Raises
    ------
    FmuError
        On a platform the export does not build for (only 64-bit Linux and macOS).
    """
    if sys.maxsize <= 2**32 or not sys.platform.startswith(("linux", "darwin")):
        raise FmuError(f"FMU binaries are built for 64-bit Linux and macOS only, not {sys.platform}")
    return "darwin64" if sys.platform == "darwin" else "linux64"


def model_identifier(model: ThermalModel) -> str:
    """C identifier of the model: ``genco_rf201a (nonlinear)`` -> ``genco_rf201a_nonlinear``."""
    identifier = re.sub(r"[^A-Za-z0-9_]+", "_", model.name).strip("_")
    return identifier if re.match(r"^[A-Za-z_]", identifier) else f"m_{identifier}"


def output_jacobians(model: ThermalModel) -> dict:
    """CasADi functions ``output_jac_x``, ``output_jac_u``: ∂y/∂x and ∂y/∂u at (x, u, p)."""
    outputs = model.functions["outputs"]
    x, u, p = outputs.sx_in()
    y = outputs(x, u, p)
    return {f"output_jac_{name}": ca.Function(f"output_jac_{name}", [x, u, p], [ca.densify(ca.jacobian(y, wrt))],
                                              ["x", "u", "p"], [f"dy_d{name}"])
            for name, wrt in (("x", x), ("u", u))}


def export_fmu(model: ThermalModel, out_path) -> FmuExport:
    """Write an FMI 2.0 FMU (model exchange and co-simulation) of ``model``.

    Parameters
    ----------
    model : ThermalModel
        Nonlinear simulation model or linear design model (with any effects).
    out_path : str or pathlib.Path
        The ``.fmu`` file to write (its directory is created).

    Returns
    -------
    FmuExport

    Raises
    ------
    InputError
        ``out_path`` does not end in ``.fmu``.
    FmuError
        Something of the model FMI cannot express (a unit, clashing names) or an unsupported platform.
    genthermal.errors.CompilerNotFoundError, genthermal.ccompile.CompilationError
        No C compiler, or it failed. In every error case no file is left at ``out_path``.
    """
    out_path = Path(out_path)
    if out_path.suffix != ".fmu":
        raise InputError("out", str(out_path), "an FMU file name must end in .fmu")
    platform = fmi_platform()
    every = variables(model)  # refuses what FMI cannot express before anything is built
    identifier = model_identifier(model)
    with tempfile.TemporaryDirectory(prefix="genthermal-fmu-") as scratch:
        sources_dir = Path(scratch) / "sources"
        generated = generate_c(model, sources_dir, prefix=PREFIX, extra_functions=output_jacobians(model))
        guid = "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, f"genthermal:{generated.source_hash}")) + "}"
        wrapper = sources_dir / "fmi2_wrapper.c"
        wrapper.write_text(_wrapper_source(model, guid))
        binary = _build_binary(generated, wrapper, Path(scratch) / f"{identifier}.so")
        files = sorted(p.name for p in sources_dir.iterdir())
        description = description_xml(model, identifier, guid, files, f"genthermal {__version__}")
        out_path.parent.mkdir(parents=True, exist_ok=True)
        partial = out_path.with_name(f".{out_path.name}.{uuid.uuid4().hex}.tmp")
        try:
            with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as archive:
                archive.writestr("modelDescription.xml", description)
                archive.write(binary, f"binaries/{platform}/{identifier}.so")
                for name in files:
                    archive.write(sources_dir / name, f"sources/{name}")
            os.replace(partial, out_path)
        finally:
            partial.unlink(missing_ok=True)
    return FmuExport(out_path, identifier, guid, platform, len(every))


def piecewise_constant_input(inputs, names) -> np.ndarray:
    """A mission's inputs as an FMPy input signal that holds each sample (zero-order hold).

    FMPy interpolates input signals linearly; a time repeated with the old and the new value marks
    a step change (an event for model exchange), so the FMU sees the inputs genthermal holds.

    Parameters
    ----------
    inputs : pandas.DataFrame
        ``time_s`` and the input columns, e.g. ``Mission.to_inputs(dt)``.
    names : sequence of str
        The FMU's input names (the model's ``input_names``).

    Returns
    -------
    numpy.ndarray
        Structured array with ``time`` and one field per input.
    """
    t, U = inputs["time_s"].to_numpy(dtype=float), inputs[list(names)].to_numpy(dtype=float)
    rows = []
    for k in range(len(t)):
        if k and np.any(U[k] != U[k - 1]):
            rows.append((t[k], *U[k - 1]))
        rows.append((t[k], *U[k]))
    return np.array(rows, dtype=[("time", float)] + [(n, float) for n in names])


def _wrapper_source(model: ThermalModel, guid: str) -> str:
    template = resources.files(__package__).joinpath("fmi2_wrapper.c").read_text()
    starts = [model.spec.interface.default_input_values()[name] for name in model.input_names]
    fields = {"PREFIX": PREFIX, "PREFIX_UPPER": PREFIX.upper(), "GUID": guid, "ATOL_K": repr(ATOL_K),
              "RTOL": repr(RTOL), "STATE_START": ", ".join([repr(STATE_START_C)] * model.n_states),
              "INPUT_START": ", ".join(map(repr, starts))}
    return re.sub(r"@([A-Z_]+)@", lambda match: fields[match.group(1)], template)


def _build_binary(generated, wrapper: Path, target: Path) -> Path:
    compiler = find_compiler()
    objects = compile_objects(generated.sources, generated.headers, _FLAGS, compiler)
    objects += compile_objects([wrapper], generated.headers, _WRAPPER_FLAGS, compiler)
    command = [*compiler, "-shared", *_FLAGS, "-o", str(target), *map(str, objects), "-lm"]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise CompilationError(f"linking the FMU binary failed: {' '.join(command)}\n{result.stderr[-2000:]}")
    return target
