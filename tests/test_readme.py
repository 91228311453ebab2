"""The README is short, points at pages that exist, and its examples run as written."""

import re
import shlex
from pathlib import Path

import pytest

from genthermal import cli

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", README, flags=re.S)


def test_the_readme_fits_on_a_few_screens():
    assert len(README.splitlines()) <= 200


def test_the_quick_start_is_two_commands_the_demo_and_the_tests():
    quick = README[README.index("## Quick start"):]
    commands = [line for line in blocks("bash")[0].splitlines() if line.strip()]
    assert quick.index(blocks("bash")[0]) < quick.index("\n## ", 1)
    assert len(commands) == 2
    assert commands[0].split("#")[0].strip().endswith("genthermal demo")
    assert commands[1].split("#")[0].strip().endswith("python3 -m pytest")


def test_every_genthermal_command_in_the_readme_exists_and_parses():
    parser_commands = set(cli.COMMANDS)
    lines = [line.split("#")[0].strip() for block in blocks("bash") for line in block.splitlines()]
    invocations = [shlex.split(part.strip()) for line in lines for part in line.split("&&")
                   if part.strip().startswith("genthermal ")]
    assert len(invocations) >= 8
    for words in invocations:
        assert words[1] in parser_commands, words
        cli.build_parser(words[1:2]).parse_args(words[1:])  # every option is a real one


def test_every_docs_page_the_readme_names_exists():
    named = set(re.findall(r"`(docs/[\w/.-]+)`", README))
    assert named
    for path in named:
        assert (ROOT / path).exists(), path


def test_every_headline_result_has_a_command_and_a_source():
    table = README[README.index("## Headline results"):]
    rows = [line for line in table.splitlines() if line.startswith("| ") and not line.startswith("| result")]
    assert len(rows) >= 5
    for row in rows:
        cells = [cell.strip() for cell in row.strip("|").split("|")]
        assert cells[2].startswith("`") or "walkthrough" in cells[2], row
        assert cells[3] in ("run for this README", "previous README"), row


@pytest.mark.slow
@pytest.mark.parametrize("index", range(len(blocks("python"))))
def test_the_python_examples_run_as_written(index, capsys):
    exec(compile(blocks("python")[index], f"README python block {index}", "exec"), {})
    out = capsys.readouterr().out
    assert "°C" in out
