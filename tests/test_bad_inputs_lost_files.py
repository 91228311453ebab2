"""No lost file: the seven ways a careless user lost one, each refused or made harmless.

1. an input (``--plant``, a baseline, a scenario file, any file the command line names) as an output;
2.-4. ``--out X --force`` on a device node, a FIFO or a symbolic link (refused by name: the node,
   the pipe and the link's target are left as they were);
5. SIGTERM during ``codegen`` (no hidden half-written folder is left);
6. Ctrl-C during ``demo`` (the folder it says it left empty is empty: it does not exist);
7. two runs on one output without ``--force`` (at most one claims success; the other says why).
"""

import os
import shutil
import signal
import stat
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from genthermal.cli import main
from genthermal.errors import InputError
from genthermal.outputs import replacing, replacing_folder, replacing_policy

ROOT = Path(__file__).resolve().parents[1]


def run_cli(argv, capsys):
    code = main([str(a) for a in argv])
    return code, capsys.readouterr().err


# --- 1. inputs are never outputs ------------------------------------------------------------------
@pytest.mark.parametrize("command", ["plan", "fly"])
def test_the_plant_file_is_never_an_output(command, tmp_path, capsys):
    plant = tmp_path / "plant.yaml"
    plant.write_text("machine: genco_rf201a\nparameters:\n  h_end_air: {value: 15.0}\n")
    before = plant.read_bytes()
    code, err = run_cli([command, "blockage_large", "--plant", plant, "--json", plant, "--force"], capsys)
    assert code == 2 and "is also an input" in err and "--json" in err
    assert plant.read_bytes() == before


def test_a_scenario_file_and_a_baseline_are_never_outputs(tmp_path, capsys):
    scenario = tmp_path / "mission.yaml"
    scenario.write_text("name: m\nactions:\n  - {load_percent: 50, duration_min: 10}\n")
    code, err = run_cli(["simulate", scenario, "--out", tmp_path / "x.csv", "--plot", scenario, "--force"], capsys)
    assert code == 2 and "is also an input" in err
    healthy = tmp_path / "healthy.csv"
    healthy.write_text("not even read")
    code, err = run_cli(["diagnose", tmp_path / "faulty.csv", "--baseline", healthy, "--json", healthy, "--force"],
                        capsys)
    assert code == 2 and "is also an input" in err and healthy.read_text() == "not even read"


def test_any_existing_file_the_command_line_names_is_protected(tmp_path, capsys):
    """A trusted machine file (like any future input option) is protected without being listed."""
    machine = tmp_path / "motor.py"
    machine.write_text("MACHINE = None\n")
    code, err = run_cli(["plan", "blockage_large", "--trust-machine", machine, "--json", machine, "--force"], capsys)
    assert code == 2 and "is also an input" in err and machine.read_text() == "MACHINE = None\n"


# --- 2.-4. --force replaces regular files only ----------------------------------------------------------
def _device(path: Path) -> Path:
    try:
        os.mknod(path, stat.S_IFCHR | 0o600, os.makedev(1, 3))  # a copy of /dev/null's node
    except PermissionError:
        pytest.skip("creating a device node needs root")
    return path


@pytest.mark.parametrize("kind", ["device", "fifo", "symlink", "dangling symlink"])
def test_force_never_replaces_a_device_a_fifo_or_a_link(kind, tmp_path, capsys):
    target = tmp_path / "precious.csv"
    target.write_text("precious\n")
    out = tmp_path / "out.csv"
    if kind == "device":
        _device(out)
    elif kind == "fifo":
        os.mkfifo(out)
    elif kind == "symlink":
        out.symlink_to(target)
    else:
        out.symlink_to(tmp_path / "nowhere.csv")
    before = os.lstat(out)
    code, err = run_cli(["simulate", "step_rated", "--out", out, "--force"], capsys)
    assert code == 2 and "regular files only" in err and str(out) in err
    after = os.lstat(out)
    assert (after.st_mode, after.st_ino) == (before.st_mode, before.st_ino)
    assert target.read_text() == "precious\n" and not (tmp_path / "nowhere.csv").exists()


def test_a_link_put_in_place_while_a_file_is_written_is_not_replaced(tmp_path):
    target = tmp_path / "precious.txt"
    target.write_text("precious")
    out = tmp_path / "out.txt"
    with pytest.raises(InputError, match="symbolic link"):
        with replacing(out) as temporary:
            temporary.write_text("new")
            out.symlink_to(target)
    assert out.is_symlink() and target.read_text() == "precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.txt", "precious.txt"]  # no temporary left


# --- 5.-6. a folder is written whole or not at all, under SIGTERM and Ctrl-C --------------------------------
def _stop_when(argv, folder: Path, ready, stop_signal, cwd: Path, timeout_s: float = 60.0, attempts: int = 3):
    """Run the CLI in a subprocess, send ``stop_signal`` once ``ready(temporary folders)`` holds.

    On a loaded machine the command can finish between two looks at its folder, or the signal can
    arrive only once its output is in place (while the interpreter exits); such an attempt stopped
    nothing, so its output is removed and the command run again (at most ``attempts`` times).
    """
    environment = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""),
                   "MPLBACKEND": "Agg"}
    for _ in range(attempts):
        process = subprocess.Popen([sys.executable, "-m", "genthermal.cli", *map(str, argv)], cwd=cwd,
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=environment)
        started = time.monotonic()
        while time.monotonic() - started < timeout_s and process.poll() is None:
            temporary = list(folder.parent.glob(f".{folder.name}.*"))
            if temporary and ready(temporary):
                break
            time.sleep(0.02)
        if process.poll() is None:
            process.send_signal(stop_signal)
            _, err = process.communicate(timeout=60)
            if not folder.exists():  # stopped during the work: what the test is about
                return process.returncode, err
        else:
            process.communicate()
            assert process.returncode == 0, f"the command failed before it could be stopped: {process.returncode}"
        assert not list(folder.parent.glob(f".{folder.name}.*")), "a finished run left its temporary folder"
        shutil.rmtree(folder)
    raise AssertionError(f"the command ended before it could be stopped, {attempts} times")


def test_a_second_interrupt_during_cleanup_still_removes_the_temporary_folder(tmp_path, monkeypatch):
    """A stop signal pending while a first interrupt unwinds must not leave the hidden folder behind."""
    real_rmtree, calls = shutil.rmtree, []

    def interrupted_once(path, *args, **kwargs):
        calls.append(path)
        if len(calls) == 1:
            raise KeyboardInterrupt
        return real_rmtree(path, *args, **kwargs)

    monkeypatch.setattr("genthermal.outputs.shutil.rmtree", interrupted_once)
    with pytest.raises(KeyboardInterrupt):
        with replacing_folder(tmp_path / "report") as temporary:
            (temporary / "plot.png").write_bytes(b"half")
            raise KeyboardInterrupt
    assert len(calls) == 2 and list(tmp_path.iterdir()) == []


def test_a_second_interrupt_during_cleanup_still_removes_the_temporary_file(tmp_path, monkeypatch):
    real_unlink, calls = os.unlink, []

    def interrupted_once(path, *args, **kwargs):
        calls.append(path)
        if len(calls) == 1:
            raise KeyboardInterrupt
        return real_unlink(path, *args, **kwargs)

    monkeypatch.setattr("genthermal.outputs.os.unlink", interrupted_once)
    with pytest.raises(KeyboardInterrupt):
        with replacing(tmp_path / "result.csv") as temporary:
            temporary.write_text("half")
            raise KeyboardInterrupt
    assert len(calls) == 2 and list(tmp_path.iterdir()) == []


def test_sigterm_during_codegen_leaves_no_half_written_folder(tmp_path, tmp_path_factory, monkeypatch):
    # An empty compile cache: with the library already cached, codegen ends milliseconds after its
    # temporary folder appears, and on a loaded machine the signal can arrive after a clean exit.
    monkeypatch.setenv("GENTHERMAL_CACHE_DIR", str(tmp_path_factory.mktemp("empty-cache")))
    out = tmp_path / "generated"
    code, err = _stop_when(["codegen", "--out", out, "--no-kalman"], out, lambda found: True,
                           signal.SIGTERM, tmp_path)
    assert code == 128 + signal.SIGTERM and "SIGTERM" in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def test_an_interrupt_inside_code_run_from_a_string_still_exits_130(tmp_path):
    """CPython notes a KeyboardInterrupt that ends ``exec`` of source text (a dataclass being made,
    sympy parsing) and, under ``python -m``, ended the process by SIGINT itself after the handler
    (the demo's Ctrl-C once exited -SIGINT); the handler forgets that note."""
    machine = tmp_path / "interrupted_machine.py"
    machine.write_text('exec("raise KeyboardInterrupt")\n', encoding="utf-8")
    environment = {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    done = subprocess.run([sys.executable, "-m", "genthermal.cli", "describe", "--model", str(machine)],
                          capture_output=True, text=True, env=environment, timeout=120)
    assert done.returncode == 130 and "interrupted" in done.stderr, (done.returncode, done.stderr)


def test_ctrl_c_that_a_native_solver_takes_still_stops_the_command(tmp_path, monkeypatch, capsys):
    """CasADi's IPOPT takes a Ctrl-C as a failed solve and returns (status NonIpopt_Exception_Thrown):
    calibrate went on, exited 0 and wrote the interrupted fit. The command line notes the Ctrl-C."""
    import genthermal.diagnose.multi_record as multi_record
    from genthermal.resources import BENCH_MOTOR_DIR

    real_fit = multi_record.fit_records

    def solver_takes_the_interrupt(*args, **kwargs):
        try:
            signal.raise_signal(signal.SIGINT)  # Ctrl-C during the solve ...
        except KeyboardInterrupt:
            pass  # ... which the solver takes, returning what it has
        return real_fit(*args, **kwargs)

    monkeypatch.setattr(multi_record, "fit_records", solver_takes_the_interrupt)
    out = tmp_path / "fit.yaml"
    code = main(["calibrate", "--model", str(BENCH_MOTOR_DIR / "ipmsm_machine.py"),
                 str(BENCH_MOTOR_DIR / "id_9_first_3000s.csv"), "--params", "G_jacket", "--fit-step", "60",
                 "--out", str(out)])
    assert code == 130 and "interrupted" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []  # neither the model file nor its temporary sibling
    with replacing(tmp_path / "after.txt") as temporary:  # the next write, outside a command, is not refused
        temporary.write_text("ok")
    assert (tmp_path / "after.txt").read_text() == "ok"


def test_ctrl_c_during_demo_leaves_no_plot_behind(tmp_path):
    out = tmp_path / "demo"
    code, err = _stop_when(["demo", "--quick", "--out", out], out,
                           lambda found: any(f.glob("*.png") for f in found), signal.SIGINT, tmp_path)
    assert code == 130 and "interrupted" in err and "Traceback" not in err, (code, err)
    assert list(tmp_path.iterdir()) == []  # neither the folder nor its temporary sibling


# --- 7. concurrent runs on one output ---------------------------------------------------------------------
def test_a_file_that_appears_meanwhile_is_not_replaced_without_force(tmp_path):
    out = tmp_path / "result.csv"
    with replacing_policy(False), pytest.raises(InputError, match="another run"):
        with replacing(out) as temporary:
            temporary.write_text("second run")
            out.write_text("first run")
    assert out.read_text() == "first run" and list(tmp_path.iterdir()) == [out]
    with replacing_policy(True), replacing(out) as temporary:  # --force: replaced on purpose
        temporary.write_text("forced")
    assert out.read_text() == "forced"


def test_a_folder_filled_meanwhile_is_not_merged_without_force(tmp_path):
    out = tmp_path / "report"
    with replacing_policy(False), pytest.raises(InputError, match="another run"):
        with replacing_folder(out) as temporary:
            (temporary / "report.md").write_text("second run")
            out.mkdir()
            (out / "report.md").write_text("first run")
    assert (out / "report.md").read_text() == "first run" and list(tmp_path.iterdir()) == [out]


def test_two_concurrent_runs_on_one_output_cannot_both_succeed(tmp_path, monkeypatch, capsys):
    """Both runs pass the start-up check (neither has written yet) and meet before moving their file
    into place: exactly one succeeds, the other says why and leaves the first one's file."""
    from genthermal import outputs

    out = tmp_path / "mission.csv"
    meet = threading.Barrier(2, timeout=60)
    move = outputs._move_file_into_place
    # CasADi's symbolic core is not thread-safe: the runs take turns at building and simulating
    # the model (one holds ``computing`` until its file is ready) and meet only to move it.
    computing = threading.Lock()

    def move_after_both_worked(temporary, path):
        computing.release()
        meet.wait()
        move(temporary, path)

    def one_run():
        assert computing.acquire(timeout=120)
        codes.append(main(["simulate", "step_rated", "--out", str(out), "--dt", "600"]))

    monkeypatch.setattr(outputs, "_move_file_into_place", move_after_both_worked)
    codes = []
    runs = [threading.Thread(target=one_run) for _ in range(2)]
    for run in runs:
        run.start()
    for run in runs:
        run.join(timeout=120)
    assert sorted(codes) == [0, 2]
    assert "another run" in capsys.readouterr().err
    assert out.is_file() and [p.name for p in tmp_path.iterdir()] == [out.name]
