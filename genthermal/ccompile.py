"""Compile generated C into a shared library with the system compiler, cache it, load it (ctypes).

:func:`compile_objects` and :func:`compile_library` build objects in parallel and cache objects and
libraries under a key of compiler, flags and sources in ``$GENTHERMAL_CACHE_DIR`` (default
``~/.cache/genthermal``); :class:`CompiledModel` loads a library (ctypes). The cache is private to the user and every entry is checked against its
recorded SHA-256 before use: ``docs/guide/safety.md``.
"""

from __future__ import annotations

import concurrent.futures
import ctypes
import functools
import hashlib
import os
import re
import shlex
import shutil
import stat
import subprocess
import sys
import uuid
from pathlib import Path

import numpy as np

from .codegen import ABI_VERSION, CodegenError, GeneratedLibrary
from .errors import CompilerNotFoundError, GenthermalError, InputError

#: Flags of every object of the library (``-shared`` is added when linking).
COMPILE_FLAGS = ("-O2", "-fPIC", "-std=c99")
#: Lines of compiler output quoted in a CompilationError.
STDERR_TAIL_LINES = 25
_LIBRARY_SUFFIX = ".dylib" if sys.platform == "darwin" else ".so"
_INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.MULTILINE)


class CompilationError(GenthermalError):
    """The C compiler or linker failed; the message quotes the end of its output."""


class LibraryCallError(GenthermalError):
    """A C entry point returned a non-zero status."""


def find_compiler() -> list[str]:
    """Return the C compiler command: ``$CC`` if set (may carry arguments), else ``cc`` or ``gcc``.

    Raises
    ------
    CompilerNotFoundError
        If none is found on PATH.
    """
    configured = os.environ.get("CC", "").strip()
    candidates = [shlex.split(configured)] if configured else [["cc"], ["gcc"]]
    for command in candidates:
        executable = shutil.which(command[0])
        if executable:
            return [executable, *command[1:]]
    looked_for = ", ".join(" ".join(c) for c in candidates)
    raise CompilerNotFoundError(
        f"no C compiler found (looked for {looked_for} on PATH; set CC to choose one). The C "
        "sources were generated and the Python/CasADi path (genthermal simulate, model.functions) "
        "works without a compiler. To compile, install one, e.g. `sudo apt-get install gcc` "
        "(Debian/Ubuntu), `sudo dnf install gcc` (Fedora) or `xcode-select --install` (macOS).")


def cache_dir() -> Path:
    """Directory of compiled objects and libraries: ``$GENTHERMAL_CACHE_DIR`` or ``~/.cache/genthermal``."""
    configured = os.environ.get("GENTHERMAL_CACHE_DIR", "").strip()
    return Path(configured).expanduser() if configured else Path.home() / ".cache" / "genthermal"


def private_folder(path: Path) -> Path:
    """``path`` under :func:`cache_dir`, created (with the missing folders up to it) with mode 0700.

    Raises
    ------
    InputError
        The cache folder or one below it is not a folder, belongs to another user, or other users
        may write in it: a library found there could have been put there by them.
    """
    root = cache_dir()
    chain = [root, *reversed([p for p in Path(path).parents if root in p.parents]), Path(path)]
    for folder in dict.fromkeys(chain):
        try:
            folder.mkdir(mode=0o700, parents=folder == root, exist_ok=True)
        except FileExistsError:
            pass
        info = os.stat(folder)
        reason = None
        if not stat.S_ISDIR(info.st_mode):
            reason = "is not a folder"
        elif hasattr(os, "getuid") and info.st_uid != os.getuid():
            reason = f"belongs to another user (uid {info.st_uid})"
        elif info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
            reason = f"may be written by other users (mode {stat.S_IMODE(info.st_mode):o})"
        if reason:
            raise InputError("compiled-library cache (GENTHERMAL_CACHE_DIR)", str(folder),
                             f"{reason}: a library loaded from it could be anyone's code; make it private "
                             "(chmod 700) or set GENTHERMAL_CACHE_DIR to a folder of your own")
    return Path(path)


def _record(path: Path) -> Path:
    return path.with_name(path.name + ".sha256")


def _file_digest(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as file:
        for block in iter(lambda: file.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _is_intact(path: Path, key: str) -> bool:
    """True when ``path`` and its record exist and the record holds ``key`` and the file's SHA-256."""
    try:
        recorded = _record(path).read_text().split()
        return recorded == [key, _file_digest(path)]
    except (OSError, UnicodeDecodeError):
        return False


def _enter(scratch: Path, target: Path, key: str) -> None:
    """Move a complete ``scratch`` file onto ``target`` in the cache, with its record."""
    record = _atomic_target(_record(target))
    record.write_text(f"{key} {_file_digest(scratch)}\n")
    os.replace(scratch, target)
    os.replace(record, _record(target))


@functools.lru_cache(maxsize=None)
def _compiler_identity(command: tuple) -> str:
    """Path and version banner of the compiler (part of every cache key)."""
    try:
        banner = subprocess.run([*command, "--version"], capture_output=True, text=True, timeout=30).stdout
    except (OSError, subprocess.SubprocessError):
        banner = ""
    return f"{command}\n{banner.strip()}"


def _run(command: list[str], what: str) -> None:
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        tail = "\n".join((result.stderr or result.stdout).strip().splitlines()[-STDERR_TAIL_LINES:])
        raise CompilationError(f"{what} failed (exit {result.returncode}): {shlex.join(command)}\n{tail}")


def _atomic_target(final: Path) -> Path:
    final.parent.mkdir(parents=True, exist_ok=True)
    return final.with_name(f".{final.name}.{uuid.uuid4().hex}.tmp")


def compile_objects(sources, headers=(), flags=COMPILE_FLAGS, compiler=None) -> list[Path]:
    """Compile C sources to cached object files, the missing ones in parallel.

    Parameters
    ----------
    sources : sequence of path-like
        C files.
    headers : sequence of path-like
        Headers the sources may include: their directories are searched, and the contents of those
        a source includes (``#include "name.h"``) are part of its cache key.
    flags : sequence of str
        Compiler flags.
    compiler : list of str, optional
        Compiler command; default :func:`find_compiler`.

    Returns
    -------
    list of pathlib.Path
        Object files in the cache, in the order of ``sources``.
    """
    compiler = compiler or find_compiler()
    headers = {Path(h).name: Path(h) for h in headers}
    common = hashlib.sha256(_compiler_identity(tuple(compiler)).encode() + repr(tuple(flags)).encode())
    include = [f"-I{d}" for d in dict.fromkeys(str(h.parent) for h in headers.values())]
    objects, missing = [], []
    for source in map(Path, sources):
        text = source.read_bytes()
        key = common.copy()
        key.update(source.name.encode() + text)
        for name in sorted(set(_INCLUDE.findall(text.decode(errors="replace"))) & set(headers)):
            key.update(name.encode() + headers[name].read_bytes())
        target = private_folder(cache_dir() / "codegen" / "obj") / f"{source.stem}-{key.hexdigest()[:24]}.o"
        objects.append(target)
        if not _is_intact(target, key.hexdigest()):
            missing.append((source, target, key.hexdigest()))

    def build(item):
        source, target, key = item
        scratch = _atomic_target(target)
        try:
            _run([*compiler, *flags, *include, "-c", str(source), "-o", str(scratch)], f"compiling {source.name}")
            _enter(scratch, target, key)
        finally:
            scratch.unlink(missing_ok=True)

    missing.sort(key=lambda item: item[0].stat().st_size, reverse=True)  # longest compile first
    if missing:
        with concurrent.futures.ThreadPoolExecutor(max_workers=min(len(missing), os.cpu_count() or 1)) as pool:
            list(pool.map(build, missing))
    return objects


def compile_library(generated: GeneratedLibrary, out_dir=None) -> Path:
    """Compile the generated sources into a shared library (``-O2 -fPIC -shared -std=c99``).

    Parameters
    ----------
    generated : GeneratedLibrary
        From :func:`genthermal.codegen.generate_c`.
    out_dir : path-like, optional
        Where to copy ``lib<prefix>.so``; default: leave it in the cache only.

    Returns
    -------
    pathlib.Path
        The library (in ``out_dir`` if given, else in the cache).

    Raises
    ------
    CompilerNotFoundError
        No C compiler.
    CompilationError
        The compiler or linker failed (the message ends with its output).
    """
    compiler = find_compiler()
    objects = compile_objects(generated.sources, generated.headers, COMPILE_FLAGS, compiler)
    key = hashlib.sha256("\n".join(_record(o).read_text() for o in objects).encode()).hexdigest()
    name = f"lib{generated.prefix}{_LIBRARY_SUFFIX}"
    cached = private_folder(cache_dir() / "codegen" / "lib" / key[:24]) / name
    if not _is_intact(cached, key):
        scratch = _atomic_target(cached)
        try:
            _run([*compiler, "-shared", *COMPILE_FLAGS, "-o", str(scratch), *map(str, objects), "-lm"],
                 f"linking {name}")
            _enter(scratch, cached, key)
        finally:
            scratch.unlink(missing_ok=True)
    if out_dir is None:
        return cached
    target = Path(out_dir) / name
    target.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(cached, target)
    return target


def _vector(value, size: int, field: str) -> np.ndarray:
    array = np.ascontiguousarray(value, dtype=np.float64).reshape(-1)
    if array.size != size:
        raise InputError(field, list(np.shape(value)), f"expected {size} values")
    return array


class CompiledModel:
    """A compiled model library, called through ctypes on preallocated numpy arrays.

    Parameters
    ----------
    library_path : path-like
        Shared library from :func:`compile_library`.
    generated : GeneratedLibrary
        What it was compiled from (prefix, sizes, extra functions).

    Attributes
    ----------
    path : pathlib.Path
        The loaded library.
    dt_s : float
        Step of :meth:`step` and :meth:`simulate`, s.
    n_states, n_inputs, n_params, n_outputs : int
    state_names, input_names, parameter_names, output_names : tuple of str
    default_params : numpy.ndarray
        Parameter values used when ``p`` is None (SI units).

    Notes
    -----
    The C library is reentrant; an instance of this class owns one work buffer, so give every
    thread its own instance. Arrays are float64 in °C, A, s, as documented in ``codegen/ABI.md``.
    """

    def __init__(self, library_path, generated: GeneratedLibrary):
        self.path = Path(library_path)
        self.generated = generated
        self._lib = ctypes.CDLL(str(self.path))
        prefix = self.prefix = generated.prefix
        if self._constant(ctypes.c_int, "abi_version") != ABI_VERSION:
            raise CodegenError(f"{self.path} has ABI version {self._constant(ctypes.c_int, 'abi_version')}"
                               f", this genthermal reads version {ABI_VERSION}: regenerate it")
        self.n_states = self._constant(ctypes.c_int, "n_states")
        self.n_inputs = self._constant(ctypes.c_int, "n_inputs")
        self.n_params = self._constant(ctypes.c_int, "n_params")
        self.n_outputs = self._constant(ctypes.c_int, "n_outputs")
        if (self.n_states, self.n_inputs, self.n_params) != (generated.n_states, generated.n_inputs,
                                                             generated.n_params):
            raise CodegenError(f"{self.path} does not match the generated sources of {generated.model_name}")
        self.dt_s = self._constant(ctypes.c_double, "dt_s")
        self.default_params = np.array((ctypes.c_double * self.n_params).in_dll(self._lib, f"{prefix}_default_params"))
        self.state_names = self._names("state_names", self.n_states)
        self.input_names = self._names("input_names", self.n_inputs)
        self.parameter_names = self._names("param_names", self.n_params)
        self.output_names = self._names("output_names", self.n_outputs)
        self._lib[f"{prefix}_work_size"].restype = ctypes.c_size_t
        self._work = np.zeros(max(int(self._lib[f"{prefix}_work_size"]()), 1))
        self._work_pointer = self._work.ctypes.data
        n, m, k = self.n_states, self.n_inputs, self.n_params
        self._results = {"step": np.empty(n), "rhs": np.empty(n), "jac_x": np.empty((n, n)),
                         "jac_u": np.empty((n, m)), "jac_p": np.empty((n, k)), "outputs": np.empty(self.n_outputs)}
        self._entries = {name: self._entry(name, 6) for name in self._results}
        self._entries["step"] = self._entry("step", 5)
        self._entries["simulate"] = self._entry("simulate", 6, {2: ctypes.c_int})
        self._signatures = {s.name: s for s in generated.extra_functions}
        for signature in generated.extra_functions:
            self._entries[signature.name] = self._entry(signature.name,
                                                        len(signature.inputs) + len(signature.outputs) + 2)

    # --- loading helpers ----------------------------------------------------------------------
    def _constant(self, ctype, name):
        return ctype.in_dll(self._lib, f"{self.prefix}_{name}").value

    def _names(self, name: str, count: int) -> tuple:
        return tuple(v.decode() for v in (ctypes.c_char_p * count).in_dll(self._lib, f"{self.prefix}_{name}"))

    def _entry(self, name: str, n_arguments: int, types: dict | None = None):
        """Entry point ``<prefix>_<name>``: pointers, except ``types`` by index and the last
        argument, the work size (``size_t``)."""
        function = self._lib[f"{self.prefix}_{name}"]
        function.restype = ctypes.c_int
        function.argtypes = [(types or {}).get(i, ctypes.c_void_p) for i in range(n_arguments - 1)] + [ctypes.c_size_t]
        return function

    def _call(self, name: str, *arguments) -> None:
        status = self._entries[name](*arguments, self._work_pointer, self._work.size)
        if status != 0:
            raise LibraryCallError(f"{self.prefix}_{name} returned status {status} (see codegen/ABI.md)")

    def _xup(self, name: str, x, u, p):
        x = _vector(x, self.n_states, "x")
        u = _vector(u, self.n_inputs, "u")
        p = None if p is None else _vector(p, self.n_params, "p")
        result = self._results[name]
        self._call(name, x.ctypes.data, u.ctypes.data, None if p is None else p.ctypes.data, result.ctypes.data)
        return result.copy()

    # --- entry points -------------------------------------------------------------------------
    def step(self, x, u) -> np.ndarray:
        """State (°C) after one step of ``dt_s`` s from ``x`` (°C) with input ``u`` held."""
        x = _vector(x, self.n_states, "x")
        u = _vector(u, self.n_inputs, "u")
        result = self._results["step"]
        self._call("step", x.ctypes.data, u.ctypes.data, result.ctypes.data)
        return result.copy()

    def simulate(self, x0, U, out: np.ndarray | None = None) -> np.ndarray:
        """Run ``len(U)`` steps from ``x0``.

        Parameters
        ----------
        x0 : array_like
            Initial state, °C, shape (n_states,).
        U : array_like
            Inputs, shape (n_steps, n_inputs); row k is held over step k (A, °C).
        out : numpy.ndarray, optional
            C-contiguous float64 array of shape (n_steps, n_states) to write into (no allocation).

        Returns
        -------
        numpy.ndarray
            States after each step, °C, shape (n_steps, n_states).
        """
        x0 = _vector(x0, self.n_states, "x0")
        U = np.ascontiguousarray(U, dtype=np.float64)
        if U.ndim != 2 or U.shape[1] != self.n_inputs:
            raise InputError("U", list(U.shape), f"expected shape (n_steps, {self.n_inputs})")
        shape = (U.shape[0], self.n_states)
        if out is None:
            out = np.empty(shape)
        elif out.shape != shape or out.dtype != np.float64 or not out.flags.c_contiguous:
            raise InputError("out", list(out.shape), f"expected a C-contiguous float64 array of shape {shape}")
        self._call("simulate", x0.ctypes.data, U.ctypes.data, U.shape[0], out.ctypes.data)
        return out

    def rhs(self, x, u, p=None) -> np.ndarray:
        """dx/dt, K/s; ``p`` defaults to the parameters the library was generated with."""
        return self._xup("rhs", x, u, p)

    def jac_x(self, x, u, p=None) -> np.ndarray:
        """∂(dx/dt)/∂x, shape (n_states, n_states), 1/s."""
        return self._xup("jac_x", x, u, p)

    def jac_u(self, x, u, p=None) -> np.ndarray:
        """∂(dx/dt)/∂u, shape (n_states, n_inputs)."""
        return self._xup("jac_u", x, u, p)

    def jac_p(self, x, u, p=None) -> np.ndarray:
        """∂(dx/dt)/∂p, shape (n_states, n_params)."""
        return self._xup("jac_p", x, u, p)

    def outputs(self, x, u, p=None) -> np.ndarray:
        """Sensor temperatures, °C, in ``output_names`` order."""
        return self._xup("outputs", x, u, p)

    def call(self, name: str, *inputs):
        """Call an extra entry point given to :func:`genthermal.codegen.generate_c`.

        Parameters
        ----------
        name : str
            The extra function's name.
        *inputs : array_like
            One array per input, of the input's shape (matrices row-major).

        Returns
        -------
        numpy.ndarray or tuple of numpy.ndarray
            The outputs, shape (rows,) for a column and (rows, columns) otherwise.
        """
        if name not in self._signatures:
            raise InputError("name", name, f"not an extra function of this library ({', '.join(self._signatures)})")
        signature = self._signatures[name]
        if len(inputs) != len(signature.inputs):
            raise InputError(f"{name} inputs", len(inputs), f"expected {len(signature.inputs)}")
        arrays = [_vector(value, rows * cols, f"{name}.{argument}")
                  for value, (argument, (rows, cols)) in zip(inputs, signature.inputs)]
        results = [np.empty((rows, cols) if cols > 1 else rows) for _, (rows, cols) in signature.outputs]
        self._call(name, *(a.ctypes.data for a in arrays), *(r.ctypes.data for r in results))
        return results[0] if len(results) == 1 else tuple(results)

    def __repr__(self) -> str:
        return (f"CompiledModel({self.generated.model_name}, {self.path.name}: {self.n_states} states, "
                f"dt = {self.dt_s:g} s)")
