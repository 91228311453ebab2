"""Cross toolchain of the Cortex-M4F target: compile, link, measure, run under QEMU.

The target is the ARM MPS2 AN386 board (Cortex-M4 with the single-precision FPU) that
``qemu-system-arm`` emulates, built with the Debian ``gcc-arm-none-eabi`` toolchain and newlib,
hard-float ABI. Programs run bare metal (``c/startup.c``: no C start-up code, no heap) and talk to
the host through ARM semihosting.

Costs are counted in instructions: QEMU runs with ``-icount shift=ICOUNT_SHIFT``, so its virtual
clock advances ``2**ICOUNT_SHIFT`` ns per executed instruction, and the SysTick timer counts that
clock at the board's 25 MHz. QEMU does not model the pipeline, wait states or the 14-cycle double
division, so these are instruction counts, not cycles; a Cortex-M4 needs at least one cycle per
instruction.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
import re
import shutil
import subprocess
import tempfile
from importlib import resources
from pathlib import Path

from ..ccompile import CompilationError
from ..errors import CompilerNotFoundError, GenthermalError

#: QEMU machine: ARM MPS2 with the AN386 FPGA image, a Cortex-M4F.
MACHINE = "mps2-an386"
#: QEMU -icount shift: 2**shift ns of virtual time per instruction.
ICOUNT_SHIFT = 5
#: SysTick clock of the board (the processor clock), Hz.
SYSTICK_HZ = 25e6
#: Cortex-M4F, Thumb-2, single-precision FPU, hard-float calling convention.
CPU_FLAGS = ("-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard")
#: Flags of every object; ``-fstack-usage`` writes one ``.su`` file per object (frame sizes) and
#: ``-fcallgraph-info=su`` one ``.ci`` file (the call graph with those sizes).
COMPILE_FLAGS = (*CPU_FLAGS, "-O2", "-std=c99", "-ffunction-sections", "-fdata-sections", "-fstack-usage",
                 "-fcallgraph-info=su")
#: Bytes the Cortex-M4F stacks on an interrupt with an active FPU context (26 words).
EXCEPTION_FRAME_BYTES = 104
#: Hand-written sources compile warning-free with these; CasADi's sources add -Wno-unused-parameter.
STRICT_FLAGS = ("-Wall", "-Wextra", "-Werror")
#: Extra flags of each precision: the generated arithmetic in double or in float.
PRECISION_FLAGS = {"double": (), "single": ("-Dcasadi_real=float", "-fsingle-precision-constant")}
#: Symbols whose presence in the linked program would mean heap use.
HEAP_SYMBOLS = ("malloc", "_malloc_r", "calloc", "_calloc_r", "realloc", "_realloc_r", "free", "_free_r", "_sbrk",
                "_sbrk_r")
INSTALL_HINT = ("install them with `apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm` "
                "(Debian/Ubuntu)")


class TargetToolchainError(CompilerNotFoundError):
    """The cross compiler, newlib or QEMU is missing."""


class TargetRunError(GenthermalError):
    """The emulated program failed or did not finish."""


def tool(name: str) -> str:
    """Path of a tool of the target toolchain (``arm-none-eabi-gcc``, ``qemu-system-arm`` ...).

    Raises
    ------
    TargetToolchainError
        If it is not on PATH (the message says how to install it).
    """
    path = shutil.which(name)
    if path is None:
        raise TargetToolchainError(f"{name} not found on PATH: the Cortex-M4 target needs the Debian packages "
                                   f"gcc-arm-none-eabi, libnewlib-arm-none-eabi and qemu-system-arm; {INSTALL_HINT}")
    return path


def check_toolchain() -> None:
    """Raise :class:`TargetToolchainError` unless compiler, newlib and QEMU are all there."""
    gcc = tool("arm-none-eabi-gcc")
    tool("qemu-system-arm")
    libc = subprocess.run([gcc, *CPU_FLAGS, "-print-file-name=libc.a"], capture_output=True, text=True).stdout.strip()
    if not Path(libc).is_file():
        raise TargetToolchainError(f"arm-none-eabi-gcc finds no newlib for {' '.join(CPU_FLAGS)}; {INSTALL_HINT}")


def support_file(name: str) -> Path:
    """Path of a C support file of the target (``startup.c``, ``cortex_m4.ld`` ...)."""
    return Path(str(resources.files(__package__).joinpath("c").joinpath(name)))


@dataclasses.dataclass(frozen=True)
class TargetBuild:
    """A linked program for the target.

    Attributes
    ----------
    elf : pathlib.Path
    link_map : pathlib.Path
    objects : tuple of pathlib.Path
    precision : str
        ``"double"`` or ``"single"``.
    """

    elf: Path
    link_map: Path
    objects: tuple
    precision: str


def build(sources, include_dirs, out_dir, name: str, precision: str, generated_sources=(), defines=()) -> TargetBuild:
    """Compile and link a bare-metal program with the start-up code and linker script.

    Parameters
    ----------
    sources : sequence of path-like
        Hand-written C files (compiled with :data:`STRICT_FLAGS`).
    include_dirs : sequence of path-like
    out_dir : path-like
        Objects, ``.su`` files, the ELF and its link map go here.
    name : str
        Program name.
    precision : {"double", "single"}
    generated_sources : sequence of path-like
        CasADi-generated C files (strict flags and ``-Wno-unused-parameter``).
    defines : sequence of str
        ``NAME=VALUE`` macros for every file.

    Raises
    ------
    TargetToolchainError, genthermal.ccompile.CompilationError
    """
    gcc = tool("arm-none-eabi-gcc")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    common = [*COMPILE_FLAGS, *STRICT_FLAGS, *PRECISION_FLAGS[precision], *(f"-D{d}" for d in defines),
              *(f"-I{d}" for d in include_dirs), f"-I{support_file('board.h').parent}"]
    jobs = [(Path(s), common) for s in [support_file("startup.c"), *sources]]
    jobs += [(Path(s), [*common, "-Wno-unused-parameter"]) for s in generated_sources]

    def compile_one(job):
        source, flags = job
        target = out_dir / f"{source.stem}.o"
        _run([gcc, *flags, "-c", str(source), "-o", str(target)], f"cross-compiling {source.name}")
        return target

    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        objects = list(pool.map(compile_one, jobs))
    elf, link_map = out_dir / f"{name}.elf", out_dir / f"{name}.map"
    _run([gcc, *CPU_FLAGS, "-nostartfiles", "-T", str(support_file("cortex_m4.ld")), "-Wl,--gc-sections",
          f"-Wl,-Map={link_map}", "-o", str(elf), *map(str, objects), "-Wl,--start-group", "-lc", "-lm", "-lgcc",
          "-Wl,--end-group"], f"linking {elf.name}")
    return TargetBuild(elf, link_map, tuple(objects), precision)


def _run(command, what: str) -> subprocess.CompletedProcess:
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise CompilationError(f"{what} failed: {' '.join(command)}\n{result.stderr[-3000:]}")
    return result


def section_sizes(elf) -> dict:
    """Bytes of ``.text``, ``.rodata``, ``.data``, ``.bss`` (and ``.isr_vector``) of a linked program."""
    output = _run([tool("arm-none-eabi-size"), "-A", str(elf)], "reading section sizes").stdout
    sizes = {}
    for line in output.splitlines():
        parts = line.split()
        if len(parts) >= 2 and parts[0] in (".isr_vector", ".text", ".rodata", ".ARM.exidx", ".data", ".bss"):
            sizes[parts[0].lstrip(".")] = int(parts[1])
    return sizes


def symbol_sizes(elf) -> dict:
    """Name -> bytes of every sized symbol of a linked program."""
    output = _run([tool("arm-none-eabi-nm"), "--print-size", str(elf)], "listing symbols").stdout
    sizes = {}
    for line in output.splitlines():
        parts = line.split()
        if len(parts) == 4:
            sizes[parts[3]] = int(parts[1], 16)
    return sizes


def heap_symbols(build_result: TargetBuild) -> list[str]:
    """Heap functions present in the program's symbols or pulled in by its link map (should be none)."""
    defined = set(symbol_sizes(build_result.elf))
    map_text = build_result.link_map.read_text()
    pulled = {name for name in HEAP_SYMBOLS if re.search(rf"\({re.escape(name)}\)", map_text)}
    return sorted((defined & set(HEAP_SYMBOLS)) | pulled)


def stack_usage(build_result: TargetBuild) -> dict:
    """Function -> stack bytes of its own frame, from the ``.su`` files (``-fstack-usage``)."""
    frames = {}
    for obj in build_result.objects:
        su = obj.with_suffix(".su")
        for line in su.read_text().splitlines() if su.is_file() else []:
            location, size, kind = line.rsplit("\t", 2)
            if "dynamic" in kind and "bounded" not in kind:
                raise TargetRunError(f"{location.split(':')[-1]} has an unbounded stack frame ({kind})")
            frames[location.split(":")[-1]] = int(size)
    return frames


def worst_case_stack(build_result: TargetBuild, root: str = "reset_handler") -> tuple[int, list[str]]:
    """Deepest stack of any call path from ``root``, from the call graphs of ``-fcallgraph-info=su``.

    Adds :data:`EXCEPTION_FRAME_BYTES` for the SysTick interrupt, which may arrive at the deepest
    point (its handler's own frame is in the graph). A call through a function pointer (gcc's
    ``__indirect_call`` node: the ABI layer calls the generated CasADi functions so) is bounded by
    the deepest function that makes no indirect call itself.

    Returns
    -------
    bytes : int
    external : list of str
        Linked functions called on those paths whose frames the graph does not know (library
        routines compiled elsewhere, e.g. newlib's ``memcpy``): their stack is not included.
        Functions the linker removed still count in the depth: the bound is conservative.

    Raises
    ------
    TargetRunError
        A recursive call path or an unbounded frame: the stack has no static bound.
    """
    frames, calls = {}, {}
    for obj in build_result.objects:
        ci = obj.with_suffix(".ci")
        text = ci.read_text() if ci.is_file() else ""
        for title, label in re.findall(r'node: \{ title: "([^"]+)" label: "([^"]*)"', text):
            size = re.search(r"(\d+) bytes \(([^)]*)\)", label)
            if size:
                if "dynamic" in size.group(2) and "bounded" not in size.group(2):
                    raise TargetRunError(f"{title} has an unbounded stack frame ({size.group(2)})")
                frames[title] = int(size.group(1))
        for source, target in re.findall(r'edge: \{ sourcename: "([^"]+)" targetname: "([^"]+)"', text):
            calls.setdefault(source, set()).add(target)
    external, depth, visiting = set(), {}, set()

    def deepest(function: str) -> int:
        if function in depth:
            return depth[function]
        if function in visiting:
            raise TargetRunError(f"recursive call path through {function}: the stack has no static bound")
        if function not in frames:
            external.add(function)
            return 0
        visiting.add(function)
        depth[function] = frames[function] + max((deepest(c) for c in calls.get(function, ())), default=0)
        visiting.discard(function)
        return depth[function]

    direct = [f for f in frames if "__indirect_call" not in calls.get(f, ()) and not f.endswith("reset_handler")]
    frames["__indirect_call"] = 0
    calls["__indirect_call"] = set(direct)
    interrupt = max((deepest(t) for t in frames if t.endswith("systick_handler")), default=0)
    linked = symbol_sizes(build_result.elf)  # functions the linker removed are no external calls
    return deepest(root) + EXCEPTION_FRAME_BYTES + interrupt, sorted(f for f in external if f in linked)


def run(elf, timeout_s: float = 600.0) -> str:
    """Run a program on the emulated board; return what it printed.

    Raises
    ------
    TargetRunError
        Non-zero exit status (the program's ``main`` result or 99 for a fault) or a timeout.
    """
    with tempfile.TemporaryDirectory(prefix="genthermal-qemu-") as scratch:
        printed = Path(scratch) / "semihosting.txt"
        command = [tool("qemu-system-arm"), "-machine", MACHINE, "-nographic", "-monitor", "none", "-serial", "none",
                   "-chardev", f"file,id=semihosting,path={printed}",
                   "-semihosting-config", "enable=on,target=native,chardev=semihosting",
                   "-icount", f"shift={ICOUNT_SHIFT}", "-kernel", str(elf)]
        try:
            result = subprocess.run(command, capture_output=True, text=True, timeout=timeout_s)
        except subprocess.TimeoutExpired:
            raise TargetRunError(f"{Path(elf).name} did not finish within {timeout_s:g} s on {MACHINE}") from None
        output = printed.read_text() if printed.is_file() else ""
    if result.returncode != 0:
        tail = "\n".join((output + result.stderr).splitlines()[-5:])
        raise TargetRunError(f"{Path(elf).name} exited with status {result.returncode} on {MACHINE}:\n{tail}")
    return output


def instructions(ticks: float) -> float:
    """Instructions executed in ``ticks`` SysTick ticks under ``-icount shift=ICOUNT_SHIFT``."""
    return ticks / (SYSTICK_HZ * 2**ICOUNT_SHIFT * 1e-9)
