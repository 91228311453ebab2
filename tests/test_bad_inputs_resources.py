"""Bounded resources and no crash on reachable input: each a clear exit-2 message, never exit 1.

An alias bomb, a 10**400 integer, /dev/zero, an endless pipe, a file over the size limit, a time
stamp of 1e308, a step of 5e-324 s, a two-row diagnosis, a terminal that cannot print "°C".
hypothesis writes the numbers and the YAML.
"""

import io
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from genthermal import input_limits
from genthermal.cli import main
from genthermal.errors import SHOWN_VALUE_CHARS, InputError
from genthermal.measurements import load_measurements
from genthermal.model_file import load_model

ROOT = Path(__file__).resolve().parents[1]


def alias_bomb(levels: int = 30, width: int = 9) -> str:
    """A YAML flow sequence of under 2 kB whose last item stands for width**levels strings."""
    items = ["&a0 [" + ", ".join(["x"] * width) + "]"]
    items += [f"&a{i} [{', '.join([f'*a{i - 1}'] * width)}]" for i in range(1, levels)]
    return "[" + ", ".join(items) + "]"


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    from genthermal.machines import build_model
    from genthermal.mission import load_mission
    from genthermal.synth import synthesize

    path = tmp_path_factory.mktemp("rig") / "rig.csv"
    synthesize(build_model(), load_mission("step_rated"), dt_s=60.0, seed=1).to_csv(path, index=False)
    return path


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    assert "internal error" not in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err
    return err


@pytest.mark.parametrize("where", ["parameter value", "effect parameters", "unknown key", "scenario action"])
def test_an_alias_bomb_in_a_bad_field_gives_a_short_message_quickly(where, tmp_path, capsys):
    bomb = alias_bomb()
    assert len(bomb) < 2000
    text = {"parameter value": f"machine: genco_rf201a\nparameters:\n  h_end_air: {{value: {bomb}}}\n",
            "effect parameters": f"machine: genco_rf201a\neffects:\n  - {{name: coolant_flow_reduction, "
                                 f"parameters: {bomb}}}\n",
            "unknown key": f"machine: genco_rf201a\nbomb: {bomb}\n",
            "scenario action": f"name: m\nactions: {bomb}\n"}[where]
    path = tmp_path / "bomb.yaml"
    path.write_text(text)
    argv = (["simulate", str(path), "--out", str(tmp_path / "x.csv")] if where == "scenario action"
            else ["describe", "--model", str(path)])
    started = time.monotonic()
    assert main(argv) == 2 and time.monotonic() - started < 10.0
    assert len(one_error_line(capsys)) < 1000


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.recursive(st.one_of(st.integers(), st.floats(), st.text(max_size=20), st.none(), st.booleans()),
                    lambda children: st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=5), children,
                                                                                        max_size=4), max_leaves=40))
def test_a_shown_value_is_bounded_whatever_it_is(value):
    message = str(InputError("field", value, "reason"))
    assert len(message) <= len("field = : reason") + SHOWN_VALUE_CHARS + 40


def test_a_shared_structure_a_billion_items_deep_is_shown_in_a_line():
    value = ["x"] * 9
    for _ in range(30):
        value = [value] * 9
    started = time.monotonic()
    message = str(InputError("field", value, "bad"))
    assert time.monotonic() - started < 0.5 and len(message) < 200


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(digits=st.integers(300, 6000), sign=st.sampled_from(["", "-"]),
       field=st.sampled_from(["parameters:\n  h_end_air: {{value: {n}}}",
                              "effects:\n  - {{name: coolant_flow_reduction, "
                              "parameters: {{k_flow: {n}}}, onset_s: {n}}}"]))
def test_huge_yaml_integers_are_refused_not_overflowed(tmp_path_factory, digits, sign, field):
    path = tmp_path_factory.mktemp("int") / "model.yaml"
    path.write_text("machine: genco_rf201a\n" + field.format(n=sign + "1" + "0" * digits) + "\n")
    if digits + 1 > 308:  # more than a float holds: refused while the YAML is read
        with pytest.raises(InputError, match="digits"):
            load_model(path)
        return
    try:  # a float-sized integer: loaded or refused by the field's own range, never an overflow
        load_model(path)
    except InputError:
        pass


def test_a_scenario_integer_of_400_digits_is_refused(tmp_path, capsys):
    path = tmp_path / "m.yaml"
    path.write_text(f"name: m\nactions:\n  - {{load_percent: 50, duration_min: 1{'0' * 400}}}\n")
    assert main(["simulate", str(path), "--out", str(tmp_path / "x.csv")]) == 2
    assert "digits" in one_error_line(capsys)


@pytest.mark.parametrize("argv", [["compare", "/dev/zero"], ["describe", "--model", "/dev/zero"],
                                  ["simulate", "/dev/zero", "--out", "{out}"], ["compare", "/dev/urandom"]])
def test_a_device_is_refused_at_once(argv, tmp_path, capsys):
    if not os.path.exists(argv[1] if argv[1].startswith("/dev") else argv[-1]):
        pytest.skip("no /dev here")
    started = time.monotonic()
    assert main([a.replace("{out}", str(tmp_path / "x.csv")) for a in argv]) == 2
    assert time.monotonic() - started < 10.0
    err = one_error_line(capsys)
    assert "/dev/" in err


def test_an_endless_pipe_is_cut_at_the_limit(tmp_path, monkeypatch):
    monkeypatch.setattr(input_limits, "MAX_RECORD_BYTES", 2**20)
    import genthermal.measurements as measurements

    monkeypatch.setattr(measurements, "MAX_RECORD_BYTES", 2**20)
    fifo = tmp_path / "endless"
    os.mkfifo(fifo)

    def write_forever():
        try:
            with open(fifo, "wb") as pipe:
                while True:
                    pipe.write(b"time_s,I_u\n" * 4096)
        except (BrokenPipeError, OSError):
            pass

    writer = threading.Thread(target=write_forever, daemon=True)
    writer.start()
    with pytest.raises(InputError, match="more than the 1 MiB"):
        load_measurements(fifo)


@pytest.mark.parametrize("what, argv", [("data file", ["compare", "{path}"]),
                                        ("model file", ["describe", "--model", "{path}"]),
                                        ("scenario", ["simulate", "{path}", "--out", "{out}"])])
def test_a_file_over_the_limit_is_refused_before_it_is_read(what, argv, tmp_path, capsys):
    path = tmp_path / ("big.csv" if what == "data file" else "big.yaml")
    with open(path, "wb") as file:
        file.truncate(input_limits.MAX_RECORD_BYTES + 1)  # sparse: no disk, no time
    code = main([a.replace("{path}", str(path)).replace("{out}", str(tmp_path / "x.csv")) for a in argv])
    assert code == 2
    err = one_error_line(capsys)
    assert "MiB" in err and str(path) in err


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(stamp=st.one_of(st.sampled_from(["1e308", "-1e308", "1.7976931348623157e308", "inf", "nan", "1e-320",
                                        "9" * 400, "0x1p1023"]),
                       st.floats(allow_nan=True, allow_infinity=True).map(repr)),
       row=st.integers(0, 200))
def test_any_time_stamp_is_read_or_refused_by_name(rig, stamp, row):
    frame = pd.read_csv(rig, dtype=str)
    frame.loc[row, "time_s"] = stamp
    try:
        load_measurements(io.StringIO(frame.to_csv(index=False)))
    except InputError as error:
        assert "time_s" in str(error)


@pytest.mark.parametrize("argv", [["compare", "{rig}", "--dt", "5e-324"], ["compare", "{rig}", "--dt", "1e-300"],
                                  ["simulate", "step_rated", "--out", "{out}", "--dt", "5e-324"],
                                  ["estimate", "{rig}", "--dt", "5e-324"]])
def test_a_tiny_step_is_refused(argv, rig, tmp_path, capsys):
    assert main([a.replace("{rig}", str(rig)).replace("{out}", str(tmp_path / "x.csv")) for a in argv]) == 2
    assert "samples" in one_error_line(capsys)


def test_diagnose_on_a_two_row_file_says_it_is_too_short(rig, tmp_path, capsys):
    short = tmp_path / "two_rows.csv"
    pd.read_csv(rig).iloc[:2].to_csv(short, index=False)
    assert main(["diagnose", str(short)]) == 2
    assert "at least 30 samples" in one_error_line(capsys)


class _AsciiTerminal(io.TextIOWrapper):
    def __init__(self):
        super().__init__(io.BytesIO(), encoding="ascii")

    def text(self) -> str:
        self.flush()
        return self.buffer.getvalue().decode("ascii")


def test_an_ascii_terminal_gets_ascii_not_a_crash(rig, tmp_path, monkeypatch):
    kelvin = tmp_path / "kelvin.csv"
    frame = pd.read_csv(rig)
    frame[["T_inlet", "T_ambient"]] += 273.15
    frame.to_csv(kelvin, index=False)
    for argv, expected in ((["describe"], 0), (["compare", str(rig)], 0), (["compare", str(kelvin)], 2)):
        out, err = _AsciiTerminal(), _AsciiTerminal()
        monkeypatch.setattr(sys, "stdout", out)
        monkeypatch.setattr(sys, "stderr", err)
        assert main(argv) == expected
        monkeypatch.undo()
        assert "internal error" not in err.text()
        assert "degC" in out.text() + err.text() or expected == 0


def test_lang_c_and_pythonioencoding_ascii_in_a_real_process(rig):
    environment = {**os.environ, "LANG": "C", "LC_ALL": "C", "PYTHONIOENCODING": "ascii",
                   "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    result = subprocess.run([sys.executable, "-m", "genthermal.cli", "describe"], capture_output=True,
                            env=environment, timeout=120)
    assert result.returncode == 0, result.stderr
    assert b"degC" in result.stdout and all(byte < 128 for byte in result.stdout)
