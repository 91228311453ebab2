"""Output files: JSON holds finite numbers only, files appear whole or not at all."""

import json
import os
import stat

import numpy as np
import pytest

from genthermal.outputs import replacing, replacing_folder, write_json


def test_json_never_holds_nan_or_infinity_and_says_where(tmp_path):
    path = tmp_path / "out.json"
    replaced = write_json(path, {"rmse": np.float64(0.25), "gain": [1.0, np.inf], "n": np.int64(3),
                                 "ok": np.bool_(True), "nested": {"bias": float("nan")}, "A": np.eye(2)})
    text = path.read_text()
    assert "NaN" not in text and "Infinity" not in text
    document = json.loads(text)
    assert document == {"rmse": 0.25, "gain": [1.0, None], "n": 3, "ok": True, "nested": {"bias": None},
                        "A": [[1.0, 0.0], [0.0, 1.0]]}
    assert replaced == ["gain[1] (inf)", "nested.bias (nan)"]


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path):
    path = tmp_path / "result.csv"
    path.write_text("old\n")
    with pytest.raises(RuntimeError):
        with replacing(path) as temporary:
            temporary.write_text("half")
            raise RuntimeError("disk full")
    assert path.read_text() == "old\n" and [p.name for p in tmp_path.iterdir()] == ["result.csv"]


def test_a_written_file_has_the_permissions_of_a_new_file(tmp_path):
    path = tmp_path / "new.json"
    write_json(path, {"a": 1})
    mask = os.umask(0)
    os.umask(mask)
    assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~mask


def test_a_folder_appears_whole_or_not_at_all(tmp_path):
    out = tmp_path / "code"
    with pytest.raises(KeyboardInterrupt):
        with replacing_folder(out) as build:
            (build / "gt.c").write_text("complete")
            (build / "gt.h").write_text("half")
            raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []  # neither the folder nor a temporary one
    with replacing_folder(out) as build:
        (build / "gt_casadi_old.c").write_text("old")
        (build / "gt.c").write_text("old")
    with pytest.raises(KeyboardInterrupt):
        with replacing_folder(out, ("gt_casadi_*.c",)) as build:
            (build / "gt.c").write_text("new")
            raise KeyboardInterrupt
    assert {p.name: p.read_text() for p in out.iterdir()} == {"gt_casadi_old.c": "old", "gt.c": "old"}
    (out / "notes.txt").write_text("the user's")
    with replacing_folder(out, ("gt_casadi_*.c",)) as build:
        (build / "gt.c").write_text("new")
        (build / "gt_casadi_new.c").write_text("new")
    assert {p.name: p.read_text() for p in out.iterdir()} == {"gt.c": "new", "gt_casadi_new.c": "new",
                                                               "notes.txt": "the user's"}
    assert [p.name for p in tmp_path.iterdir()] == ["code"]
