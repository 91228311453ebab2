r"""The thesis's managed large blockage as a continuous proxy of the chapter-7 calibration.

Thesis 7.3.3 (Figs 7.13-7.15), the large blockage flown with the load manager: "Once the fault has
occurred at 1.1 hours the next 3 K-conditions are accommodated using only load displacement.
After this both generators are placed into rest mode for 10 mins to allow the execution of the
final landing K-condition", with "two small breaches of 110.7 °C at 2 hours and 111 °C at 3 hours".

Proxy
-----
Two copies of the plant fly the Fig 7.7 mission (thesis 7.3.2: "two copies of the simulation
model"): gen1 with the large blockage from :data:`~studies.chapter7.ONSET_S` (flow
fraction ``k_flow``, exponent ``n_flow``, inlet rising by 31 K with the blockage's time constant),
gen2 healthy. Both rest 10 min (minimum power mode, 27.3 % of rated) before landing. In each of
the four K-conditions from the fault on (cruise, cruise/combat, cruise, landing) a constant current
:math:`I_d(k)` moves from gen1 to gen2 (eqs. 7.3-7.4): decision variables of the fit, in
:data:`DISPLACEMENT_BOUNDS_A`. The proxy's residuals are, per K-condition and generator, the
smooth excess of the winding's peak over :data:`LIMIT_C` (:func:`smooth_excess`): zero when some
displacement keeps both generators within θmax in all four conditions with only the 10-min rest,
which is the thesis's outcome. The excess is measured on the plant (no manager lag): the thesis's
own breaches (0.7 and 1 K) are what its manager's prediction errors cost on top.

The healthy receiver is not held to the rated current here: the thesis bounds it by θmax alone
(eqs. 7.2-7.4), and it displaces load in landing, whose first 5 min run at 100 % (7.3.3: "a short
rest with some load displacement is required for landing"), which a receiver held to rated
current could not take. The rated-current reading of "very little spare capacity" is an option of
:func:`best_displacement` and of the feasibility study (``receiver_limit_A``, with
:func:`receiver_headroom_A`), and ``per_level`` gives each K-condition's 5-min start-up and
continuous levels their own displaced current (:func:`level_masks`).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from genthermal.coolant import inlet_load_factor, inlet_rise
from genthermal.diagnose.trajectory import ParametricSimulator
from genthermal.errors import InputError
from genthermal.mission import load_mission
from genthermal.model import ThermalModel

#: θmax of the thesis experiments, °C (7.3.1).
LIMIT_C = 110.0
#: Rest of both generators before landing, s (7.3.3: "rest mode for 10 mins").
REST_BEFORE_LANDING_S = 600.0
#: Minimum power mode: condition 1's continuous level, % of rated (thesis Table 7.1).
REST_PERCENT = 27.3
#: The four K-conditions after the fault on the Fig 7.7 mission (before the inserted rest), s.
CONDITIONS = (("cruise", 66 * 60.0, 120 * 60.0), ("cruise_combat", 120 * 60.0, 180 * 60.0),
              ("cruise_after", 180 * 60.0, 220 * 60.0), ("landing", 220 * 60.0, 240 * 60.0))
#: Bounds of each displaced current, A: from none to the whole continuous cruise load of gen1.
DISPLACEMENT_BOUNDS_A = (0.0, 4.0)
#: Length of a K-condition's start-up level, s (thesis Table 7.1: "5 mins", then the continuous level).
START_UP_S = 300.0
#: Sharpness of the smooth excess, K: :math:`s \ln(1 + e^{x/s})` is within :math:`s \ln 2` = 0.07 K
#: of :math:`\max(x, 0)`.
EXCESS_SHARPNESS_K = 0.1


def smooth_excess(value, limit: float):
    """Smooth :math:`\\max(v - limit, 0)` (softplus at :data:`EXCESS_SHARPNESS_K`), K."""
    s = EXCESS_SHARPNESS_K
    x = (value - limit) / s
    return s * ca.if_else(x > 30, x, ca.log1p(ca.exp(ca.fmin(x, 30))))


def managed_timeline(dt_s: float, rest_s: float = REST_BEFORE_LANDING_S) -> dict:
    """The Fig 7.7 mission with the rest of ``rest_s`` s (default the thesis's 10 min; its rig rested
    20 min) before landing, sampled every ``dt_s`` s.

    Returns
    -------
    dict
        ``time_s`` (n,), ``current_A`` (n,) the nominal phase current of both generators,
        ``mission_time_s`` (n,) the mission clock (time without the inserted rest), ``masks``
        (4, n): 1 where each K-condition runs, and ``rest`` (n,) bool.
    """
    if not (isinstance(dt_s, (int, float)) and np.isfinite(dt_s) and dt_s > 0
            and abs(300.0 / dt_s - round(300.0 / dt_s)) < 1e-9):
        raise InputError("dt_s", dt_s, "must be a sample period in s that divides 300 s (the mission's 5-min levels)")
    if not (isinstance(rest_s, (int, float)) and np.isfinite(rest_s) and rest_s > 0
            and abs(rest_s / dt_s - round(rest_s / dt_s)) < 1e-9):
        raise InputError("rest_s", rest_s, f"must be a rest in s > 0, a multiple of the sample period {dt_s:g} s")
    mission = load_mission("thesis_fig_7_7")
    rest_start = CONDITIONS[-1][1]
    end = mission.duration_s + rest_s
    time_s = np.arange(int(round(end / dt_s)) + 1) * dt_s
    resting = (time_s >= rest_start - 1e-9) & (time_s < rest_start + rest_s - 1e-9)
    mission_time = np.where(time_s < rest_start + rest_s - 1e-9, np.minimum(time_s, rest_start), time_s - rest_s)
    currents = mission.phase_currents(np.minimum(mission_time, mission.duration_s)).mean(axis=1)
    currents = np.where(resting, REST_PERCENT / 100.0 * mission.rated_current_A, currents)
    masks = np.array([(mission_time >= start - 1e-9) & (mission_time < end_ - 1e-9) & ~resting
                      for _, start, end_ in CONDITIONS], dtype=float)
    return {"time_s": time_s, "current_A": currents, "mission_time_s": mission_time, "masks": masks,
            "rest": resting, "mission": mission}


def level_masks(line: dict) -> tuple[np.ndarray, tuple[str, ...]]:
    """Each K-condition's mask of :func:`managed_timeline` split into its 5-min start-up level and its
    continuous level (Table 7.1), so a displacement can differ between the two.

    Returns
    -------
    masks : ndarray, shape (2 k, n)
        Start-up then continuous level of each K-condition, in the order of :data:`CONDITIONS`.
    names : tuple of str
        ``"<condition>_5min"`` and ``"<condition>_continuous"`` for each row.
    """
    rows, names = [], []
    for mask, (condition, start, _) in zip(line["masks"], CONDITIONS):
        start_up = line["mission_time_s"] < start + START_UP_S - 1e-9
        rows += [mask * start_up, mask * ~start_up]
        names += [f"{condition}_5min", f"{condition}_continuous"]
    return np.array(rows, dtype=float), tuple(names)


def receiver_headroom_A(nominal_current_A: np.ndarray, masks: np.ndarray, limit_A: float) -> np.ndarray:
    r"""Largest constant displacement per K-condition that keeps the receiver at or below ``limit_A``
    at every sample, A (0 where the nominal current already reaches the limit).

    Parameters
    ----------
    nominal_current_A : ndarray, shape (n,)
        Undisplaced phase current of both generators at each sample, A.
    masks : ndarray, shape (k, n)
        1 where each K-condition's displacement applies, else 0.
    limit_A : float
        Highest phase current the receiver may carry, A (> 0).

    Returns
    -------
    ndarray, shape (k,)
        :math:`\max(0, I_{lim} - \max_{t \in k} I_{nom}(t))` per K-condition, A.
    """
    if not (isinstance(limit_A, (int, float)) and math.isfinite(limit_A) and limit_A > 0):
        raise InputError("receiver_limit_A", limit_A, "must be a current > 0 A (the receiver's rated current)")
    nominal = np.asarray(nominal_current_A, dtype=float)
    masks = np.asarray(masks, dtype=float)
    if masks.ndim != 2 or masks.shape[1] != nominal.size:
        raise InputError("masks", masks.shape, f"must be (conditions, {nominal.size}), one row per K-condition")
    highest = np.array([nominal[row > 0].max(initial=0.0) for row in masks])
    return np.clip(float(limit_A) - highest, 0.0, None)


class ManagedBlockageProxy:
    """The managed-blockage proxy (module docstring) as CasADi expressions.

    Parameters
    ----------
    model : ThermalModel
        The plant with the coolant-flow effect at full flow (:func:`~studies.chapter7.blockable`).
    names : sequence of str
        Fitted plant parameters (as :class:`~studies.chapter7.ProxySimulator`).
    dt_s : float
        Sample period, s.
    k_flow : float or None
        Flow fraction of the blockage when it is not among ``names``.
    inlet_rise_C, inlet_rise_tau_s : float
        Inlet rise of gen1 from the onset on, K, and its time constant, s.
    onset_s : float
        Fault onset, s.
    rest_s : float
        Rest of both generators before landing, s (thesis simulation 10 min, rig 20 min).
    inlet_rise_of : callable, optional
        ``inlet_rise_of(time_s, gen1_current)`` → the inlet rise of gen1 (1, n) as a CasADi expression
        (e.g. of a fitted amplitude and time constant, or of the current gen1 carries after
        displacement), replacing ``inlet_rise_C`` and ``inlet_rise_tau_s``.
    inlet_load_share : float
        Share of gen1's inlet rise that follows its load, in [0, 1]
        (:func:`genthermal.coolant.inlet_load_factor` of gen1's current against the undisplaced
        one); 0 (default): the fault's rise alone. Not with ``inlet_rise_of``.
    per_level : bool
        One displaced current per level of each K-condition (its 5-min start-up level and its
        continuous level, :func:`level_masks`) instead of one per K-condition (eq. 7.3, default).

    Attributes
    ----------
    masks : ndarray, shape (4, n)
        Where each K-condition runs (the windows of its peaks).
    displacement_masks : ndarray, shape (m, n)
        Where each displaced current of :attr:`displaced` applies (``masks``, or the levels).
    displacement_names : tuple of str
        Name of each displaced current.
    """

    def __init__(self, model: ThermalModel, names, dt_s: float, k_flow: float | None, inlet_rise_C: float,
                 inlet_rise_tau_s: float, onset_s: float, rest_s: float = REST_BEFORE_LANDING_S, inlet_rise_of=None,
                 inlet_load_share: float = 0.0, per_level: bool = False):
        self.names = list(names)
        if inlet_load_share != 0 and inlet_rise_of is not None:
            raise InputError("inlet_load_share", inlet_load_share, "give it or inlet_rise_of, not both")
        line = managed_timeline(dt_s, rest_s)
        self.time_s, self.masks = line["time_s"], line["masks"]
        if per_level:
            self.displacement_masks, self.displacement_names = level_masks(line)
        else:
            self.displacement_masks, self.displacement_names = self.masks, tuple(c[0] for c in CONDITIONS)
        self.nominal_current_A = line["current_A"]
        generator = model.spec.interface.generator
        mission = line["mission"]
        self.ambient_C = mission.T_ambient_C
        current = line["current_A"]
        law = generator.exciter_law
        exciter = law(current, mission.power_factor, mission.rated_current_A)
        step = 1e-3  # A: the tangent of the AVR law about the nominal current (it is nearly linear there)
        slope = (law(current + step, mission.power_factor, mission.rated_current_A) - exciter) / step
        frame = np.zeros((len(model.input_names), self.time_s.size))
        index = model.input_names.index
        for name in generator.phase_inputs:
            frame[index(name)] = current
        frame[index(generator.excitation_input)] = exciter
        frame[index(generator.coolant_input)] = mission.T_inlet_C
        frame[index(generator.ambient_input)] = mission.T_ambient_C
        blocked = frame.copy()
        # the inlet of gen1 rises from the onset on in flight time (the inserted rest included)
        blocked[index(generator.coolant_input)] += inlet_rise(self.time_s, onset_s, inlet_rise_C, inlet_rise_tau_s)
        # inputs per ampere moved off gen1: -1 A on each phase, the AVR law's tangent on the exciter
        per_amp = np.zeros_like(frame)
        for name in generator.phase_inputs:
            per_amp[index(name)] = 1.0
        per_amp[index(generator.excitation_input)] = slope
        self.displaced = ca.MX.sym("displaced", self.displacement_masks.shape[0])
        moved_A = ca.mtimes(ca.DM(self.displacement_masks).T, self.displaced).T  # (1, n): current off gen1
        moved = ca.DM(per_amp) * ca.repmat(moved_A, frame.shape[0], 1)
        self.inputs = {"gen1": ca.DM(blocked) - moved, "gen2": ca.DM(frame) + moved}
        inlet_load_factor(1.0, 1.0, inlet_load_share)  # rejects a share outside [0, 1], naming it
        if inlet_rise_of is None and inlet_load_share != 0:
            fault_rise = ca.DM(inlet_rise(self.time_s, onset_s, inlet_rise_C, inlet_rise_tau_s)).T

            def inlet_rise_of(time_s, gen1_current):
                return fault_rise * inlet_load_factor(gen1_current, ca.DM(current).T, inlet_load_share)
        if inlet_rise_of is not None:
            gen1_current = ca.DM(current).T - moved_A
            row = np.zeros((frame.shape[0], 1))
            row[index(generator.coolant_input)] = 1.0
            self.inputs["gen1"] = ca.DM(frame) - moved + ca.mtimes(ca.DM(row), inlet_rise_of(self.time_s, gen1_current))
        after = int(np.argmax(self.time_s >= onset_s - 1e-9))
        blockage = {"k_flow": "k_flow" if "k_flow" in self.names else float(k_flow)}
        self.simulators = {
            "gen1": ParametricSimulator(model, dt_s, blocked, self.names, [{"k_flow": 1.0}, blockage]),
            "gen2": ParametricSimulator(model, dt_s, frame, self.names, [{"k_flow": 1.0}])}
        self.indicators = {"gen1": self.simulators["gen1"].indicator([after]),
                           "gen2": self.simulators["gen2"].indicator()}

    def displacement_upper_A(self, receiver_limit_A: float | None = None) -> np.ndarray:
        """Upper bound of each displaced current of :attr:`displaced`, A: :data:`DISPLACEMENT_BOUNDS_A`,
        and with ``receiver_limit_A`` (A) the receiver's headroom under it (:func:`receiver_headroom_A`)."""
        upper = np.full(self.displacement_masks.shape[0], DISPLACEMENT_BOUNDS_A[1])
        if receiver_limit_A is None:
            return upper
        return np.minimum(upper, receiver_headroom_A(self.nominal_current_A, self.displacement_masks, receiver_limit_A))

    def peaks(self, theta, softmax_K: float) -> dict:
        """Smooth winding peaks (°C) of gen1 and gen2 in each K-condition: name → (4,) expressions of
        ``theta`` and :attr:`displaced`."""
        peaks = {}
        for unit, simulator in self.simulators.items():
            # both start cold, every node at the mission's ambient (x0 = a (steady - inlet) + c, a = 0)
            winding = simulator.symbolic(theta, ca.DM([0.0, self.ambient_C]), ca.DM(self.indicators[unit]),
                                         self.inputs[unit])[0, :]
            values = []
            for mask in self.masks:
                inside = np.flatnonzero(mask > 0)
                window = ca.horzcat(*[winding[i] for i in inside])
                values.append(softmax_K * ca.logsumexp(window.T / softmax_K))
            peaks[unit] = ca.vertcat(*values)
        return peaks

    def residuals(self, theta, softmax_K: float):
        """Excess of each generator's peak over :data:`LIMIT_C` per K-condition, K (8,)."""
        peaks = self.peaks(theta, softmax_K)
        return ca.vertcat(*[smooth_excess(peaks[u], LIMIT_C) for u in ("gen1", "gen2")])


def best_displacement(plant: ThermalModel, k_flow: float, n_flow: float, inlet_rise_C: float,
                      inlet_rise_tau_s: float, onset_s: float, dt_s: float = 30.0,
                      softmax_K: float = 0.1, inlet_load_share: float = 0.0, per_level: bool = False,
                      receiver_limit_A: float | None = None) -> dict:
    """The displaced currents that give the managed-blockage proxy of ``plant`` (blockage values
    fixed) its lowest worst peak, by IPOPT over the four currents (minimise the bound :math:`w` on
    every K-condition's smooth peak of both generators): what the thesis's outcome asks of the
    plant, free of any manager's prediction error and of a current limit.

    Parameters
    ----------
    plant : ThermalModel
        The plant of both generators (the chapter-7 scenarios fly the model itself).
    k_flow, n_flow : float
        Flow fraction and convection exponent of the large blockage.
    inlet_rise_C, inlet_rise_tau_s : float
        Inlet rise of gen1 after the onset, K, and its time constant, s.
    onset_s : float
        Fault onset, s.
    dt_s, softmax_K : float
        Sample period (s) and smoothness of the peaks (K).
    inlet_load_share : float
        Share of gen1's inlet rise that follows its load (:func:`genthermal.coolant.inlet_load_factor`).
    per_level : bool
        One displaced current per level (5-min start-up, continuous) of each K-condition
        (:class:`ManagedBlockageProxy`); default one per K-condition (eq. 7.3).
    receiver_limit_A : float or None
        Highest current the receiver gen2 may carry at any instant, A (:func:`receiver_headroom_A`);
        None (default): no limit, θmax alone.

    Returns
    -------
    dict
        ``conditions`` (condition, displaced_A: the largest of its currents, gen1_peak_C, gen2_peak_C),
        ``displaced_A`` (name → A, one per displaced current), ``worst_peak_C`` (the
        lowest reachable highest smooth peak of either generator, °C), ``worst_excess_K`` (over
        :data:`LIMIT_C`), ``receiver_max_current_A`` (the most gen2 carries, A), ``converged``.
    """
    from .chapter7 import blockable  # chapter7 imports this module

    if not (isinstance(k_flow, (int, float)) and 0.0 < k_flow <= 1.0):
        raise InputError("k_flow", k_flow, "must be a flow fraction in (0, 1]")
    if not (isinstance(n_flow, (int, float)) and 0.0 <= n_flow <= 1.5):
        raise InputError("n_flow", n_flow, "must be a convection exponent in [0, 1.5] (the effect's range)")
    model = blockable(plant)
    proxy = ManagedBlockageProxy(model, ["k_flow", "n_flow"], dt_s, None, inlet_rise_C, inlet_rise_tau_s, onset_s,
                                 inlet_load_share=inlet_load_share, per_level=per_level)
    n = proxy.displaced.numel()
    upper = proxy.displacement_upper_A(receiver_limit_A)
    peaks = proxy.peaks(ca.DM([k_flow, n_flow]), softmax_K)
    every = ca.vertcat(peaks["gen1"], peaks["gen2"])
    d, bound = proxy.displaced, ca.MX.sym("worst")
    solver = ca.nlpsol("managed_displacement", "ipopt",
                       {"x": ca.vertcat(d, bound), "f": bound + 1e-6 * ca.sumsqr(d), "g": every - bound},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-8})
    solution = solver(x0=np.minimum(1.0, upper).tolist() + [150.0], lbx=[DISPLACEMENT_BOUNDS_A[0]] * n + [-ca.inf],
                      ubx=upper.tolist() + [ca.inf], ubg=0.0)
    x = np.asarray(solution["x"]).ravel()
    displaced = x[:n]
    gen1, gen2 = (np.asarray(v).ravel() for v in ca.Function("peaks", [d], [peaks["gen1"], peaks["gen2"]])(displaced))
    worst = float(max(gen1.max(), gen2.max()))
    per_condition = [float(np.max(displaced[(proxy.displacement_masks[:, row > 0] > 0).any(axis=1)]))
                     for row in proxy.masks]
    return {"conditions": [{"condition": c[0], "displaced_A": v, "gen1_peak_C": float(a), "gen2_peak_C": float(b)}
                           for c, v, a, b in zip(CONDITIONS, per_condition, gen1, gen2)],
            "displaced_A": {name: float(v) for name, v in zip(proxy.displacement_names, displaced)},
            "worst_peak_C": worst, "worst_excess_K": worst - LIMIT_C,
            "receiver_max_current_A": float(np.max(proxy.nominal_current_A + proxy.displacement_masks.T @ displaced)),
            "converged": bool(solver.stats()["success"])}
