r"""Can any chapter-7 calibration meet every published chapter-7 outcome? A minimax feasibility study.

The chapter-7 calibration (:mod:`studies.chapter7`) meets three outcomes of the thesis
(the +4 K and +16 K thresholds, the no-action blockage) and misses the fourth, the managed large
blockage (7.3.3, Figs 7.13-7.15). Here every assumed value is free within its physical bounds at
once, and IPOPT (exact derivatives) minimises the **largest violation** over all outcomes. If the
minimum is at or below zero a calibration meets them all; if not, the minimum is how far the
thesis's outcomes are apart on this machine, and the Pareto trace (:func:`pareto_trace`) shows what
the managed outcome costs the others.

Outcomes as inequalities on the winding temperature, K (positive: violated by that much)
-----------------------------------------------------------------------------------------
Each outcome is stated with the tolerance the thesis gives it, so a violation of 0 meets it and the
violations share one unit (K of winding temperature past the outcome's band):

``landing_3K`` / ``landing_4K``
    7.3.3: "at an increase of 4 °C requires a short rest and load adjust before landing. At
    increases of less than 4 °C the faulty generator is able to cope". The manager acts on its
    prediction, which stands ``lag`` K from the plant (:func:`~studies.chapter7.manager_lags`),
    so with an inlet step of +3 K the plant's landing peak is at most :math:`\theta_{max}` + lag, and
    with +4 K at least. (A 1-K resolution of the thesis's search, the step between its two cases.)
``cruise_combat_15K`` / ``cruise_combat_16K``
    The same for cruise/combat: +16 K is the smallest rise that needs displacement there (the
    thesis increased the fault "until the spare capacity ... was used"; the same 1-K resolution).
``blockage_34min`` / ``blockage_54min``
    7.3.1, Fig 7.5 (a rig test): with the large blockage and no action the winding reached 109 °C
    44 min after the fault; the issue's tolerance ±10 min: at 34 min at most 109 °C, at 54 min at
    least 109 °C.
``blockage_cruise_110C``
    The same test was switched off at 109 °C "before the upper limit of 110 °C was breached", 111
    min into the flight, inside the first cruise after the fault (66-120 min); so without action the
    winding passes 110 °C in that cruise, which is why the managed flight displaces load there
    ("the next 3 K-conditions are accommodated using only load displacement"): the no-action
    peak in that cruise is at least 110 °C.
``managed_<unit>_<condition>``
    7.3.3, Figs 7.13-7.15: with displacement alone in the three K-conditions after the fault and a
    rest of both before landing (10 min in simulation; the rig rested 20, ``rest_s``), "the
    generator remains below 110 °C except for two small breaches of 110.7 °C ... and 111 °C": every
    K-condition's peak of both generators at most :data:`MANAGED_LIMIT_C` = 111 °C, on the plant
    (:class:`~studies.chapter7_managed.ManagedBlockageProxy`; displaced currents are
    decision variables, the healthy generator held by no current limit, as eqs. 7.2-7.4 hold it by
    θmax alone).

The rated-current reading (``receiver_limit_A``)
------------------------------------------------
7.3.3 also says "during landing there is very little spare capacity in either the faulty or healthy
generators", which holds if "spare capacity" means current below the rating: a receiver held to its
rated current :math:`I_r` (7 A). With ``receiver_limit_A`` the study holds gen2 to that limit at every
instant: a constant displacement :math:`I_d(k)` (eq. 7.3-7.4) is at most :math:`I_r` less the highest
nominal current of its K-condition (:func:`~studies.chapter7_managed.receiver_headroom_A`), so none where the nominal load
reaches 100 % (landing's first 5 min). With ``per_level`` each K-condition's 5-min start-up level and
its continuous level have a displaced current of their own (as the heuristic's plan segments do),
so landing's continuous level (76.7 %) can pass up to 1.63 A to a receiver held to 7 A.

Free values and their bounds
----------------------------
The machine's assumed cooling and loss values of :data:`~studies.chapter7.FIT_BOUNDS`
plus ``h_air_gap``; the blockage's flow fraction ``k_flow`` (the orifice mapping: its bounds are the
orifice relation's for an open-outlet loss share of 0.5 to 0.003) and convection exponent
``n_flow``; the inlet rise of the blockage, its amplitude (7.3.3: "around 51 °C", taken as ±5 K:
:data:`INLET_RISE_BOUNDS_K`) and time constant (:data:`INLET_TAU_BOUNDS_MIN`); with
``inlet_follows_load`` also the share :math:`\alpha` of the rise that follows gen1's load (7.3.3:
the inlet temperature "is dependent upon both the fault and the load"): rise
:math:`\Delta T\,(1 - e^{-(t-t_0)/\tau})\,(1 - \alpha + \alpha (I_1/I_{nom})^2)`, with
:math:`I_1` the current gen1 carries after displacement (its heat recirculated into the inlet) and
:math:`I_{nom}` its undisplaced share; the factor is :func:`genthermal.coolant.inlet_load_factor`,
the one a scenario's fault with ``inlet_load_share`` flies.

The plant of the chapter-7 scenarios is the model itself (7.3.2: "two copies of the simulation
model"); the healthy generator's inlet does not rise (7.3.2: it "will be unaffected for the
duration of the test").

Peaks are smooth maxima (log-sum-exp, :data:`~studies.chapter7.SOFTMAX_K`); the
problem is :math:`\min w` subject to every violation :math:`\le w` (or, for the Pareto trace, the
managed peaks at most a cap and the others :math:`\le w`), from several starts.
"""

from __future__ import annotations

import dataclasses
import math

import casadi as ca
import numpy as np

from genthermal.coolant import inlet_load_factor
from genthermal.diagnose.trajectory import ParametricSimulator, Scaling
from genthermal.errors import InputError
from genthermal.mission import load_mission
from genthermal.model import ThermalModel
from .chapter7 import (BLOCKAGE_INLET_RISE_C, BLOCKAGE_MINUTES, DT_S, FIT_BOUNDS, INLET_TAU_BOUNDS_MIN, ONSET_S,
                       PLANNING_LIMIT_C, PROXIES, SOFTMAX_K, Proxy, ProxySimulator, blockable, manager_lags)
from .chapter7_managed import CONDITIONS, DISPLACEMENT_BOUNDS_A, REST_BEFORE_LANDING_S, ManagedBlockageProxy

#: Highest winding temperature the thesis's managed blockage reached, °C (7.3.3: breaches of 110.7 and 111 °C).
MANAGED_LIMIT_C = 111.0
#: Winding temperature at which the no-action blockage was switched off, °C (7.3.1, Fig 7.5).
SWITCH_OFF_C = 109.0
#: Tolerance on the 44 min to 109 °C, min (issue 14: "44 ± 10 min after the fault").
BLOCKAGE_TOLERANCE_MIN = 10.0
#: Inlet rises either side of each manager threshold, K (7.3.3: +4 K acts, "less than 4" does not;
#: +16 K acts in cruise/combat, taken with the same 1-K resolution below it).
THRESHOLD_RISES_K = {"landing": (3.0, 4.0), "cruise_combat": (15.0, 16.0)}
#: Amplitude of the blockage's inlet rise, K: 7.3.3 "around 51 °C" from 20 °C, taken as 51 ± 5 °C.
INLET_RISE_BOUNDS_K = (BLOCKAGE_INLET_RISE_C - 5.0, BLOCKAGE_INLET_RISE_C + 5.0)
#: Time constant of the inlet rise, min: 1 min (nearly a step) to the fit's 90 min.
INLET_TAU_RANGE_MIN = (1.0, INLET_TAU_BOUNDS_MIN[1])
#: Air-gap convection bounds, W/(m² K): rotating gap at 1500 rpm (as :data:`FIT_BOUNDS`).
H_AIR_GAP_BOUNDS = FIT_BOUNDS["h_air_gap"]
#: Smoothness of the peaks that check a solution, K: the sharp maximum of the samples within a few mK.
SHARP_K = 0.002
#: Machine values free in the study (all assumed values of the thermal model's cooling and losses).
MACHINE_NAMES = ("h_top_air", "h_end_air", "R0", "h_air_gap", "P_iron", "h_ambient", "m_dot_fan")
#: Blockage values free in the study.
BLOCKAGE_NAMES = ("n_flow", "k_flow")


@dataclasses.dataclass(frozen=True)
class Start:
    """One starting point: plant values (name → value; missing: the reference of the scaling, the
    plant's own), inlet rise (K), its time constant (min) and load share."""

    label: str
    values: dict
    inlet_rise_K: float = BLOCKAGE_INLET_RISE_C
    inlet_tau_min: float = 0.5 * (INLET_TAU_BOUNDS_MIN[0] + INLET_TAU_BOUNDS_MIN[1])
    load_share: float = 0.0


class FeasibilityProblem:
    """The violations of every chapter-7 outcome (module docstring) as CasADi expressions of one
    decision vector.

    Parameters
    ----------
    plant : ThermalModel
        Plant whose values are the reference of the scalings (the chapter-7 calibration).
    lags : dict
        Manager prediction lag per threshold (``landing``, ``cruise_combat``), K (plant peak less
        the manager's highest predicted peak; :func:`~studies.chapter7.manager_lags`).
    rest_s : float
        Rest before landing in the managed outcome, s (thesis simulation 600, rig 1200).
    inlet_follows_load : bool
        Free the share of the blockage's inlet rise that follows gen1's load (else 0: the rise is
        the fault's alone, as the scenarios fly it).
    dt_s : float
        Sample period, s.
    softmax_K : float
        Smoothness of the peaks, K (the study's :data:`~studies.chapter7.SOFTMAX_K`; a
        few mK gives the sharp peaks of the samples, to check a solution).
    receiver_limit_A : float or None
        Highest phase current the receiver gen2 may carry at any instant, A (the rated-current
        reading: the mission's rated current, 7 A); None (default): no limit, θmax alone (eqs. 7.2-7.4).
    per_level : bool
        One displaced current per level of each K-condition (its 5-min start-up and continuous
        levels, as the heuristic plans them) instead of one per K-condition (eq. 7.3, default): with
        ``receiver_limit_A`` this lets the receiver take load in landing's continuous level.
    """

    def __init__(self, plant: ThermalModel, lags: dict, rest_s: float = REST_BEFORE_LANDING_S,
                 inlet_follows_load: bool = False, dt_s: float = DT_S, softmax_K: float = SOFTMAX_K,
                 receiver_limit_A: float | None = None, per_level: bool = False):
        if receiver_limit_A is not None and not (isinstance(receiver_limit_A, (int, float))
                                                 and math.isfinite(receiver_limit_A) and receiver_limit_A > 0):
            raise InputError("receiver_limit_A", receiver_limit_A, "must be a current > 0 A or None (no limit)")
        self.receiver_limit_A = None if receiver_limit_A is None else float(receiver_limit_A)
        if not (isinstance(softmax_K, (int, float)) and math.isfinite(softmax_K) and softmax_K > 0):
            raise InputError("softmax_K", softmax_K, "must be a smoothness > 0 K")
        self.softmax_K = float(softmax_K)
        for key in THRESHOLD_RISES_K:
            if key not in lags or not math.isfinite(float(lags[key])):
                raise InputError(f"lags.{key}", lags.get(key), "must be a finite manager prediction lag, K")
        self.names = list(MACHINE_NAMES + BLOCKAGE_NAMES)
        self.lags = {k: float(lags[k]) for k in THRESHOLD_RISES_K}
        self.rest_s, self.inlet_follows_load = float(rest_s), bool(inlet_follows_load)
        model = blockable(plant)
        bounds = {**FIT_BOUNDS, "h_air_gap": H_AIR_GAP_BOUNDS}
        reference = {n: (model.parameters.value(n) if n != "k_flow" else 0.3) for n in self.names}
        reference = {n: float(np.clip(v, bounds[n][0], bounds[n][1])) for n, v in reference.items()}
        self.scalings = [Scaling("log", reference[n], 1.0, bounds[n][0], bounds[n][1]) for n in self.names]
        self.bounds = bounds
        n = len(self.names)
        # decision: scaled plant values, inlet rise K, time constant min, load share, displaced currents A
        self.z = ca.MX.sym("z", n)
        self.rise_K, self.tau_min, self.share = ca.MX.sym("inlet_rise_K"), ca.MX.sym("inlet_tau_min"), ca.MX.sym("load_share")
        theta = ca.vertcat(*[s.value(self.z[i]) for i, s in enumerate(self.scalings)])
        self.theta = theta
        self.violations = {}
        self._threshold_violations(plant, theta)
        self._blockage_violations(model, theta, dt_s)
        self.managed = ManagedBlockageProxy(model, self.names, dt_s, None, 0.0, 0.0, ONSET_S, self.rest_s,
                                            inlet_rise_of=self._gen1_inlet_rise, per_level=per_level)
        self.managed_peaks = self.managed.peaks(theta, self.softmax_K)
        for unit in ("gen1", "gen2"):
            for i, (condition, _, _) in enumerate(CONDITIONS):
                self.violations[f"managed_{unit}_{condition}"] = self.managed_peaks[unit][i] - MANAGED_LIMIT_C
        self.decision = ca.vertcat(self.z, self.rise_K, self.tau_min, self.share, self.managed.displaced)

    # --- outcomes ---------------------------------------------------------------------------
    def _threshold_violations(self, plant: ThermalModel, theta) -> None:
        windows = {p.name: p.window_s for p in PROXIES if p.manager_threshold}
        proxies = [Proxy(f"{name}_{rise:g}K", rise, None, windows[name], PLANNING_LIMIT_C + self.lags[name],
                         f"7.3.3 threshold of the manager in {name}", manager_threshold=True)
                   for name, rises in THRESHOLD_RISES_K.items() for rise in rises]
        simulator = ProxySimulator(plant, self.names, proxies)
        for proxy, peak in zip(proxies, simulator.peaks(theta, self.softmax_K)):
            below = proxy.inlet_rise_C == min(THRESHOLD_RISES_K[proxy.name.rsplit("_", 1)[0]])
            self.violations[proxy.name] = (peak - proxy.target_C) if below else (proxy.target_C - peak)

    def _inlet_rise(self, time_s: np.ndarray):
        """The blockage's inlet rise without its load share, (1, n) expression, K."""
        elapsed = np.clip(time_s - ONSET_S, 0.0, None)
        started = ca.DM((time_s >= ONSET_S - 1e-9).astype(float)).T
        return self.rise_K * started * (1 - ca.exp(-ca.DM(elapsed).T / (60.0 * self.tau_min)))

    def _gen1_inlet_rise(self, time_s: np.ndarray, gen1_current):
        """Inlet rise of the managed gen1: the fault's, times the load factor of
        :func:`genthermal.coolant.inlet_load_factor` (the one the power system flies) of gen1's
        current against its undisplaced share, the timeline's nominal current (displacement moves
        current from gen1 to gen2, so that is the two generators' mean, as
        :meth:`~genthermal.schedule.power_system.PowerSystem.inlet_C` takes it)."""
        nominal = ca.DM(self.managed_nominal_current(time_s)).T
        return self._inlet_rise(time_s) * inlet_load_factor(gen1_current, nominal, self.share)

    def managed_nominal_current(self, time_s: np.ndarray) -> np.ndarray:
        """Phase current of the managed timeline (sampled as ``time_s``) before any displacement, A."""
        from .chapter7_managed import managed_timeline

        line = managed_timeline(float(time_s[1] - time_s[0]), self.rest_s)
        return line["current_A"]

    def _blockage_violations(self, model: ThermalModel, theta, dt_s: float) -> None:
        mission = load_mission("thesis_fig_7_7")
        frame = mission.to_inputs(dt_s)
        time_s = frame["time_s"].to_numpy()
        inputs = frame[list(model.input_names)].to_numpy().T.copy()
        simulator = ParametricSimulator(model, dt_s, inputs, self.names, [{"k_flow": 1.0}, {"k_flow": "k_flow"}])
        indicator = simulator.indicator([int(np.argmax(time_s >= ONSET_S - 1e-9))])
        row = np.zeros((inputs.shape[0], 1))
        row[model.input_names.index(model.spec.interface.generator.coolant_input)] = 1.0
        symbolic_inputs = ca.DM(inputs) + ca.mtimes(ca.DM(row), self._inlet_rise(time_s))
        winding = simulator.symbolic(theta, ca.DM([0.0, mission.T_ambient_C]), ca.DM(indicator), symbolic_inputs)[0, :]
        cruise = [i for i, t in enumerate(time_s) if CONDITIONS[0][1] - 1e-9 <= t < CONDITIONS[0][2] - 1e-9]
        peak = self.softmax_K * ca.logsumexp(ca.horzcat(*[winding[i] for i in cruise]).T / self.softmax_K)
        self.violations["blockage_cruise_110C"] = PLANNING_LIMIT_C - peak
        for minutes, sign in ((BLOCKAGE_MINUTES - BLOCKAGE_TOLERANCE_MIN, 1.0),
                              (BLOCKAGE_MINUTES + BLOCKAGE_TOLERANCE_MIN, -1.0)):
            k = int(round((ONSET_S + 60.0 * minutes) / dt_s))
            self.violations[f"blockage_{minutes:g}min"] = sign * (winding[k] - SWITCH_OFF_C)

    # --- decision vector ----------------------------------------------------------------------
    def bounds_and_start(self, start: Start) -> tuple[list, list, list]:
        """Lower and upper bounds of :attr:`decision` and its value at ``start``."""
        lower = [s.bounds()[0] for s in self.scalings] + [INLET_RISE_BOUNDS_K[0], INLET_TAU_RANGE_MIN[0], 0.0]
        upper = [s.bounds()[1] for s in self.scalings] + [INLET_RISE_BOUNDS_K[1], INLET_TAU_RANGE_MIN[1],
                                                          1.0 if self.inlet_follows_load else 0.0]
        lower += [DISPLACEMENT_BOUNDS_A[0]] * self.managed.displaced.numel()
        upper += self.displacement_upper_A().tolist()
        values = [s.decision(float(np.clip(start.values.get(n, s.reference), s.lower, s.upper)))
                  for n, s in zip(self.names, self.scalings)]
        values += [start.inlet_rise_K, start.inlet_tau_min, start.load_share if self.inlet_follows_load else 0.0]
        values += [0.5] * self.managed.displaced.numel()
        return lower, upper, list(np.clip(values, lower, upper))

    def displacement_upper_A(self) -> np.ndarray:
        """Upper bound of each displaced current, A, with :attr:`receiver_limit_A`
        (:meth:`~studies.chapter7_managed.ManagedBlockageProxy.displacement_upper_A`)."""
        return self.managed.displacement_upper_A(self.receiver_limit_A)

    def describe(self, x) -> dict:
        """Values, violations (K) and managed displacement at the decision ``x``."""
        x = np.asarray(x, dtype=float).ravel()
        n = len(self.names)
        names = list(self.violations)
        evaluate = ca.Function("violations", [self.decision], [ca.vertcat(*self.violations.values())])
        violations = dict(zip(names, np.asarray(evaluate(x)).ravel().tolist()))
        managed = [v for k, v in violations.items() if k.startswith("managed_")]
        others = {k: v for k, v in violations.items() if not k.startswith("managed_")}
        displaced = x[n + 3:]
        nominal = self.managed_nominal_current(self.managed.time_s)
        receiver_max = float(np.max(nominal + self.managed.displacement_masks.T @ displaced))
        return {"values": {name: s.value(float(v)) for name, s, v in zip(self.names, self.scalings, x[:n])},
                "inlet_rise_K": float(x[n]), "inlet_tau_min": float(x[n + 1]), "inlet_load_share": float(x[n + 2]),
                "displaced_A": {name: float(d) for name, d in zip(self.managed.displacement_names, displaced)},
                "receiver_max_current_A": receiver_max, "receiver_limit_A": self.receiver_limit_A,
                "violations_K": violations, "worst_violation_K": max(violations.values()),
                "worst_outcome": max(violations, key=violations.get),
                "managed_peak_C": MANAGED_LIMIT_C + max(managed), "others_worst_violation_K": max(others.values()),
                "others_worst_outcome": max(others, key=others.get),
                "at_bound": self._at_bound(x)}

    def _at_bound(self, x) -> list:
        n = len(self.names)
        hits = [name for name, s, v in zip(self.names, self.scalings, x[:n])
                if min(abs(v - s.bounds()[0]), abs(v - s.bounds()[1])) < 1e-4]
        for label, value, (low, high) in (("inlet_rise_K", x[n], INLET_RISE_BOUNDS_K),
                                          ("inlet_tau_min", x[n + 1], INLET_TAU_RANGE_MIN)):
            if min(abs(value - low), abs(value - high)) < 1e-3:
                hits.append(label)
        if self.inlet_follows_load and min(abs(x[n + 2]), abs(x[n + 2] - 1.0)) < 1e-3:
            hits.append("inlet_load_share")
        return hits


def minimise_worst_violation(problem: FeasibilityProblem, start: Start, managed_cap_C: float | None = None,
                             others_cap_K: float | None = None, x0=None, max_iter: int = 400) -> dict:
    """IPOPT: the least :math:`w` with every violation :math:`\\le w` (exact derivatives).

    Pareto points between the managed outcome and the others: ``managed_cap_C`` holds every managed
    peak at or below that temperature and minimises the largest violation of the other outcomes;
    ``others_cap_K`` holds every other violation at or below that many K and minimises the highest
    managed peak. ``x0`` (a previous solution's ``decision``) overrides the start's values.

    Returns
    -------
    dict
        :meth:`FeasibilityProblem.describe` of the solution plus ``start``, ``decision`` (list),
        ``converged``, ``iterations``, ``solve_s``, ``managed_cap_C``, ``others_cap_K``.
    """
    import time

    for field, value in (("managed_cap_C", managed_cap_C), ("others_cap_K", others_cap_K)):
        if value is not None and not (isinstance(value, (int, float)) and math.isfinite(value)):
            raise InputError(field, value, "must be a finite temperature (°C) or violation (K)")
    if managed_cap_C is not None and others_cap_K is not None:
        raise InputError("others_cap_K", others_cap_K, "cannot be given with managed_cap_C (one Pareto cap at a time)")
    lower, upper, values = problem.bounds_and_start(start)
    if x0 is not None:
        values = list(np.clip(np.asarray(x0, dtype=float).ravel(), lower, upper))
    worst = ca.MX.sym("worst")
    managed = [v for k, v in problem.violations.items() if k.startswith("managed_")]
    others = [v for k, v in problem.violations.items() if not k.startswith("managed_")]
    if managed_cap_C is not None:
        bounded, capped, cap = others, managed, managed_cap_C - MANAGED_LIMIT_C
    elif others_cap_K is not None:
        bounded, capped, cap = managed, others, others_cap_K
    else:
        bounded, capped, cap = managed + others, [], 0.0
    constraints = [v - worst for v in bounded] + [v - cap for v in capped]
    n_displaced = problem.managed.displaced.numel()
    regulariser = 1e-4 * ca.sumsqr(problem.z) + 1e-4 * ca.sumsqr(problem.decision[-n_displaced:])
    solver = ca.nlpsol("chapter7_feasibility", "ipopt",
                       {"x": ca.vertcat(problem.decision, worst), "f": worst + regulariser, "g": ca.vertcat(*constraints)},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-7,
                        "ipopt.max_iter": max_iter})
    started = time.perf_counter()
    evaluate = ca.Function("bounded", [problem.decision], [ca.vertcat(*bounded)])
    w0 = float(np.max(np.asarray(evaluate(values)).ravel()))
    solution = solver(x0=values + [w0], lbx=lower + [-ca.inf], ubx=upper + [ca.inf], ubg=[0.0] * len(constraints),
                      lbg=[-ca.inf] * len(constraints))
    x = np.asarray(solution["x"]).ravel()[:-1]
    stats = solver.stats()
    return {"start": start.label, "managed_cap_C": managed_cap_C, "others_cap_K": others_cap_K,
            **problem.describe(x), "decision": x.tolist(),
            "converged": bool(stats["success"]), "iterations": int(stats["iter_count"]),
            "solve_s": time.perf_counter() - started}


def default_starts(chapter7: ThermalModel, default: ThermalModel) -> tuple[Start, ...]:
    """Starts of the study: the shipped chapter-7 calibration with the blockage of
    ``scenarios/chapter7_blockage_large.yaml``, the chapter-3-5 default (same blockage, a faster
    inlet), and the geometric centre of every bound."""
    from genthermal.schedule.power_system import PowerSystem

    fault = PowerSystem.from_mission(load_mission("chapter7_blockage_large")).faults[0]
    bounds = {**FIT_BOUNDS, "h_air_gap": H_AIR_GAP_BOUNDS}
    blockage = {n: fault.values[n] for n in BLOCKAGE_NAMES}
    return (Start("shipped chapter7", {**{n: chapter7.parameters.value(n) for n in MACHINE_NAMES}, **blockage},
                  fault.inlet_rise_C, fault.inlet_rise_tau_s / 60.0, fault.inlet_load_share),
            Start("default (ch. 3-5)", {**{n: default.parameters.value(n) for n in MACHINE_NAMES}, **blockage},
                  inlet_tau_min=20.0),
            Start("centre of the bounds", {n: math.sqrt(bounds[n][0] * bounds[n][1]) for n in MACHINE_NAMES + BLOCKAGE_NAMES},
                  inlet_tau_min=45.0))


def pareto_trace(problem: FeasibilityProblem, best: dict, managed_caps_C=(), others_caps_K=()) -> list:
    """The trade-off between the managed outcome and the others, each point warm-started from ``best``:
    for each cap on the managed peaks (°C) the least worst violation of the other outcomes, and for
    each cap on the others' violations (K) the lowest highest managed peak."""
    points = [minimise_worst_violation(problem, Start("pareto", {}), managed_cap_C=float(cap), x0=best["decision"])
              for cap in managed_caps_C]
    points += [minimise_worst_violation(problem, Start("pareto", {}), others_cap_K=float(cap), x0=best["decision"])
               for cap in others_caps_K]
    return points


def measured_lags(model: ThermalModel) -> dict:
    """Manager prediction lags (K) of ``model`` at the two thresholds (:func:`~studies.chapter7.manager_lags`)."""
    return {name: value["lag_K"] for name, value in manager_lags(model).items()}


def calibrated_plant(base: ThermalModel, result: dict) -> ThermalModel:
    """``base`` with the machine values of a study ``result`` (the blockage's stay with the fault)."""
    from .chapter7 import fitted_model

    return fitted_model(base, {n: result["values"][n] for n in MACHINE_NAMES})


def study(chapter7: ThermalModel, default: ThermalModel, rest_s: float = REST_BEFORE_LANDING_S,
          inlet_follows_load: bool = False, rounds: int = 2, starts=None,
          receiver_limit_A: float | None = None, per_level: bool = False, lags_K: dict | None = None) -> dict:
    """The minimax study from every start, with the manager lags re-measured on the best solution
    and the problem solved again from it, ``rounds`` times in all (the lags depend on the values).
    ``receiver_limit_A`` holds the receiver to that current at every instant (the rated-current
    reading, :class:`FeasibilityProblem`); ``per_level`` gives each level of a K-condition its own
    displaced current. ``lags_K`` (``landing``, ``cruise_combat``, K) holds the manager lags at
    these values instead of measuring them on the design model's manager: zero for a manager that
    predicts on the simulation model itself (thesis 7.3.4, ``planner_model`` ``nonlinear``). With
    held lags there is nothing to re-measure and the study makes one round whatever ``rounds``.

    Returns
    -------
    dict
        ``starts`` (each start's first-round solution), ``best`` (the last round's), ``sharp`` (its
        violations with the sharp peaks of the samples, :data:`SHARP_K`), ``rounds``
        (per round: the lags used, the worst violation), ``problem`` (the last round's
        :class:`FeasibilityProblem`, not JSON).
    """
    if not (isinstance(rounds, int) and rounds >= 1):
        raise InputError("rounds", rounds, "must be an integer >= 1")
    lags = measured_lags(chapter7) if lags_K is None else dict(lags_K)
    problem = FeasibilityProblem(chapter7, lags, rest_s, inlet_follows_load, receiver_limit_A=receiver_limit_A,
                                 per_level=per_level)
    firsts = [minimise_worst_violation(problem, s) for s in (starts or default_starts(chapter7, default))]
    best = min(firsts, key=lambda r: r["worst_violation_K"])
    history = [{"lags_K": lags, "worst_violation_K": best["worst_violation_K"], "start": best["start"]}]
    for _ in range(rounds - 1 if lags_K is None else 0):  # held lags: nothing to re-measure
        lags = measured_lags(calibrated_plant(chapter7, best))
        problem = FeasibilityProblem(chapter7, lags, rest_s, inlet_follows_load, receiver_limit_A=receiver_limit_A,
                                     per_level=per_level)
        best = minimise_worst_violation(problem, Start("previous round", {}), x0=best["decision"])
        history.append({"lags_K": lags, "worst_violation_K": best["worst_violation_K"], "start": best["start"]})
    sharp = FeasibilityProblem(chapter7, lags, rest_s, inlet_follows_load, softmax_K=SHARP_K,
                               receiver_limit_A=receiver_limit_A, per_level=per_level).describe(best["decision"])
    return {"starts": firsts, "best": best, "sharp": {k: sharp[k] for k in ("violations_K", "worst_violation_K",
                                                                            "worst_outcome")},
            "rounds": history, "problem": problem}
