"""The curated public API: what ``import genthermal`` exports, documented and strict about keywords."""

import importlib
import inspect
import re
import subprocess
import sys
from pathlib import Path

import pytest

import genthermal

ROOT = Path(__file__).resolve().parents[1]
EXPORTS = [name for name in genthermal.__all__ if name != "__version__"]
#: docstring sections that list parameters (numpydoc)
PARAMETER_SECTIONS = ("Parameters", "Other Parameters", "Attributes")


def documented_names(docstring: str) -> set[str]:
    """The names a numpy-style docstring lists under its parameter sections (``a, b : float``)."""
    names, section = set(), None
    lines = inspect.cleandoc(docstring).splitlines()
    for line, underline in zip(lines, lines[1:] + [""]):
        if underline.strip() and set(underline.strip()) == {"-"}:
            section = line.strip()
            continue
        if section in PARAMETER_SECTIONS and line and not line[0].isspace() and not set(line.strip()) == {"-"}:
            head = line.split(" : ")[0]
            names.update(name.strip().lstrip("*") for name in head.split(","))
    return names


def signature_of(obj):
    return inspect.signature(obj.__init__ if inspect.isclass(obj) else obj)


def test_import_genthermal_is_light():
    """The entry points are imported on first use: importing the package loads no numerical library."""
    code = ("import sys, genthermal; heavy = [m for m in ('casadi', 'sympy', 'pandas', 'matplotlib', 'scipy') "
            "if m in sys.modules]; print(','.join(heavy))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.strip() == ""


@pytest.mark.parametrize("name", EXPORTS)
def test_every_export_resolves_to_a_documented_object(name):
    obj = getattr(genthermal, name)
    assert callable(obj), name
    doc = inspect.getdoc(obj)
    assert doc and len(doc.splitlines()[0]) > 10, f"{name} has no summary line"


@pytest.mark.parametrize("name", EXPORTS)
def test_every_parameter_of_an_export_is_documented(name):
    obj = getattr(genthermal, name)
    parameters = [p for p in signature_of(obj).parameters.values()
                  if p.name != "self" and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]
    missing = [p.name for p in parameters if p.name not in documented_names(inspect.getdoc(obj) or "")]
    assert not missing, f"genthermal.{name}: parameters without a docstring entry: {missing}"


@pytest.mark.parametrize("name", [n for n in EXPORTS if n != "InputError"])
def test_an_unknown_keyword_argument_raises(name):
    obj = getattr(genthermal, name)
    assert not any(p.kind is p.VAR_KEYWORD for p in signature_of(obj).parameters.values()), \
        f"genthermal.{name} takes **kwargs: a misspelt keyword would pass silently"
    with pytest.raises(TypeError, match="definitely_not_a_parameter"):
        obj(definitely_not_a_parameter=1)


def test_an_export_named_like_a_sub_module_stays_the_function():
    importlib.import_module("genthermal.simulate")
    importlib.import_module("genthermal.diagnose.report")
    assert inspect.isfunction(genthermal.simulate) and inspect.isfunction(genthermal.diagnose)
    assert sys.modules["genthermal.simulate"].simulate is genthermal.simulate


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no_such_thing"):
        genthermal.no_such_thing  # noqa: B018


def test_the_api_reference_documents_every_export():
    page = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    listed = set(re.findall(r"\.\. auto(?:function|class):: genthermal\.(\w+)", page))
    assert listed == set(EXPORTS)


def test_importing_genthermal_modules_leaves_the_matplotlib_backend_alone():
    code = ("import matplotlib; matplotlib.use('svg'); import genthermal.plots, genthermal.estimation.ekf, "
            "genthermal.schedule.report, genthermal.diagnose.report; print(matplotlib.get_backend())")
    env = {k: v for k, v in __import__("os").environ.items() if k != "MPLBACKEND"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT, env=env)
    assert out.stdout.strip() == "svg"


def test_python_m_genthermal_is_the_command_line():
    out = subprocess.run([sys.executable, "-m", "genthermal", "--version"], capture_output=True, text=True,
                         check=True, cwd=ROOT)
    assert out.stdout.strip() == f"genthermal {genthermal.__version__}"


def test_the_package_is_typed():
    assert (Path(genthermal.__file__).parent / "py.typed").is_file()
