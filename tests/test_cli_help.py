"""``genthermal --help`` is light, and every command's help names where to read more."""

import importlib
import subprocess
import sys
from pathlib import Path

import pytest

from genthermal import cli

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("matplotlib.pyplot", "sympy", "casadi", "pandas", "scipy", "dask", "tqdm")


def test_top_level_help_imports_no_heavy_library():
    code = ("import sys\nfrom genthermal.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
            f"print('imported:', ','.join(m for m in {HEAVY!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert "usage: genthermal" in out.stdout
    assert out.stdout.strip().splitlines()[-1] == "imported:"


def test_top_level_help_lists_every_command_and_the_documentation(capsys):
    with pytest.raises(SystemExit) as exit_:
        cli.main(["--help"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out
    for name in cli.COMMANDS:
        assert name in out
    assert "docs/" in out


def test_each_command_summary_is_the_one_its_module_registers():
    """The light listing repeats each command's summary; it must not drift from the module's."""
    full = cli.build_parser()
    choices = next(a for a in full._actions if a.dest == "command")
    registered = {action.dest: action.help for action in choices._choices_actions}
    assert registered == {name: summary for name, (_, summary, _) in cli.COMMANDS.items()}


@pytest.mark.parametrize("name", list(cli.COMMANDS))
def test_each_command_help_names_an_existing_documentation_page(name, capsys):
    with pytest.raises(SystemExit):
        cli.main([name, "--help"])
    out = capsys.readouterr().out
    page = cli.COMMANDS[name][2]
    assert f"read more: docs/{page}" in " ".join(out.split())
    assert (ROOT / "docs" / page).is_file()


def test_command_modules_register_the_names_of_the_table():
    for name, (module, _, _) in cli.COMMANDS.items():
        assert hasattr(importlib.import_module(f"genthermal.commands.{module}"), "register"), name
