"""Bad command-line options, and the CLI's promises: one table row per case.

Exit codes (genthermal/cli.py): 0 ok, 2 bad input, 130 interrupted, 141 closed pipe, 1 internal
error with a bug-report hint. No traceback ever reaches the user, no option is abbreviated, no
output replaces an input, an existing file or a half-written one.
"""

import subprocess
import sys

import pandas as pd
import pytest

from genthermal import __version__
from genthermal.cli import build_parser, main

# (case, argv with {rig} = a valid data file and {out} = a fresh output folder, text the error must contain)
BAD_OPTIONS = [
    ("abbreviated option", ["calibrate", "{rig}", "--param", "R0"], "required: --params"),
    ("abbreviated --out", ["simulate", "step_rated", "--ou", "{out}/x.csv"], "required: --out"),
    ("unknown option", ["simulate", "step_rated", "--out", "{out}/x.csv", "--speed", "2"], "unrecognized"),
    ("unknown command", ["simulat", "step_rated"], "invalid choice"),
    ("--dt zero", ["simulate", "step_rated", "--out", "{out}/x.csv", "--dt", "0"], "--dt"),
    ("--dt nan", ["simulate", "step_rated", "--out", "{out}/x.csv", "--dt", "nan"], "--dt"),
    ("--dt inf", ["simulate", "step_rated", "--out", "{out}/x.csv", "--dt", "inf"], "--dt"),
    ("--dt of a microsecond", ["simulate", "step_rated", "--out", "{out}/x.csv", "--dt", "1e-6"], "samples"),
    ("--dt longer than the record", ["estimate", "{rig}", "--dt", "1e9"], "dt_s"),
    ("output is the input", ["estimate", "{rig}", "--json", "{rig}"], "is also an input"),
    ("output is the input, forced", ["estimate", "{rig}", "--json", "{rig}", "--force"], "is also an input"),
    ("two outputs, one file", ["simulate", "step_rated", "--out", "{out}/x.png", "--plot", "{out}/x.png"],
     "give each output its own name"),
    ("existing output", ["synth", "step_rated", "--out", "{rig}"], "--force"),
    ("output is a folder", ["simulate", "step_rated", "--out", "{out}"], "is a folder"),
    ("plot with a text suffix", ["simulate", "step_rated", "--out", "{out}/x.csv", "--plot", "{out}/p.txt"],
     "suffixes"),
    ("report folder not empty", ["compare", "{rig}", "--report", "{full}"], "not empty"),
    ("codegen into a full folder", ["codegen", "--out", "{full}"], "not empty"),
    ("seed negative", ["synth", "step_rated", "--out", "{out}/x.csv", "--seed", "-1"], "--seed"),
    ("seed text", ["synth", "step_rated", "--out", "{out}/x.csv", "--seed", "abc"], "--seed"),
    ("noise variance 1e300", ["synth", "step_rated", "--out", "{out}/x.csv", "--noise-iron", "1e300"],
     "--noise-iron"),
    ("current noise 300 %", ["synth", "step_rated", "--out", "{out}/x.csv", "--current-noise", "3"],
     "--current-noise"),
    ("noise nan", ["synth", "step_rated", "--out", "{out}/x.csv", "--noise-winding", "nan"], "--noise-winding"),
    ("variant unknown", ["describe", "--variant", "cubic"], "--variant"),
    ("parameter without value", ["describe", "--param", "R0"], "NAME=VALUE"),
    ("parameter not physical", ["describe", "--param", "R0=-1"], "R0"),
    ("predict steps a billion", ["codegen", "--out", "{out}/g", "--predict-steps", "1e9"], "--predict-steps"),
    ("predict steps fractional", ["codegen", "--out", "{out}/g", "--predict-steps", "1.5"], "predict_steps"),
    ("prediction start text", ["estimate", "{rig}", "--predict-from", "soon"], "--predict-from"),
    ("min improvement negative", ["estimate", "{rig}", "--min-improvement", "-1"], "--min-improvement"),
    ("sysid order range reversed", ["sysid", "{rig}", "{rig}", "--na", "3-1"], "--na"),
    ("calibrate unknown parameter", ["calibrate", "{rig}", "--params", "R9"], "R9"),
    ("data file missing", ["compare", "{out}/none.csv"], "none.csv"),
    ("data file is a folder", ["compare", "{out}"], "Is a directory"),
    ("scheduler unknown", ["plan", "blockage_large", "--scheduler", "magic"], "--scheduler"),
    ("fly with a negative seed", ["fly", "blockage_large", "--seed", "-1"], "--seed"),
    ("management cycle of a millisecond", ["plan", "blockage_large", "--cycle-min", "1e-5"], "--cycle-min"),
    ("only commas as parameter names", ["calibrate", "{rig}", "--params", ",,"], "--params = ',,'"),
    ("a data file as the scenario", ["simulate", "{rig}", "--out", "{out}/x.csv"], "characters)"),
    ("--dt beyond a double", ["simulate", "step_rated", "--out", "{out}/x.csv", "--dt", "1e400"], "--dt"),
    ("parameter beyond a double", ["describe", "--param", "R0=1e999"], "finite"),
    ("diagnose with no worker", ["diagnose", "{rig}", "--workers", "0"], "workers"),
    ("diagnose workers as text", ["diagnose", "{rig}", "--workers", "two"], "--workers"),
    ("diagnose phases unknown", ["diagnose", "{rig}", "--phases", "split"], "--phases"),
    ("rest budget negative", ["fly", "blockage_large", "--rest-budget-min", "-3"], "--rest-budget-min"),
    ("rest budget nan", ["fly", "blockage_large", "--rest-budget-min", "nan"], "--rest-budget-min"),
    ("model file that does not exist", ["describe", "--model", "{out}/machine.py"], "machine.py"),
]


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    path = tmp_path_factory.mktemp("rig") / "rig.csv"
    assert main(["synth", "step_rated", "--out", str(path), "--dt", "30"]) == 0
    return path


@pytest.mark.parametrize("argv, named", [c[1:] for c in BAD_OPTIONS], ids=[c[0] for c in BAD_OPTIONS])
def test_bad_option_exits_2_naming_it(argv, named, rig, tmp_path, capsys):
    full = tmp_path / "full"
    full.mkdir()
    (full / "keep.txt").write_text("keep")
    before = rig.read_bytes()
    argv = [a.format(rig=rig, out=tmp_path, full=full) for a in argv]
    try:
        code = main(argv)
    except SystemExit as stop:  # argparse's own usage errors
        code = stop.code
    err = capsys.readouterr().err
    assert code == 2 and named in err and "Traceback" not in err
    assert rig.read_bytes() == before and (full / "keep.txt").read_text() == "keep"
    assert {p.name for p in tmp_path.iterdir()} == {"full"}  # nothing written


def test_every_parser_refuses_abbreviations():
    parser = build_parser()
    subparsers = next(a for a in parser._actions if a.dest == "command").choices
    assert not parser.allow_abbrev and all(not p.allow_abbrev for p in subparsers.values())


def test_version(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0 and capsys.readouterr().out.strip() == f"genthermal {__version__}"


def test_force_replaces_an_existing_output(tmp_path):
    out = tmp_path / "sim.csv"
    out.write_text("old")
    assert main(["simulate", "step_rated", "--out", str(out), "--force"]) == 0
    assert list(pd.read_csv(out).columns)[0] == "time_s"


def test_ctrl_c_exits_130_and_keeps_the_old_file(tmp_path, monkeypatch, capsys):
    out = tmp_path / "sim.csv"
    out.write_text("the previous result\n")

    def interrupted_write(frame, path, *args, **kwargs):
        with open(path, "w") as file:
            file.write("time_s,I_u\n0,")  # half a file, then Ctrl-C
        raise KeyboardInterrupt

    monkeypatch.setattr(pd.DataFrame, "to_csv", interrupted_write)
    assert main(["simulate", "step_rated", "--out", str(out), "--force"]) == 130
    assert "interrupted" in capsys.readouterr().err
    assert out.read_text() == "the previous result\n"
    assert [p.name for p in tmp_path.iterdir()] == ["sim.csv"]  # no temporary file left


def test_internal_error_exits_1_with_a_bug_hint_and_no_traceback(tmp_path, monkeypatch, capsys):
    import genthermal.commands.describe as describe

    monkeypatch.setattr(describe, "model_from_args", lambda args: 1 / 0)
    assert main(["describe"]) == 1
    err = capsys.readouterr().err
    assert "internal error: ZeroDivisionError" in err and "bug" in err and "Traceback" not in err
    saved = err.rsplit("traceback saved in ", 1)[1].strip()
    assert "ZeroDivisionError" in open(saved).read()


def test_closed_pipe_ends_quietly():
    command = [sys.executable, "-c", "import sys; from genthermal.cli import main; sys.exit(main(['describe']))"]
    with subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE) as process:
        process.stdout.readline()
        process.stdout.close()  # like `| head -1`
        err = process.stderr.read().decode()
        code = process.wait(timeout=120)
    assert "Traceback" not in err and "Error" not in err
    assert code in (0, 141)  # 0 if describe finished writing before the pipe closed
