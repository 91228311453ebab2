"""Machines are plug-ins: a built-in name, an entry point of group genthermal.machines, or a .py file."""

import importlib
import sys
import textwrap

import pytest

from genthermal.errors import InputError
from genthermal.machines import build_model, known_machines, resolve_machine
from genthermal.machines.genco_rf201a import MACHINE as GENCO
from genthermal.machines.registry import ENTRY_POINT_GROUP
from genthermal.model_file import load_model, model_document

#: A user's machine file: the thesis generator under another name, built without touching genthermal/.
MACHINE_FILE = textwrap.dedent('''
    import dataclasses
    from genthermal.machines.genco_rf201a import MACHINE as GENCO

    MACHINE = dataclasses.replace(GENCO, name="{name}")
    OTHER = "not a machine"
''')


@pytest.fixture
def machine_file(tmp_path):
    path = tmp_path / "my_generator.py"
    path.write_text(MACHINE_FILE.format(name="my_generator"))
    return path


@pytest.fixture
def installed_plugin(tmp_path, monkeypatch):
    """A package with an entry point in genthermal.machines, found on sys.path (no pip install)."""
    (tmp_path / "plugin_machines.py").write_text(MACHINE_FILE.format(name="plugin_generator"))
    dist = tmp_path / "plugin_machines-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: plugin-machines\nVersion: 1.0\n")
    (dist / "entry_points.txt").write_text(f"[{ENTRY_POINT_GROUP}]\nplugin_generator = plugin_machines:MACHINE\n"
                                           "broken_generator = plugin_machines:NO_SUCH_NAME\n"
                                           "wrong_generator = plugin_machines:OTHER\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    importlib.invalidate_caches()
    yield
    sys.modules.pop("plugin_machines", None)


def test_a_built_in_name_resolves():
    assert resolve_machine("genco_rf201a") is GENCO


def test_a_machine_file_builds_a_model_without_changing_the_package(machine_file):
    model = build_model(str(machine_file))
    assert model.spec.name == "my_generator" and model.n_states == 8
    linear = load_model(f"{machine_file}:linear")
    assert linear.spec.variant == "linear" and linear.spec.machine_source == str(machine_file)
    assert model_document(load_model(str(machine_file)))["machine"] == str(machine_file)
    assert resolve_machine(f"{machine_file}:MACHINE").name == "my_generator"


def test_an_entry_point_machine_is_found_by_name(installed_plugin):
    assert "plugin_generator" in known_machines()
    model = load_model("plugin_generator")
    assert model.spec.name == "plugin_generator"
    assert model_document(model)["machine"] == "plugin_generator"


@pytest.mark.parametrize("reference, field, words", [
    ("no_such_machine", "machine", "unknown machine; known: genco_rf201a"),
    ("missing/machine.py", "machine file", "no such file"),
])
def test_bad_references_name_the_value(reference, field, words):
    with pytest.raises(InputError) as error:
        resolve_machine(reference)
    assert error.value.field == field and reference in str(error.value) and words in error.value.reason


def test_a_file_that_fails_or_defines_no_machine_is_named(tmp_path, machine_file):
    broken = tmp_path / "broken.py"
    broken.write_text("raise RuntimeError('typo in my machine')\n")
    with pytest.raises(InputError, match="broken.py.*failed to run: RuntimeError: typo in my machine"):
        resolve_machine(str(broken))
    with pytest.raises(InputError, match="attribute OTHER is str, not a genthermal.machines.Machine"):
        resolve_machine(f"{machine_file}:OTHER")
    empty = tmp_path / "empty.py"
    empty.write_text("x = 1\n")
    with pytest.raises(InputError, match="attribute MACHINE is NoneType"):
        resolve_machine(str(empty))


def test_a_broken_entry_point_is_named(installed_plugin):
    with pytest.raises(InputError, match="entry point plugin_machines:NO_SUCH_NAME.*failed to load"):
        resolve_machine("broken_generator")
    with pytest.raises(InputError, match="plugin_machines:OTHER is str"):
        resolve_machine("wrong_generator")


def test_the_cli_takes_a_machine_file(machine_file, capsys):
    from genthermal.cli import main

    assert main(["describe", "--model", str(machine_file)]) == 0
    assert "my_generator" in capsys.readouterr().out
