"""Progress is shown on a terminal only: pipes, logs, CI and tests see nothing."""

import io
import time

import pytest

from genthermal import progress


class FakeTerminal(io.StringIO):
    def isatty(self):
        return True


def test_quiet_when_stderr_is_not_a_terminal(capsys):
    with progress.working("diagnose"):
        time.sleep(0.01)
    assert capsys.readouterr().err == ""


def test_shown_on_a_terminal_and_removed_at_the_end(monkeypatch):
    terminal = FakeTerminal()
    monkeypatch.setattr("sys.stderr", terminal)
    monkeypatch.delenv("GENTHERMAL_PROGRESS", raising=False)
    with progress.working("diagnose"):
        time.sleep(progress.REFRESH_S * 1.5)
    text = terminal.getvalue()
    assert "diagnose: working" in text and "elapsed" in text
    assert text.endswith("\r")  # the line is cleared, not left behind
    monkeypatch.setenv("GENTHERMAL_PROGRESS", "0")
    assert not progress.enabled()


def test_a_counter_is_a_bar_on_a_terminal_only(monkeypatch, capsys):
    monkeypatch.delenv("GENTHERMAL_PROGRESS", raising=False)
    with progress.counter(3, "cases") as bar:  # stderr captured: not a terminal
        bar.update(3)
    assert capsys.readouterr().err == ""
    terminal = FakeTerminal()
    monkeypatch.setattr("sys.stderr", terminal)
    with progress.counter(3, "cases") as bar:
        bar.update(3)
    assert "cases" in terminal.getvalue() and "3/3" in terminal.getvalue()
    with progress.counter(3, "hidden", show=False) as bar:  # the caller's own switch
        bar.update(3)
    assert "hidden" not in terminal.getvalue()


def test_one_switch_silences_every_kind_of_progress_on_a_terminal(monkeypatch):
    """``quiet()`` (``genthermal --quiet``) and ``GENTHERMAL_PROGRESS=0`` turn off the tqdm bar,
    the elapsed-time display and the progress lines alike; the environment is restored after."""
    terminal = FakeTerminal()
    monkeypatch.setattr("sys.stderr", terminal)
    monkeypatch.delenv("GENTHERMAL_PROGRESS", raising=False)
    assert progress.enabled()
    with progress.quiet():
        assert not progress.enabled()
        with progress.counter(2, "cases") as bar:
            bar.update(2)
        with progress.working("diagnose"):
            time.sleep(progress.REFRESH_S * 1.5)
        progress.say("a line")
    assert terminal.getvalue() == "" and "GENTHERMAL_PROGRESS" not in __import__("os").environ
    monkeypatch.setenv("GENTHERMAL_PROGRESS", "0")
    with progress.counter(2, "cases") as bar:
        bar.update(2)
    progress.say("a line")
    assert terminal.getvalue() == ""


@pytest.mark.parametrize("argv", [["--quiet", "describe"], ["describe", "--quiet"]])
def test_quiet_before_or_after_the_command(argv, monkeypatch):
    """The command runs with progress off (its worker processes inherit GENTHERMAL_PROGRESS=0)."""
    import os

    import genthermal.commands.describe as describe
    from genthermal.cli import main

    seen = {}
    monkeypatch.setattr("sys.stderr", FakeTerminal())
    monkeypatch.delenv("GENTHERMAL_PROGRESS", raising=False)
    monkeypatch.setattr(describe, "run", lambda args: seen.update(enabled=progress.enabled(),
                                                                  env=os.environ.get("GENTHERMAL_PROGRESS")) or 0)
    assert main(argv) == 0
    assert seen == {"enabled": False, "env": "0"} and progress.enabled()
    assert main(["describe"]) == 0 and seen["enabled"] is True


def test_a_command_writes_only_its_result_lines_into_a_log(tmp_path, monkeypatch, capsys):
    """Not a terminal (a log, CI), progress switched on in the environment: nothing on stderr,
    only result lines on stdout (no carriage-return redraws)."""
    from pathlib import Path

    from genthermal.cli import main

    record = str(Path(__file__).resolve().parents[1] / "scenarios" / "data" / "hidden_effect_demo.csv")
    monkeypatch.setenv("GENTHERMAL_PROGRESS", "1")
    assert main(["compare", record, record, "--fit-step", "60"]) == 0  # two records: shown as "working" on a tty
    out, err = capsys.readouterr()
    assert err == "" and "\r" not in out and "RMSE" in out


def test_lines_printed_during_work_appear_above_the_display(monkeypatch):
    """stdout and stderr on one terminal (demo, fly): each printed line is whole, on its own line,
    never glued to the elapsed-time display."""
    import sys

    terminal = FakeTerminal()
    monkeypatch.setattr("sys.stderr", terminal)
    monkeypatch.setattr("sys.stdout", terminal)
    monkeypatch.delenv("GENTHERMAL_PROGRESS", raising=False)
    with progress.working("demo part 1 of 2"):
        time.sleep(progress.REFRESH_S * 1.5)
        print("== Mission thesis_fig_7_7 ==")
        print("peak", end="")
        time.sleep(progress.REFRESH_S * 1.5)
        print(" T_winding 96.1 °C")
        print("genthermal demo: warning: a data warning", file=sys.stderr)
    assert sys.stdout is terminal and sys.stderr is terminal  # given back
    screen = terminal.getvalue()
    lines = [line.rsplit("\r", 1)[-1] for line in screen.split("\n")]  # what each line ends up showing
    assert "== Mission thesis_fig_7_7 ==" in lines and "peak T_winding 96.1 °C" in lines
    assert "genthermal demo: warning: a data warning" in lines
    assert "demo part 1 of 2: working" in screen


def _run_in_a_terminal(argv: list[str]) -> str:
    """Run ``python -m genthermal.cli argv`` with stdout and stderr on a pseudo-terminal; return
    everything it drew."""
    import os
    import pty
    import subprocess
    import sys

    leader, follower = pty.openpty()
    env = {**os.environ, "COLUMNS": "100", "LINES": "30"}
    env.pop("GENTHERMAL_PROGRESS", None)
    process = subprocess.Popen([sys.executable, "-m", "genthermal.cli", *argv], stdout=follower, stderr=follower,
                               stdin=subprocess.DEVNULL, env=env, close_fds=True)
    os.close(follower)
    chunks = []
    while True:
        try:
            chunk = os.read(leader, 4096)
        except OSError:  # the terminal closed: the process ended
            break
        if not chunk:
            break
        chunks.append(chunk)
    os.close(leader)
    assert process.wait(timeout=300) == 0
    return b"".join(chunks).decode(errors="replace")


@pytest.mark.slow
def test_a_real_terminal_shows_the_display_and_quiet_removes_it():
    """On a pseudo-terminal ``compare`` of two records shows its elapsed-time display above which
    the result lines appear whole; ``genthermal --quiet`` draws the same lines and no display."""
    from pathlib import Path

    record = str(Path(__file__).resolve().parents[1] / "scenarios" / "data" / "hidden_effect_demo.csv")
    argv = ["compare", record, record, "--fit-step", "60"]
    shown, quiet = _run_in_a_terminal(argv), _run_in_a_terminal(["--quiet", *argv])
    assert "compare: working" in shown and "working" not in quiet
    result = [line.rsplit("\r", 1)[-1] for line in quiet.replace("\r\n", "\n").split("\n") if line.strip()]
    drawn = [line.rsplit("\r", 1)[-1] for line in shown.replace("\r\n", "\n").split("\n") if line.strip()]
    assert result and drawn == result  # every line whole, none glued to the display
