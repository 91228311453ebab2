"""On the real bench IPMSM, ``diagnose`` names what the plain model lacks: a rotor-side effect
rising with speed, and no sensor fault (the measured profiles in ``../shared``; skipped without)."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / ".." / "shared" / "records" / "ipmsm_bench"
MACHINE_FILE = ROOT / "examples" / "ipmsm" / "ipmsm_machine.py"
TRAIN = ("id_1", "id_2", "id_3", "id_7", "id_8", "id_9", "id_12", "id_13", "id_14")
ROTOR_SIDE_SPEED_EFFECTS = {"magnet_eddy_loss", "air_gap_convection_speed", "end_space_convection_speed"}


@pytest.mark.slow
@pytest.mark.skipif(not DATA.is_dir(), reason="no ../shared/records/ipmsm_bench")
def test_the_plain_models_diagnosis_names_a_rotor_loss_rising_with_speed():
    from genthermal.column_map import ColumnMap, read_logged_set
    from genthermal.diagnose.discovery import Discovery
    from genthermal.diagnose.fitter import OnsetFitter
    from genthermal.diagnose.multi_record import decimated, fit_records, record_from_measurements
    from genthermal.effects import CATALOGUE
    from genthermal.machines import build_model, resolve_machine

    machine = resolve_machine(str(MACHINE_FILE))
    plain = build_model(f"{MACHINE_FILE}:MACHINE_PLAIN")
    column_map = ColumnMap.from_dict(machine.column_map, machine.interface)
    train = read_logged_set([DATA / f"{n}.csv" for n in TRAIN], column_map, machine.interface)
    names = [n for n in plain.parameter_names if plain.parameters[n].provenance == "assumed"]
    fit = fit_records(plain, [record_from_measurements(plain, d, 30.0) for d in train], names, prior_weight=30.0)
    unseen = decimated(read_logged_set([DATA / "id_5.csv"], column_map, machine.interface)[0], 60.0)
    result = Discovery(fitter=OnsetFitter(pairs=False), design_experiment=False).fit(fit.model, unseen)
    document = result.to_dict()
    first = document["ranked"][0]
    assert first["effect"] in ROTOR_SIDE_SPEED_EFFECTS and first["significant"], first
    assert document["verdict"] == first["effect"] and document["sensor_faults"] == []
    # the fitted size is physical, and the effect cuts the unseen profile's error by a quarter at least
    assert CATALOGUE[first["effect"]].implausible(first["params"]) is None
    assert first["rmse_after"] <= 0.75 * first["rmse_before"]
