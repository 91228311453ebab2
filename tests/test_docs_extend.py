"""The tutorial "Your own machine and a new effect" runs as written: a user effect and a user machine."""

import re
from pathlib import Path

import pytest

from genthermal import effects

TUTORIAL = Path(__file__).resolve().parents[1] / "docs" / "tutorials" / "own-machine.md"


def extend_blocks() -> list[str]:
    """The tutorial's code cells, the machine file without its ``%%writefile`` line."""
    cells = re.findall(r"```\{code-cell\} ipython3\n(.*?)```", TUTORIAL.read_text(encoding="utf-8"), flags=re.S)
    return [re.sub(r"\A%%writefile \S+\n", "", cell) for cell in cells]


@pytest.fixture
def user_effect_registered(monkeypatch):
    """The tutorial registers its effect into a private copy of the registry: the package's is
    never changed, so no test has to undo it."""
    monkeypatch.setattr(effects, "CATALOGUE", dict(effects.CATALOGUE))


def test_the_extend_it_code_runs(tmp_path, monkeypatch, capsys, user_effect_registered):
    effect_code, machine_file, usage = extend_blocks()
    assert machine_file.startswith("# my_motor.py")
    exec(compile(effect_code, "tutorial effect", "exec"), {})
    assert effects.CATALOGUE["winding_ac_loss"].needs
    (tmp_path / "my_motor.py").write_text(machine_file)
    monkeypatch.chdir(tmp_path)
    exec(compile(usage, "tutorial machine", "exec"), {})
    coil, applicable = capsys.readouterr().out.strip().splitlines()
    # at rated current: 10 A^2 * R0 (1 + alpha theta) through 1/8 + 1/12 K/W above 25 degC
    theta = 25.0
    for _ in range(50):
        theta = 25.0 + 100.0 * 0.5 * (1 + 0.00393 * theta) * (1 / 8 + 1 / 12)
    assert float(coil.strip("[]")) == pytest.approx(theta, rel=1e-9)
    assert "winding_ac_loss" in applicable and "winding_insulation_degradation" not in applicable


def test_the_cli_describes_the_tutorial_machine(tmp_path, monkeypatch, capsys):
    from genthermal.cli import main

    (tmp_path / "my_motor.py").write_text(extend_blocks()[1])
    monkeypatch.chdir(tmp_path)
    assert main(["describe", "--model", "my_motor.py"]) == 0
    out = capsys.readouterr().out
    assert "my_motor" in out and "T_coil = node winding" in out and "limit 130 °C" in out
