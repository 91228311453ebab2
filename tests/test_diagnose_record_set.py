"""``diagnose`` over several records: the error model pooled over a baseline set, and the bad
input of a call with several records (on the bench IPMSM's shipped profile slice)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from genthermal.cli import main
from genthermal.diagnose.error_model import MIN_BASELINE_S, ErrorModel
from genthermal.errors import InputError
from genthermal.resources import BENCH_MOTOR_DIR

MACHINE_FILE = str(BENCH_MOTOR_DIR / "ipmsm_machine.py")
SLICE = BENCH_MOTOR_DIR / "id_9_first_3000s.csv"


def _ar1(phi, n, seed):
    rng = np.random.default_rng(seed)
    e = np.zeros(n)
    for t in range(1, n):
        e[t] = phi * e[t - 1] + math.sqrt(1 - phi ** 2) * rng.standard_normal()
    return e


def test_one_residual_pooled_is_the_single_record_model():
    e = _ar1(0.9, 800, 1)[None, :]
    one, pooled = ErrorModel.from_residual(e, ["T"], 10.0), ErrorModel.from_residuals([e], ["T"], 10.0)
    assert one == pooled


def test_pooled_correlation_is_taken_within_records_not_across_their_joins():
    """Pooled, the last sample of one record and the first of the next are no neighbour pair:
    the lag-1 sum lacks exactly that product (the records' levels differ by 4 K)."""
    a, b = _ar1(0.5, 400, 2) + 2.0, _ar1(0.5, 400, 3) - 2.0
    pooled = ErrorModel.from_residuals([a[None, :], b[None, :]], ["T"], 10.0)
    joined = ErrorModel.from_residual(np.concatenate([a, b])[None, :], ["T"], 10.0)
    assert abs(pooled.sensors[0].level_K - joined.sensors[0].level_K) < 1e-12
    assert pooled.sensors[0].phi == pytest.approx(joined.sensors[0].phi - float(a[-1] * b[0]) /
                                                  float(np.concatenate([a, b]) @ np.concatenate([a, b])))


def test_pooled_records_must_be_long_enough_together():
    short = [_ar1(0.5, 100, s)[None, :] for s in (4, 5)]  # 2 x 1000 s at 10 s
    with pytest.raises(InputError, match="baseline"):
        ErrorModel.from_residuals(short, ["T"], 10.0)
    enough = short * 2  # 4000 s together
    assert 4 * 1000.0 >= MIN_BASELINE_S and ErrorModel.from_residuals(enough, ["T"], 10.0).sensors[0].level_K > 0


def _variant(tmp_path, name, rows=slice(0, 1200), change=None):
    frame = pd.read_csv(SLICE).iloc[rows].reset_index(drop=True)
    if change:
        change(frame)
    path = tmp_path / name
    frame.to_csv(path, index=False)
    return str(path)


def _run(argv, capsys):
    code = main(["diagnose", "--model", f"{MACHINE_FILE}:MACHINE_PLAIN", *argv])
    return code, capsys.readouterr().err


def test_baselines_too_short_together_name_the_files(tmp_path, capsys):
    data = _variant(tmp_path, "data.csv")
    a, b = _variant(tmp_path, "a.csv", slice(0, 900)), _variant(tmp_path, "b.csv", slice(900, 1800))
    code, err = _run([data, "--baseline", a, b], capsys)
    assert code == 2 and "a.csv" in err and "b.csv" in err and "together 0.49 h" in err and "1.0 h" in err


def test_baseline_of_other_columns_is_refused_naming_file_and_column(tmp_path, capsys):
    data = _variant(tmp_path, "data.csv")
    other = _variant(tmp_path, "other.csv", change=lambda f: f.pop("bearing"))
    code, err = _run([data, "--baseline", other], capsys)
    assert code == 2 and "other.csv" in err and "bearing" in err


def test_a_run_of_nan_in_a_baseline_names_file_column_and_rows(tmp_path, capsys):
    data = _variant(tmp_path, "data.csv")

    def lose(frame):
        frame.loc[100:199, "rotor"] = np.nan
    lost = _variant(tmp_path, "lost.csv", change=lose)
    code, err = _run([data, "--baseline", lost], capsys)
    assert code == 2 and "lost.csv" in err and "column rotor" in err and "NaN" in err


def test_baseline_swallowing_every_file_says_how_to_give_data(tmp_path, capsys):
    a = _variant(tmp_path, "a.csv")
    code, err = _run(["--baseline", a], capsys)
    assert code == 2 and "DATA" in err and "--" in err


def test_several_data_records_refuse_one_model_out(tmp_path, capsys):
    a, b = _variant(tmp_path, "a.csv"), _variant(tmp_path, "b.csv", slice(1200, 2400))
    code, err = _run([a, b, "--out", str(tmp_path / "m.yaml")], capsys)
    assert code == 2 and "--out" in err and "one DATA record" in err
