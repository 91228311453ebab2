"""One effect fitted over several records at once (``diagnose --joint``): it finds an effect present
in every record of an independent generator with a size near the truth, claims nothing on healthy
records, and names the record and column of bad input. The tests on ``../shared`` (10-15 s each on
a loaded machine) skip without it."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from genthermal.cli import main
from genthermal.errors import InputError
from genthermal.resources import BENCH_MOTOR_DIR

RECORDS = Path(__file__).resolve().parents[1] / ".." / "shared" / "records" / "independent_batch1"
MACHINE_FILE = str(BENCH_MOTOR_DIR / "ipmsm_machine.py")
SLICE = BENCH_MOTOR_DIR / "id_9_first_3000s.csv"


def _halves(tmp_path, name):
    """The record split in two at its middle: two records of one machine with the same effect."""
    frame = pd.read_csv(RECORDS / "data" / f"{name}.csv")
    middle = len(frame) // 2
    paths = []
    for k, part in enumerate((frame.iloc[:middle], frame.iloc[middle:])):
        paths.append(tmp_path / f"{name}_{k}.csv")
        part.to_csv(paths[-1], index=False)
    return [str(p) for p in paths]


def _joint(tmp_path, data):
    out = tmp_path / "joint.json"
    code = main(["diagnose", *data, "--joint", "--fit-step", "60", "--json", str(out),
                 "--baseline", str(RECORDS / "data" / "healthy_baseline.csv")])
    assert code == 0
    return json.loads(out.read_text())


@pytest.mark.skipif(not RECORDS.is_dir(), reason="no ../shared/records/independent_batch1")
def test_the_joint_fit_finds_a_stray_loss_present_in_both_records_at_its_size(tmp_path):
    document = _joint(tmp_path, _halves(tmp_path, "effect_c_end_winding_stray_loss"))
    truth = json.loads((RECORDS / "truth" / "effect_c_end_winding_stray_loss.json").read_text())["effects"][0]
    named = {document["verdict"], *document["look_alikes"]}
    assert "end_winding_stray_loss" in named, document["verdict"]
    entry = next(e for e in document["ranked"] if e["effect"] == "end_winding_stray_loss")
    # the generator's k (W/A² on the sum of the phase currents squared) is genthermal's R_stray
    assert entry["significant"] and entry["implausible"] is None
    assert 0.5 < entry["params"]["R_stray"] / truth["params"]["k_W_per_A2"] < 1.5, entry["params"]
    assert all(r["rmse_after_K"] < r["rmse_before_K"] for r in entry["per_record"])


@pytest.mark.skipif(not RECORDS.is_dir(), reason="no ../shared/records/independent_batch1")
def test_the_joint_fit_claims_nothing_on_healthy_records(tmp_path):
    document = _joint(tmp_path, [str(RECORDS / "data" / f"{n}.csv") for n in ("step_040pct", "step_080pct")])
    assert document["verdict"] == "none" and not any(e["significant"] for e in document["ranked"])


@pytest.fixture(scope="module")
def slice_records():
    from genthermal.column_map import ColumnMap, read_logged
    from genthermal.diagnose.multi_record import record_from_measurements
    from genthermal.machines import build_model, resolve_machine

    machine = resolve_machine(MACHINE_FILE)
    data = read_logged(SLICE, ColumnMap.from_dict(machine.column_map, machine.interface), machine.interface)
    model = build_model(f"{MACHINE_FILE}:MACHINE_PLAIN")
    record = record_from_measurements(model, data, 60.0)
    return model, record


def test_records_too_short_or_without_a_sensor_are_refused_by_name(slice_records):
    from genthermal.diagnose.over_records import fit_effect_over_records

    model, record = slice_records
    short = dataclasses.replace(record, name="short.csv", inputs=record.inputs[:, :20], outputs=record.outputs[:, :20])
    with pytest.raises(InputError, match="short.csv: samples"):
        fit_effect_over_records(model, [record, short], "magnet_eddy_loss")
    outputs = record.outputs.copy()
    outputs[model.output_names.index("T_rotor")] = np.nan
    blind = dataclasses.replace(record, name="blind.csv", outputs=outputs)
    with pytest.raises(InputError, match="blind.csv: column T_rotor"):
        fit_effect_over_records(model, [record, blind], "magnet_eddy_loss")
    with pytest.raises(InputError, match="records"):
        fit_effect_over_records(model, [record], "magnet_eddy_loss")


def test_joint_records_of_different_columns_are_refused_naming_the_file_and_column(tmp_path, capsys):
    frame = pd.read_csv(SLICE, nrows=1200)
    first, second = tmp_path / "a.csv", tmp_path / "b.csv"
    frame.to_csv(first, index=False)
    frame.drop(columns=["endcap"]).to_csv(second, index=False)
    code = main(["diagnose", "--model", MACHINE_FILE, str(first), str(second), "--joint", "--dt", "1"])
    message = capsys.readouterr().err
    assert code == 2 and "b.csv: columns" in message and "endcap" in message
