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


@pytest.mark.parametrize("name", [n for n in EXPORTS if not inspect.isclass(getattr(genthermal, n))])
def test_every_exported_function_documents_what_it_returns(name):
    assert "Returns\n-------" in inspect.getdoc(getattr(genthermal, name)), f"genthermal.{name} has no Returns section"


#: The result objects of the entry points and the methods that turn them into tables and figures.
RESULT_METHODS = [("genthermal.diagnose", "Diagnosis", "to_pandas"), ("genthermal.diagnose", "Diagnosis", "plot"),
                  ("genthermal.diagnose", "CalibrationResult", "to_pandas"),
                  ("genthermal.diagnose", "CalibrationResult", "plot"),
                  ("genthermal.schedule.flight.flight_result", "FlightResult", "to_pandas"),
                  ("genthermal.schedule.flight.flight_result", "FlightResult", "plot")]


@pytest.mark.parametrize("module, cls, method", RESULT_METHODS)
def test_every_result_method_documents_its_parameters_and_rejects_unknown_keywords(module, cls, method):
    function = getattr(getattr(importlib.import_module(module), cls), method)
    doc = inspect.getdoc(function) or ""
    parameters = [p.name for p in inspect.signature(function).parameters.values() if p.name != "self"]
    assert "Returns\n-------" in doc and not [p for p in parameters if p not in documented_names(doc)]
    with pytest.raises(TypeError, match="definitely_not_a_parameter"):
        function(object(), definitely_not_a_parameter=1)


def test_the_api_reference_documents_the_result_methods():
    page = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    for module, cls, method in RESULT_METHODS:
        block = re.search(rf"^\.\. autoclass:: [\w.]*\.{cls}\n((?:   .*\n)+)", page, re.MULTILINE)
        assert block and method in block.group(1), f"{cls}.{method} is not in docs/api.md"


def test_an_export_named_like_a_sub_module_stays_the_function():
    importlib.import_module("genthermal.simulate")
    importlib.import_module("genthermal.diagnose.report")
    assert genthermal.simulate.__wrapped__ is sys.modules["genthermal.simulate"].simulate
    assert genthermal.diagnose.__wrapped__ is sys.modules["genthermal.diagnose.discover"].diagnose
    for name in ("simulate", "diagnose"):
        function = getattr(genthermal, name)
        assert inspect.signature(function) == inspect.signature(function.__wrapped__)
        assert inspect.getdoc(function) == inspect.getdoc(function.__wrapped__)


def test_the_sub_module_named_like_an_export_is_reachable_through_it():
    import genthermal.diagnose as diagnose_package
    import genthermal.diagnose.report as report
    import genthermal.simulate as simulate_module

    assert report is sys.modules["genthermal.diagnose.report"]
    assert diagnose_package.Diagnosis is sys.modules["genthermal.diagnose"].Diagnosis
    assert diagnose_package.compare is sys.modules["genthermal.diagnose"].compare
    assert simulate_module.simulate is sys.modules["genthermal.simulate"].simulate
    assert "report" in dir(genthermal.diagnose)
    with pytest.raises(AttributeError, match="no_such_module"):
        genthermal.diagnose.no_such_module  # noqa: B018


@pytest.mark.parametrize("statement", [
    "import genthermal.diagnose.report as r; import genthermal; assert r.write_diagnosis_report; "
    "assert callable(genthermal.diagnose) and not isinstance(genthermal.diagnose, type(r))",
    "import genthermal; f = genthermal.diagnose; import genthermal.diagnose.report as r; assert genthermal.diagnose is f",
])
def test_both_spellings_work_in_a_fresh_interpreter(statement):
    """Whichever comes first, the entry point or the sub-module import, both work."""
    subprocess.run([sys.executable, "-c", statement], capture_output=True, text=True, check=True, cwd=ROOT)


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no_such_thing"):
        genthermal.no_such_thing  # noqa: B018


def test_the_api_reference_documents_every_export():
    page = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    listed = set(re.findall(r"^\.\. auto(?:function|class):: genthermal\.(\w+)$", page, re.MULTILINE))
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
