"""Data files never run code, and the compiled-library cache is checked before a library is loaded.

A model file's ``machine:`` (or a scenario's ``generators.machine``) naming a ``.py`` file is
refused before the file runs, however the path is written; the side-effect file the machine file
would create proves that it did not run. Running a machine file needs ``--model FILE.py`` or
``--trust-machine FILE.py``. A cached library or object that was changed is built again.
"""

import os
import stat
import textwrap

import pytest

from genthermal.cli import main
from genthermal.errors import InputError
from genthermal.machines.registry import trusted_machine_files
from genthermal.model_file import load_model

#: A machine file that leaves a mark when it runs, then defines a valid machine.
MARKING_MACHINE = textwrap.dedent('''
    import dataclasses, pathlib
    pathlib.Path({mark!r}).write_text("this machine file ran")
    from genthermal.machines.genco_rf201a import MACHINE as GENCO
    MACHINE = dataclasses.replace(GENCO, name="marking_generator")
''')


@pytest.fixture
def machine_file(tmp_path):
    folder = tmp_path / "machines"
    folder.mkdir()
    path = folder / "marking.py"
    path.write_text(MARKING_MACHINE.format(mark=str(tmp_path / "RAN")))
    return path


def references(machine_file, model_folder):
    """The same file written as a data file might: relative, absolute, with ../, with :ATTRIBUTE."""
    relative = os.path.relpath(machine_file, model_folder)
    return {"absolute": str(machine_file), "relative with ..": relative,
            "dotted absolute": str(machine_file.parent / ".." / machine_file.parent.name / machine_file.name),
            "with attribute": f"{machine_file}:MACHINE", "linear variant": str(machine_file)}


@pytest.mark.parametrize("form", ["absolute", "relative with ..", "dotted absolute", "with attribute",
                                  "linear variant"])
def test_a_model_file_naming_a_machine_file_is_refused_and_the_file_does_not_run(form, machine_file, tmp_path,
                                                                                 monkeypatch, capsys):
    models = tmp_path / "models"
    models.mkdir()
    monkeypatch.chdir(models)  # a relative path is read from where the user runs genthermal
    reference = references(machine_file, models)[form]
    variant = "variant: linear\n" if form == "linear variant" else ""
    (models / "sent_to_me.yaml").write_text(f"machine: {reference}\n{variant}")
    with pytest.raises(InputError, match="registered machine") as caught:
        load_model(models / "sent_to_me.yaml")
    assert "--trust-machine" in str(caught.value)
    assert main(["describe", "--model", "sent_to_me.yaml"]) == 2
    err = capsys.readouterr().err
    assert "does not run" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "RAN").exists()


def test_a_scenario_naming_a_machine_file_is_refused_and_the_file_does_not_run(machine_file, tmp_path, capsys):
    scenario = tmp_path / "scenario.yaml"
    scenario.write_text(f"name: s\nactions:\n  - {{load_percent: 50, duration_min: 10}}\n"
                        f"generators:\n  count: 2\n  machine: {machine_file}\n")
    assert main(["plan", str(scenario)]) == 2
    assert "generators.machine" in capsys.readouterr().err
    assert not (tmp_path / "RAN").exists()


def test_a_trusted_machine_file_loads_from_a_model_file(machine_file, tmp_path, capsys):
    model_path = tmp_path / "fitted.yaml"
    model_path.write_text(f"machine: {machine_file}\nparameters:\n  R0: {{value: 1.2}}\n")
    with trusted_machine_files([machine_file]):
        assert load_model(model_path).spec.name == "marking_generator"
    assert (tmp_path / "RAN").exists()
    (tmp_path / "RAN").unlink()
    assert main(["describe", "--model", str(model_path), "--trust-machine", str(machine_file)]) == 0
    assert (tmp_path / "RAN").exists()
    with pytest.raises(InputError, match="registered machine"):  # the trust ends with the block
        load_model(model_path)


def test_trusting_one_machine_file_does_not_trust_another(machine_file, tmp_path):
    other = tmp_path / "other.py"
    other.write_text(MARKING_MACHINE.format(mark=str(tmp_path / "OTHER_RAN")))
    model_path = tmp_path / "fitted.yaml"
    model_path.write_text(f"machine: {other}\n")
    with trusted_machine_files([machine_file]), pytest.raises(InputError, match="registered machine"):
        load_model(model_path)
    assert not (tmp_path / "OTHER_RAN").exists()


@pytest.mark.parametrize("given", ["missing.py", "notes.txt"])
def test_trust_names_an_existing_machine_file(given, tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("x")
    assert main(["describe", "--trust-machine", str(tmp_path / given)]) == 2
    assert "--trust-machine" in capsys.readouterr().err


def test_the_command_line_runs_a_machine_file_it_is_given(machine_file, tmp_path):
    assert main(["describe", "--model", str(machine_file)]) == 0
    assert (tmp_path / "RAN").exists()


# --- the compiled-library cache ----------------------------------------------------------------------
@pytest.fixture(scope="module")
def generated(tmp_path_factory):
    from genthermal.ccompile import find_compiler
    from genthermal.codegen import generate_c
    from genthermal.errors import CompilerNotFoundError
    from genthermal.machines import build_model

    try:
        find_compiler()
    except CompilerNotFoundError as exc:
        pytest.skip(f"no C compiler: {exc}")
    return generate_c(build_model(), tmp_path_factory.mktemp("generated"), 10.0, "gtrust")


@pytest.fixture
def cache(tmp_path_factory, monkeypatch):
    folder = tmp_path_factory.getbasetemp() / "trust-cache"
    monkeypatch.setenv("GENTHERMAL_CACHE_DIR", str(folder))
    return folder


def test_the_cache_is_private_and_a_tampered_library_is_rebuilt(generated, cache):
    from genthermal.ccompile import CompiledModel, compile_library

    library = compile_library(generated)
    for folder in (cache, cache / "codegen", cache / "codegen" / "lib", library.parent):
        assert stat.S_IMODE(folder.stat().st_mode) == 0o700, folder
    original = library.read_bytes()
    library.write_bytes(original[: len(original) // 2])  # truncated (or replaced) behind genthermal's back
    rebuilt = compile_library(generated)
    assert rebuilt == library and rebuilt.read_bytes() == original
    assert CompiledModel(rebuilt, generated).n_states == 8


def test_a_tampered_object_is_compiled_again(generated, cache):
    from genthermal.ccompile import compile_library

    library = compile_library(generated)
    objects = sorted((cache / "codegen" / "obj").glob("gtrust_casadi_rhs-*.o"))
    original = objects[0].read_bytes()
    objects[0].write_bytes(b"\x7fELF not the compiled code")
    again = compile_library(generated)
    assert objects[0].read_bytes() == original and again.is_file()


@pytest.mark.parametrize("mode", [0o777, 0o770, 0o722])
def test_a_cache_others_may_write_in_is_refused(mode, generated, tmp_path, monkeypatch):
    from genthermal.ccompile import compile_library

    shared = tmp_path / "shared-cache"
    shared.mkdir()
    shared.chmod(mode)
    monkeypatch.setenv("GENTHERMAL_CACHE_DIR", str(shared))
    with pytest.raises(InputError, match="other users") as caught:
        compile_library(generated)
    assert str(shared) in str(caught.value)
    assert not list(shared.iterdir())  # nothing was built or loaded there
