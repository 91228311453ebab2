"""C code of a ThermalModel: CasADi-generated arithmetic behind a small, stable, hand-written ABI.

:func:`generate_c` writes one CasADi source per function (``step``, ``rhs``, ``jac_x``, ``jac_u``,
``jac_p_row``, ``outputs``) and the ABI layer ``<prefix>.c`` / ``<prefix>.h`` from the templates in
``codegen/`` (the ABI: ``codegen/ABI.md``); :func:`model_library` generates, compiles (cached) and
loads a model in one call. Every public C symbol carries the prefix, and the code is checked for
static mutable data and heap use. Guide: ``docs/guide/embedded.md``; method notes:
``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import re
import tempfile
from pathlib import Path

import casadi as ca

from . import __version__
from .codegen_simplify import affine_with_floors, inline_floors
from .errors import GenthermalError, InputError
from .model import ThermalModel
from .resources import TEMPLATE_DIR, shipped_file

#: Version of the C interface written into ``<PREFIX>_ABI_VERSION``.
ABI_VERSION = 2
#: Continuous-model functions of (x, u, p) generated as they are (``jac_p`` is built from rows).
MODEL_FUNCTIONS = ("rhs", "jac_x", "jac_u", "outputs")
#: Names of the fixed entry points and metadata; extra functions may not take them (nor start
#: with ``cg_`` or ``casadi``, the names of the generated functions and files).
RESERVED_NAMES = ("step", "simulate", "rhs", "jac_x", "jac_u", "jac_p", "jac_p_row", "outputs", "work_size",
                  "abi_version", "model_name", "n_states", "n_inputs", "n_params", "n_outputs", "dt_s",
                  "step_is_exact", "default_params", "state_names", "input_names", "param_names",
                  "output_names")
_C_KEYWORDS = set("auto break case char const continue default do double else enum extern float for goto if "
                  "inline int long register restrict return short signed sizeof static struct switch "
                  "typedef union unsigned void volatile while work work_size size_t".split())  # the last arguments
_IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_MUTABLE_STATIC = re.compile(r"^\s*static\s+(?!const\b)(?!inline\b)[^(]*[=;\[]")
_HEAP_CALL = re.compile(r"\b(malloc|calloc|realloc|free)\s*\(")


class CodegenError(GenthermalError):
    """The model or an extra function cannot be turned into C under the ABI's rules."""


@dataclasses.dataclass(frozen=True)
class Signature:
    """C signature of an extra entry point ``<prefix>_<name>(inputs..., outputs..., work, work_size)``.

    Attributes
    ----------
    name : str
        Entry point name without the prefix.
    inputs, outputs : tuple of (str, (int, int))
        Argument names and (rows, columns) of the dense row-major arrays.
    """

    name: str
    inputs: tuple
    outputs: tuple


@dataclasses.dataclass(frozen=True)
class GeneratedLibrary:
    """What :func:`generate_c` wrote.

    Attributes
    ----------
    directory : pathlib.Path
        Where the files are.
    prefix : str
        Prefix of every public C symbol and file.
    model_name : str
        ``ThermalModel.name``.
    sources : tuple of pathlib.Path
        Every C source to compile (the CasADi sources and the ABI layer).
    headers : tuple of pathlib.Path
        ``<prefix>.h`` (include this one) and ``<prefix>_casadi.h``.
    dt_s : float
        Step of ``<prefix>_step``, s.
    exact : bool
        True when the step is the exact zero-order hold of the linear model.
    n_states, n_inputs, n_params, n_outputs : int
    work_size : int
        Doubles of caller work memory that every entry point needs.
    extra_functions : tuple of Signature
    source_hash : str
        SHA-256 of every written file (names and contents): the compiled library's cache key.
    """

    directory: Path
    prefix: str
    model_name: str
    sources: tuple
    headers: tuple
    dt_s: float
    exact: bool
    n_states: int
    n_inputs: int
    n_params: int
    n_outputs: int
    work_size: int
    extra_functions: tuple
    source_hash: str

    @property
    def header(self) -> Path:
        """The ABI header users include, ``<prefix>.h``."""
        return self.directory / f"{self.prefix}.h"

    @property
    def abi_source(self) -> Path:
        """The ABI layer, ``<prefix>.c``."""
        return self.directory / f"{self.prefix}.c"

    @property
    def casadi_sources(self) -> tuple:
        """The CasADi-generated sources, ``<prefix>_casadi_<name>.c``."""
        return tuple(s for s in self.sources if s != self.abi_source)


def generate_c(model: ThermalModel, out_dir, dt_s: float = 10.0, prefix: str = "gt",
               extra_functions: dict | None = None) -> GeneratedLibrary:
    """Write the C sources, headers and ABI layer of ``model`` into ``out_dir``.

    Parameters
    ----------
    model : ThermalModel
        Nonlinear simulation model or linear design model.
    out_dir : str or pathlib.Path
        Output directory (created). Stale ``<prefix>_casadi_*.c`` files in it are removed.
    dt_s : float
        Step of the discrete ``<prefix>_step``, s.
    prefix : str
        C identifier that starts every public symbol and file name.
    extra_functions : dict of str to casadi.Function, optional
        More entry points ``<prefix>_<name>(inputs..., outputs..., work, work_size)``; every input and output
        becomes a dense row-major array named after the CasADi argument.

    Returns
    -------
    GeneratedLibrary

    Raises
    ------
    InputError
        Bad prefix, extra-function name or argument name.
    CodegenError
        Generated code that would break the ABI rules (mutable static data, heap use).
    """
    if not _IDENTIFIER.match(prefix) or prefix.lower() in _C_KEYWORDS:
        raise InputError("prefix", prefix, "must be a C identifier (letters, digits, _), e.g. gt")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    discrete = model.discretise(dt_s)
    functions = _casadi_functions(model, discrete, prefix)
    signatures = []
    for name, function in (extra_functions or {}).items():
        signature = _extra_signature(name, function)
        signatures.append(signature)
        functions[name] = _dense_function(f"{prefix}_cg_{name}", inline_floors(function))
    for stale in out_dir.glob(f"{prefix}_casadi_*.c"):
        stale.unlink()
    sources = [_generate_source(out_dir, prefix, name, function) for name, function in functions.items()]
    casadi_header = _generate_header(out_dir, prefix, functions.values())
    work = _work_sizes(casadi_header.read_text(), [f"{prefix}_cg_{name}" for name in functions])
    fields = _template_fields(model, discrete, prefix, signatures, work)
    abi_source = _fill_template("model.c.in", fields, out_dir / f"{prefix}.c")
    abi_header = _fill_template("model.h.in", fields, out_dir / f"{prefix}.h")
    written = sources + [abi_source, abi_header, casadi_header]
    digest = hashlib.sha256()
    for path in sorted(written):
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return GeneratedLibrary(
        directory=out_dir, prefix=prefix, model_name=model.name, sources=tuple(sources + [abi_source]),
        headers=(abi_header, casadi_header), dt_s=float(dt_s), exact=bool(discrete.exact),
        n_states=model.n_states, n_inputs=len(model.input_names), n_params=len(model.parameter_names),
        n_outputs=len(model.output_names), work_size=work["w"], extra_functions=tuple(signatures),
        source_hash=digest.hexdigest())


def model_library(model: ThermalModel, dt_s: float = 10.0, prefix: str = "gt", extra_functions=None):
    """Generate, compile (cached by source hash) and load the C library of ``model``.

    Parameters
    ----------
    model : ThermalModel
    dt_s : float
        Step of the discrete step function, s.
    prefix : str
        Prefix of the C symbols.
    extra_functions : dict of str to casadi.Function, optional
        See :func:`generate_c`.

    Returns
    -------
    genthermal.ccompile.CompiledModel

    Raises
    ------
    genthermal.errors.CompilerNotFoundError
        No C compiler; ``model.functions`` and :func:`genthermal.simulate.simulate` still work.
    """
    from .ccompile import CompiledModel, compile_library  # ccompile builds on this module

    with tempfile.TemporaryDirectory(prefix="genthermal-codegen-") as scratch:
        generated = generate_c(model, scratch, dt_s=dt_s, prefix=prefix, extra_functions=extra_functions)
        library = compile_library(generated)
    return CompiledModel(library, generated)


# --- CasADi functions -------------------------------------------------------------------------------
def _dense_function(name: str, function: ca.Function) -> ca.Function:
    """``function`` with every input and output a dense, row-major, flat array."""
    symbol = ca.SX.sym if function.is_a("SXFunction") else ca.MX.sym
    flat_inputs, matrices = [], []
    for i in range(function.n_in()):
        rows, cols = function.size_in(i)
        flat = symbol(function.name_in(i), rows * cols)
        flat_inputs.append(flat)
        matrices.append(ca.reshape(flat, cols, rows).T)  # row-major memory = column-major transpose
    outputs = function.call(matrices)
    flat_outputs = [ca.vec(ca.densify(output.T)) for output in outputs]
    return ca.Function(name, flat_inputs, flat_outputs, function.name_in(), function.name_out())


def _casadi_functions(model: ThermalModel, discrete, prefix: str) -> dict:
    """The functions behind the fixed entry points, named ``<prefix>_cg_<name>``; the step of an
    affine model as matrix products with its loss floors (:func:`affine_with_floors`), any other
    step without divisions by constants."""
    step = (discrete.exact and affine_with_floors(discrete.step)) or inline_floors(discrete.step, reciprocals=True)
    functions = {"step": _dense_function(f"{prefix}_cg_step", step)}
    for name in MODEL_FUNCTIONS:
        functions[name] = _dense_function(f"{prefix}_cg_{name}", inline_floors(model.functions[name]))
    rhs = model.functions["rhs"]
    x, u, p = rhs.sx_in()
    seed = ca.SX.sym("seed", model.n_states)
    row = ca.cse(ca.densify(ca.jtimes(rhs(x, u, p), p, seed, True)))  # cse: 4 % less code to compile
    functions["jac_p_row"] = ca.Function(f"{prefix}_cg_jac_p_row", [x, u, p, seed], [row],
                                         ["x", "u", "p", "seed"], ["row"])
    return functions


def _extra_signature(name: str, function) -> Signature:
    """Check an extra function and return its C signature."""
    field = f"extra_functions[{name!r}]"
    if not isinstance(function, ca.Function):
        raise InputError(field, type(function).__name__, "must be a casadi.Function")
    if (not _IDENTIFIER.match(name) or name in RESERVED_NAMES or name in _C_KEYWORDS
            or name.startswith(("cg_", "casadi"))):
        raise InputError("extra_functions", name, "the name must be a C identifier, not a C keyword, not "
                         f"starting with cg_ or casadi, and none of {', '.join(RESERVED_NAMES)}")
    if function.n_in() == 0 or function.n_out() == 0:
        raise InputError(field, function.str(), "needs at least one input and one output")
    inputs = tuple((function.name_in(i), tuple(function.size_in(i))) for i in range(function.n_in()))
    outputs = tuple((function.name_out(i), tuple(function.size_out(i))) for i in range(function.n_out()))
    arguments = [argument for argument, _ in inputs + outputs]
    for argument in arguments:
        if not _IDENTIFIER.match(argument) or argument in _C_KEYWORDS:
            raise InputError(f"{field} argument", argument, "argument names must be C identifiers other "
                             "than C keywords and 'work' (name them in the casadi.Function)")
    if len(set(arguments)) != len(arguments):
        raise InputError(field, arguments, "input and output names must differ (they become C arguments)")
    return Signature(name, inputs, outputs)


# --- files ------------------------------------------------------------------------------------------
def _generate_source(out_dir: Path, prefix: str, name: str, function: ca.Function) -> Path:
    """Write one CasADi source and check it against the ABI rules."""
    generator = ca.CodeGenerator(f"{prefix}_casadi_{name}.c", {"with_header": False})
    generator.add(function)
    path = Path(generator.generate(str(out_dir) + "/"))
    problems = forbidden_constructs(path.read_text())
    if problems:
        raise CodegenError(f"generated code of {name!r} breaks the reentrancy rules (no mutable static "
                           f"data, no heap): {'; '.join(problems[:3])}")
    return path


def _generate_header(out_dir: Path, prefix: str, functions) -> Path:
    """Write ``<prefix>_casadi.h`` declaring every generated function (one CasADi header)."""
    generator = ca.CodeGenerator(f"{prefix}_casadi", {"with_header": True})
    for function in functions:
        generator.add(function)
    with tempfile.TemporaryDirectory() as scratch:  # the combined .c would duplicate the sources
        generator.generate(scratch + "/")
        text = (Path(scratch) / f"{prefix}_casadi.h").read_text()
    header = out_dir / f"{prefix}_casadi.h"
    header.write_text(text)
    return header


def forbidden_constructs(source: str) -> list[str]:
    """Lines of C ``source`` that define mutable static data or call the heap allocator.

    Parameters
    ----------
    source : str
        C source text.

    Returns
    -------
    list of str
        The offending lines (empty when the source keeps the reentrancy rules).
    """
    code = re.sub(r"/\*.*?\*/", "", source, flags=re.DOTALL)
    return [line.strip() for line in code.splitlines() if _MUTABLE_STATIC.match(line) or _HEAP_CALL.search(line)]


def _work_sizes(header: str, names: list[str]) -> dict:
    """Largest ``SZ_ARG``, ``SZ_RES``, ``SZ_IW`` and ``SZ_W`` over ``names`` (each at least 1)."""
    sizes = {}
    for key in ("arg", "res", "iw", "w"):
        values = []
        for name in names:
            match = re.search(rf"#define {name}_SZ_{key.upper()} (\d+)", header)
            if not match:
                raise CodegenError(f"the CasADi header does not state {name}_SZ_{key.upper()}; "
                                   f"CasADi {ca.__version__} may write headers this version cannot read")
            values.append(int(match.group(1)))
        sizes[key] = max(values + [1])
    return sizes


def _c_strings(texts) -> str:
    """C initializer of string literals."""
    return ", ".join('"' + t.replace("\\", "\\\\").replace('"', '\\"') + '"' for t in texts)


def _template_fields(model, discrete, prefix, signatures, work) -> dict:
    return {
        "PREFIX": prefix, "PREFIX_UPPER": prefix.upper(), "MODEL_NAME": model.name,
        "MODEL_NAME_LITERAL": _c_strings([model.name]), "GENTHERMAL_VERSION": __version__,
        "CASADI_VERSION": ca.__version__, "ABI_VERSION": str(ABI_VERSION),
        "N_STATES": str(model.n_states), "N_INPUTS": str(len(model.input_names)),
        "N_PARAMS": str(len(model.parameter_names)), "N_OUTPUTS": str(len(model.output_names)),
        "WORK_SIZE": str(work["w"]), "MAX_SZ_ARG": str(work["arg"]), "MAX_SZ_RES": str(work["res"]),
        "MAX_SZ_IW": str(work["iw"]), "DT_S": repr(float(discrete.dt_s)),
        "STEP_IS_EXACT": "1" if discrete.exact else "0",
        "DEFAULT_PARAMS": ", ".join(repr(float(v)) for v in model.p0),
        "STATE_NAMES": _c_strings(model.state_names), "INPUT_NAMES": _c_strings(model.input_names),
        "PARAM_NAMES": _c_strings(model.parameter_names), "OUTPUT_NAMES": _c_strings(model.output_names),
        "EXTRA_PROTOTYPES": "".join(_extra_prototype(prefix, s) + ";\n" for s in signatures),
        "EXTRA_DEFINITIONS": "".join(_extra_definition(prefix, s) for s in signatures),
    }


def _extra_prototype(prefix: str, signature: Signature) -> str:
    shapes = ", ".join(f"{n}[{r}x{c}]" for n, (r, c) in signature.inputs)
    results = ", ".join(f"{n}[{r}x{c}]" for n, (r, c) in signature.outputs)
    arguments = [f"const double* {n}" for n, _ in signature.inputs]
    arguments += [f"double* {n}" for n, _ in signature.outputs] + ["double* work", "size_t work_size"]
    return (f"\n/* ({shapes}) -> ({results}), dense row-major */\n"
            f"int {prefix}_{signature.name}({', '.join(arguments)})")


def _extra_definition(prefix: str, signature: Signature) -> str:
    upper = prefix.upper()
    names = [n for n, _ in signature.inputs + signature.outputs]
    n_in, n_out = len(signature.inputs), len(signature.outputs)
    lines = [_extra_prototype(prefix, signature), "{", f"    const double* inputs[{n_in}];",
             f"    double* outputs[{n_out}];",
             f"    if ({' || '.join(f'!{n}' for n in names + ['work'])}) return {upper}_ERR_NULL_POINTER;",
             f"    if (work_size < {upper}_WORK_SIZE) return {upper}_ERR_WORK_TOO_SMALL;"]
    lines += [f"    inputs[{i}] = {n};" for i, (n, _) in enumerate(signature.inputs)]
    lines += [f"    outputs[{i}] = {n};" for i, (n, _) in enumerate(signature.outputs)]
    lines += [f"    return evaluate({prefix}_cg_{signature.name}, inputs, {n_in}, outputs, {n_out}, work);", "}"]
    return "\n".join(lines) + "\n"


def _fill_template(template_name: str, fields: dict, target: Path) -> Path:
    """Replace every ``@NAME@`` of a template in ``codegen/`` and write ``target``."""
    template = shipped_file(TEMPLATE_DIR / template_name)

    def field(match):
        if match.group(1) not in fields:
            raise CodegenError(f"template {template_name} uses unknown field @{match.group(1)}@")
        return fields[match.group(1)]

    target.write_text(re.sub(r"@([A-Z_]+)@", field, template.read_text()))
    return target
