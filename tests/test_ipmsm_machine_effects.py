"""The bench IPMSM's full model is its plain model plus the speed-dependent catalogue transforms:
on the shipped profile slice it runs as the hand-written terms it replaced (a frozen reference of
those equations, kept here only as the oracle), at the file's values and at fitted-like ones."""

from __future__ import annotations

import dataclasses
import types

import numpy as np
import pytest
import sympy

from genthermal.diagnose.multi_record import record_from_measurements, simulate_record
from genthermal.losses import input_symbol
from genthermal.machines import build_model, resolve_machine
from genthermal.network import HeatSource
from genthermal.resources import BENCH_MOTOR_DIR

MACHINE_FILE = str(BENCH_MOTOR_DIR / "ipmsm_machine.py")
SLICE = BENCH_MOTOR_DIR / "id_9_first_3000s.csv"
#: Values a fit over the bench profiles reaches (docs/results/ipmsm.md): every term away from its start.
FITTED_LIKE = dict(P_hyst_ref=420.0, P_eddy_ref=90.0, k_fe_current=0.8, tooth_iron_share=0.35, G_gap_speed=22.0,
                   k_end_space_speed=2.5, k_ac=0.3, P_pm_ref=700.0, k_pm_current=0.2, pm_speed_exponent=1.15,
                   P_friction_ref=80.0)


def _frozen_reference(module):
    """The machine file's network as its hand-written terms gave it before they became catalogue
    transforms (the plain nodes and links, the old heat sources)."""
    def build(parameters):
        S = parameters.symbols()
        plain = module.build_network(module.plain_parameters())
        theta = plain.temperature_symbol
        speed = input_symbol("motor_speed") / module.N_REF_RPM
        eps = 1e-3  # the file's offset of the speed ratio in its power law
        current_squared = input_symbol("i_d") ** 2 + input_symbol("i_q") ** 2
        load = current_squared / module.RATED_CURRENT_A ** 2
        copper = sympy.Rational(3, 2) * current_squared * S["R_0"] * (1 + S["k_ac"] * speed ** 2)
        share = S["end_winding_share"]
        iron = (S["P_hyst_ref"] * speed + S["P_eddy_ref"] * speed ** 2) * (1 + S["k_fe_current"] * load)
        pm_speed = (speed + eps) ** S["pm_speed_exponent"] - eps ** S["pm_speed_exponent"]
        sources = [
            HeatSource("winding_slot", (1 - share) * copper * (1 + S["alpha_cu"] * theta("winding_slot")), "copper"),
            HeatSource("end_winding", share * copper * (1 + S["alpha_cu"] * theta("end_winding")), "copper"),
            HeatSource("tooth", S["tooth_iron_share"] * iron, "iron"),
            HeatSource("yoke_inner", (1 - S["tooth_iron_share"]) * iron, "iron"),
            HeatSource("rotor", S["P_pm_ref"] * pm_speed * (1 + S["k_pm_current"] * load), "magnet"),
            HeatSource("shaft_bearing", S["P_friction_ref"] * speed, "friction"),
        ]
        rises = {("tooth", "rotor"): S["G_gap_speed"] * speed}
        for pair, g in ((("end_winding", "end_space_air"), "G_end_winding_air"),
                        (("rotor", "end_space_air"), "G_rotor_air"), (("end_space_air", "endcap"), "G_air_endcap")):
            rises[pair] = S["k_end_space_speed"] * S[g] * speed
        for (a, b), rise in rises.items():
            flow = rise * (theta(a) - theta(b))
            sources += [HeatSource(b, flow, "rise"), HeatSource(a, -flow, "rise")]
        return plain.replace(heat_sources=tuple(sources))
    return build


@pytest.fixture(scope="module")
def models():
    from genthermal.column_map import ColumnMap, read_logged

    machine = resolve_machine(MACHINE_FILE)
    module = machine.build_network.__globals__
    reference = dataclasses.replace(machine, build_network=_frozen_reference(types.SimpleNamespace(**module)))
    data = read_logged(SLICE, ColumnMap.from_dict(machine.column_map, machine.interface), machine.interface)
    full = build_model(MACHINE_FILE)
    return full, build_model(reference), record_from_measurements(full, data, 10.0)


@pytest.mark.parametrize("values", [{}, FITTED_LIKE], ids=["file_values", "fitted_like"])
def test_the_full_model_runs_as_the_hand_written_terms_did(models, values):
    full, reference, record = models
    if values:
        full = full.with_parameters(provenance="fitted", source="test", **values)
        reference = reference.with_parameters(provenance="fitted", source="test", **values)
    new, old = simulate_record(full, record), simulate_record(reference, record)
    assert np.all(np.isfinite(old)) and np.ptp(old[full.output_names.index("T_rotor")]) > 5.0  # the slice heats
    assert np.max(np.abs(new - old)) < 1e-6


def test_the_plain_model_has_none_of_the_speed_terms():
    plain = build_model(f"{MACHINE_FILE}:MACHINE_PLAIN")
    speed = input_symbol("motor_speed")
    assert not any(speed in s.power.free_symbols for s in plain.network.heat_sources)
