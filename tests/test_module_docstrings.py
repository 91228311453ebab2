"""Every module of genthermal says in a few lines what it does; history and measured figures live elsewhere."""

import ast
import re
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "genthermal"
MAX_DOCSTRING_LINES = 12
#: A commit hash (7-40 hex digits with both a digit and a letter) or an issue number.
HISTORY = re.compile(r"\b(?=[0-9a-f]*[0-9])(?=[0-9a-f]*[a-f])[0-9a-f]{7,40}\b|\bissues?\s*#?\d+|\bcommit\b",
                     re.IGNORECASE)


def module_paths():
    return sorted(path for path in PACKAGE.rglob("*.py") if "__pycache__" not in path.parts)


def relative(path: Path) -> str:
    return path.relative_to(PACKAGE.parent).as_posix()


def module_docstring(path: Path) -> str | None:
    return ast.get_docstring(ast.parse(path.read_text(encoding="utf-8")), clean=True)


def docstring_problems(docstring: str | None) -> list[str]:
    """What is wrong with one module docstring (an empty list when nothing is)."""
    if not docstring or not docstring.strip():
        return ["no module docstring"]
    problems = []
    lines = docstring.strip().splitlines()
    if len(lines) > MAX_DOCSTRING_LINES:
        problems.append(f"{len(lines)} lines (at most {MAX_DOCSTRING_LINES})")
    problems += [f"history in a docstring: {match.group(0)!r}" for match in HISTORY.finditer(docstring)]
    return problems


@pytest.mark.parametrize("path", module_paths(), ids=relative)
def test_a_module_docstring_says_in_a_few_lines_what_the_module_does(path):
    problems = docstring_problems(module_docstring(path))
    assert not problems, f"{relative(path)}: {'; '.join(problems)}"


@pytest.mark.parametrize("path", module_paths(), ids=relative)
def test_the_pages_a_module_docstring_points_to_exist(path):
    named = re.findall(r"\bdocs/[\w/.-]+\.md\b", module_docstring(path) or "")
    missing = [page for page in named if not (PACKAGE.parent / page).is_file()]
    assert not missing, f"{relative(path)} points to missing pages: {missing}"


@pytest.mark.parametrize("docstring, problem", [
    (None, "no module docstring"),
    ("\n".join(["Summary line."] + ["more"] * MAX_DOCSTRING_LINES), "lines"),
    ("Summary.\n\nThe fix came with commit 9399c62.", "9399c62"),
    ("Summary.\n\nSee issue 32 for the history.", "issue 32"),
])
def test_the_check_catches_long_docstrings_and_history(docstring, problem):
    assert any(problem in p for p in docstring_problems(docstring))


def test_the_check_passes_a_short_docstring_with_words_that_look_like_hex():
    assert docstring_problems("Summary: a decade of added effects.\n\nSee ``docs/guide/methods.md``.") == []
