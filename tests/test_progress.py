"""Progress is shown on a terminal only: pipes, logs, CI and tests see nothing."""

import io
import time

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
