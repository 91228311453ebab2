r"""The exciter current of a generator whose AVR holds rated terminal voltage.

:func:`exciter_current` gives :math:`I_{exc} = I_{exc,0}\,|E|`, the internal EMF :math:`E` from
the phasor diagram of a cylindrical-rotor machine at the load current and power factor (per
unit, terminal voltage 1). The three constants are assumed (:data:`EXCITER_PARAMETERS`, each with
its reason); the thesis's ARX search found :math:`I_{exc}` the best input (thesis 5.3).
Derivation: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import numpy as np

from .errors import InputError
from .parameters import Parameter, ParameterSet

#: Power factor of the load when a mission does not state one: 0.8 lagging, the rating point of
#: aircraft and industrial generators (rated kVA at 0.75-0.8 lagging).
DEFAULT_POWER_FACTOR = 0.8

EXCITER_PARAMETERS = ParameterSet([
    Parameter("I_exc_no_load", 0.45, "A", "assumed",
              "exciter field current at rated voltage and no load: a few hundred mA for a 5 kVA "
              "brushless machine's exciter"),
    Parameter("x_s", 1.5, "1", "assumed",
              "synchronous reactance, per unit: 1-2 for small synchronous generators", upper=5.0),
    Parameter("r_a", 0.05, "1", "assumed",
              "armature resistance, per unit: 1.67 ohm hot phase resistance over the 34 ohm base "
              "impedance (240 V / 7 A)", upper=1.0),
])


def _checked_power_factor(power_factor) -> float:
    try:
        value = float(power_factor)
    except (TypeError, ValueError):
        raise InputError("power_factor", power_factor, "must be a number in (0, 1] (lagging)") from None
    if not 0.0 < value <= 1.0:
        raise InputError("power_factor", power_factor, "must lie in (0, 1] (lagging load power factor)")
    return value


def exciter_current(I_phase_A, power_factor: float = DEFAULT_POWER_FACTOR, rated_current_A: float = 7.0,
                    parameters: ParameterSet = EXCITER_PARAMETERS):
    r"""Exciter field current the AVR needs to hold rated voltage at a load current.

    Parameters
    ----------
    I_phase_A : float or array_like
        RMS phase current of the load (mean of the three phases), A (>= 0).
    power_factor : float
        Load power factor :math:`\cos\varphi`, lagging, in (0, 1].
    rated_current_A : float
        Rated RMS phase current, A (> 0): per-unit base of the current.
    parameters : ParameterSet
        ``I_exc_no_load`` (A), ``x_s`` and ``r_a`` (per unit); default :data:`EXCITER_PARAMETERS`.

    Returns
    -------
    float or numpy.ndarray
        Exciter current, A; same shape as ``I_phase_A``.
    """
    current = np.asarray(I_phase_A, dtype=float)
    if np.any(~(current >= 0)):
        raise InputError("I_phase_A", I_phase_A, "phase current must be a number >= 0 A")
    cos_phi = _checked_power_factor(power_factor)
    if not (isinstance(rated_current_A, (int, float)) and rated_current_A > 0):
        raise InputError("rated_current_A", rated_current_A, "must be a current > 0 A")
    sin_phi = np.sqrt(1.0 - cos_phi**2)
    x_s, r_a = parameters.value("x_s"), parameters.value("r_a")
    i = current / rated_current_A
    emf = np.hypot(1.0 + i * (r_a * cos_phi + x_s * sin_phi), i * (x_s * cos_phi - r_a * sin_phi))
    field = parameters.value("I_exc_no_load") * emf
    return float(field) if field.ndim == 0 else field


def exciter_line(power_factor: float = DEFAULT_POWER_FACTOR, rated_current_A: float = 7.0,
                 samples: int = 201, law=None) -> tuple[float, float]:
    r"""Least-squares line :math:`I_{exc} \approx I_0 + g\,I` over 0 … rated current, for planners
    that need inputs affine in the phase current (as eq. 5.3 does for :math:`I^2`).

    ``law(I, power_factor, rated_current_A)`` is the exciter law fitted (a machine's
    :attr:`~genthermal.machines.interface.GeneratorRole.exciter_law`); default
    :func:`exciter_current`.

    Returns
    -------
    (float, float)
        Intercept :math:`I_0` (A) and slope :math:`g` (A/A).
    """
    current = np.linspace(0.0, rated_current_A, samples)
    law = exciter_current if law is None else law
    slope, intercept = np.polyfit(current, law(current, power_factor, rated_current_A), 1)
    return float(intercept), float(slope)
