r"""Coolant flow through a partly blocked outlet: the outlet diameter → flow fraction relation.

:func:`outlet_flow_fraction` gives :math:`k_{flow}(d) = \sqrt{(1 + \beta)/(1 + \beta\,(d_0/d)^4)}` for a fan
driving the air through quadratic resistances in series, the outlet an orifice of diameter
:math:`d`; :math:`\beta` (:data:`OUTLET_LOSS_SHARE`, assumed) is the healthy outlet's share of the
circuit's loss. :func:`inlet_rise` and :func:`inlet_load_factor` give the coolant inlet's rise
after a fault (recirculated outlet air). Thesis section 7.3.1 (the 10 mm outlet plate);
derivation: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import InputError

#: Diameter of the unblocked coolant outlet of the thesis rig, mm (thesis 7.3.1).
OUTLET_DIAMETER_MM = 50.0
#: Assumed share β of the healthy outlet's exit loss in the rest of the circuit's resistance (fan
#: slope and passages): ~8.5 m/s in the 50 mm duct loses one velocity head, ~45 Pa, against a
#: small internal fan's ~200-400 Pa, so β ≈ 0.1-0.25; 0.15 is taken.
OUTLET_LOSS_SHARE = 0.15


def outlet_flow_fraction(diameter_mm: float, healthy_diameter_mm: float = OUTLET_DIAMETER_MM,
                         loss_share: float = OUTLET_LOSS_SHARE) -> float:
    r"""Coolant flow with an outlet orifice of ``diameter_mm``, as a fraction of the healthy flow.

    :math:`k = \sqrt{(1+\beta)/(1+\beta (d_0/d)^4)}`; see the module docstring.

    Parameters
    ----------
    diameter_mm : float
        Orifice diameter, mm; ``0 < d <= healthy_diameter_mm``.
    healthy_diameter_mm : float
        Diameter of the open outlet duct, mm (thesis rig: 50).
    loss_share : float
        :math:`\beta > 0`: exit loss of the open outlet over the rest of the circuit's resistance.

    Returns
    -------
    float
        :math:`k_{flow}` in (0, 1].
    """
    checks = (("healthy_diameter_mm", healthy_diameter_mm, healthy_diameter_mm > 0, "a diameter > 0 mm"),
              ("loss_share", loss_share, loss_share > 0, "a resistance ratio > 0"))
    for field, value, ok, what in checks:
        if not (isinstance(value, (int, float)) and math.isfinite(value) and ok):
            raise InputError(field, value, f"must be {what}")
    if not (isinstance(diameter_mm, (int, float)) and math.isfinite(diameter_mm)
            and 0 < diameter_mm <= healthy_diameter_mm):
        raise InputError("outlet_diameter_mm", diameter_mm,
                         f"must be a diameter in (0, {healthy_diameter_mm:g}] mm (the open outlet)")
    ratio = (healthy_diameter_mm / diameter_mm) ** 4
    return math.sqrt((1.0 + loss_share) / (1.0 + loss_share * ratio))


def inlet_load_factor(current_A, share_current_A, load_share):
    r"""Factor (dimensionless) on a fault's inlet rise for the load the blocked generator carries.

    .. math::
        f = 1 + \alpha\left(\left(\frac{I}{I_{share}}\right)^2 - 1\right)
          = 1 - \alpha + \alpha\left(\frac{I}{I_{share}}\right)^2,

    :math:`I` the generator's phase current, :math:`I_{share}` the current it carries when the load
    is shared out undisplaced (the mean phase current of the power system's generators; during a
    rest, the rest current), :math:`\alpha` the share of the rise that follows the load. A blocked
    outlet recirculates the generator's own heated air into its inlet, and that heat is its loss,
    which grows as :math:`I^2`: thesis 7.3.3, the inlet temperature "is dependent upon both the fault
    and the load and hence cannot be accurately described". :math:`\alpha = 0` is a rise fixed by
    the fault alone (the factor is exactly 1); :math:`\alpha = 1` a rise wholly proportional to the
    copper loss relative to the undisplaced share, so moving load off the blocked generator cools
    its inlet. The rise the scenario states is the one at the undisplaced load (:math:`f = 1`).
    The thesis gives no value of :math:`\alpha`; the chapter-7 calibration fits it
    (:mod:`studies.chapter7_feasibility`, ``genco_rf201a:chapter7``).

    Works on numbers, numpy arrays and CasADi expressions alike (the feasibility study
    differentiates through it); numeric arguments are checked.

    Parameters
    ----------
    current_A : float, array_like or CasADi expression
        Phase current of the blocked generator, A RMS, >= 0.
    share_current_A : float, array_like or CasADi expression
        Its undisplaced share of the load, A RMS, >= 0; where it is 0 every generator carries
        nothing and the ratio is taken as 0.
    load_share : float or CasADi expression
        :math:`\alpha`, in [0, 1].

    Returns
    -------
    float, numpy.ndarray or CasADi expression
        :math:`f`, dimensionless.

    Raises
    ------
    InputError
        Naming ``inlet_load_share``, ``current_A`` or ``share_current_A`` and the bad value.
    """
    if isinstance(load_share, (int, float, np.floating, np.integer)):
        if isinstance(load_share, bool) or not (math.isfinite(load_share) and 0.0 <= load_share <= 1.0):
            raise InputError("inlet_load_share", load_share, "must be a share of the inlet rise in [0, 1]")
        if load_share == 0.0:
            return np.ones(np.shape(current_A)) if isinstance(current_A, (np.ndarray, list)) else 1.0
    numeric = all(isinstance(v, (int, float, np.floating, np.integer, np.ndarray, list))
                  for v in (current_A, share_current_A))
    if not numeric:
        return 1.0 + load_share * ((current_A / share_current_A) ** 2 - 1.0)
    current, share = np.asarray(current_A, dtype=float), np.asarray(share_current_A, dtype=float)
    for field, value in (("current_A", current), ("share_current_A", share)):
        if not np.all(np.isfinite(value) & (value >= 0.0)):
            raise InputError(field, value.tolist(), "must be phase currents >= 0 A RMS")
    ratio = np.divide(current, share, out=np.zeros(np.broadcast(current, share).shape), where=share > 0)
    return 1.0 + load_share * (ratio ** 2 - 1.0)


def inlet_rise(time_s, onset_s: float, rise_K: float, time_constant_s: float = 0.0, load_share: float = 0.0,
               current_A=None, share_current_A=None) -> np.ndarray:
    r"""Rise of the coolant inlet temperature after a fault, K, at times ``time_s`` (s).

    :math:`\Delta T\,(1 - e^{-(t - t_0)/\tau})\,f` from the onset :math:`t_0` on, 0 before; a step for
    :math:`\tau = 0`. A blocked outlet warms the air the rig draws in gradually (thesis Fig 7.4 shows
    the rise after the 10 mm plate, without its time constant). :math:`f` is the load factor of
    :func:`inlet_load_factor` for a ``load_share`` above 0 (then ``current_A`` and
    ``share_current_A`` at ``time_s`` are needed), else 1: the rise of the fault alone.

    Parameters
    ----------
    time_s : array_like
        Times, s.
    onset_s : float
        Fault onset, s.
    rise_K : float
        Final rise at the undisplaced load, K.
    time_constant_s : float
        :math:`\tau` >= 0, s.
    load_share : float
        :math:`\alpha` in [0, 1] (:func:`inlet_load_factor`); 0 (default): independent of the load.
    current_A, share_current_A : array_like, optional
        The generator's phase current and its undisplaced share at ``time_s``, A RMS.
    """
    if not (math.isfinite(time_constant_s) and time_constant_s >= 0):
        raise InputError("inlet_rise_tau", time_constant_s, "must be a time constant >= 0 s")
    elapsed = np.asarray(time_s, dtype=float) - onset_s
    started = elapsed >= -1e-9
    if time_constant_s == 0:
        rise = np.where(started, rise_K, 0.0)
    else:
        rise = np.where(started, rise_K * -np.expm1(-np.clip(elapsed, 0.0, None) / time_constant_s), 0.0)
    if current_A is None or share_current_A is None:
        inlet_load_factor(1.0, 1.0, load_share)  # rejects a load_share outside [0, 1], naming it
        if load_share != 0:
            raise InputError("current_A" if current_A is None else "share_current_A", None,
                             f"needed: {load_share:g} of the inlet rise follows the generator's load")
        return rise
    return rise * inlet_load_factor(current_A, share_current_A, load_share)
