"""The AVR exciter law: exciter current from load current and power factor."""

import numpy as np
import pytest

from genthermal.errors import InputError
from genthermal.exciter import EXCITER_PARAMETERS, exciter_current, exciter_line

CURRENTS = np.linspace(0.0, 8.0, 81)


@pytest.mark.parametrize("power_factor", [0.6, 0.8, 0.95, 1.0])
def test_exciter_current_rises_with_load_from_its_no_load_value(power_factor):
    field = exciter_current(CURRENTS, power_factor)
    assert field[0] == pytest.approx(EXCITER_PARAMETERS.value("I_exc_no_load"))
    assert np.all(np.diff(field) > 0)


def test_more_lagging_load_needs_more_field_current():
    at_rated = [exciter_current(7.0, pf) for pf in (1.0, 0.9, 0.8, 0.6)]
    assert np.all(np.diff(at_rated) > 0)


def test_rated_point_is_the_phasor_diagram():
    # rated current, 0.8 lagging: E = 1 + (r + j x)(0.8 - 0.6 j) per unit
    x_s, r_a = EXCITER_PARAMETERS.value("x_s"), EXCITER_PARAMETERS.value("r_a")
    emf = abs(1.0 + complex(r_a, x_s) * complex(0.8, -0.6))
    assert exciter_current(7.0, 0.8, 7.0) == pytest.approx(EXCITER_PARAMETERS.value("I_exc_no_load") * emf)
    assert exciter_current(14.0, 0.8, 14.0) == pytest.approx(exciter_current(7.0, 0.8, 7.0))  # per unit


def test_exciter_current_is_not_affine_in_the_load_current():
    # the I^2 content the thesis's ARX found in I_exc: a line leaves a clear residual
    intercept, slope = exciter_line(0.8)
    field = exciter_current(CURRENTS[:71], 0.8)
    residual = field - (intercept + slope * CURRENTS[:71])
    assert np.max(np.abs(residual)) > 0.005 and abs(np.mean(residual)) < 1e-3
    assert np.all(np.diff(field, 2) != 0)


@pytest.mark.parametrize("kwargs, field", [
    (dict(I_phase_A=-1.0), "I_phase_A"), (dict(I_phase_A=[1.0, np.nan]), "I_phase_A"),
    (dict(I_phase_A=3.0, power_factor=0.0), "power_factor"), (dict(I_phase_A=3.0, power_factor=1.2), "power_factor"),
    (dict(I_phase_A=3.0, power_factor="lagging"), "power_factor"),
    (dict(I_phase_A=3.0, rated_current_A=0.0), "rated_current_A"),
])
def test_bad_exciter_inputs_name_the_field(kwargs, field):
    with pytest.raises(InputError) as error:
        exciter_current(**kwargs)
    assert error.value.field == field


def test_parameters_record_their_provenance():
    for name in ("I_exc_no_load", "x_s", "r_a"):
        assert EXCITER_PARAMETERS[name].provenance == "assumed" and EXCITER_PARAMETERS[name].source
