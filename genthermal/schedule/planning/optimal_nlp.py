"""Optimal load schedule on the flown nonlinear model: direct multiple shooting of the filter's
model in CasADi, IPOPT. Main objects: :func:`flown_optimal_plan`, :class:`NonlinearSettings`.
Method: docs/guide/flight-methods.md.
"""

from __future__ import annotations

import dataclasses
import time

import casadi as ca
import numpy as np

from ...discretise import ModalDecay, check_step_accuracy, phi_matrices, step_expression
from ...errors import InputError
from .heuristic import heuristic_plan
from .plan import PlanningProblem, PlanResult, Schedule, predict
from .price import SHED_PRICE_MIN_PER_AH, schedule_cost_min

#: Rests shorter than this (s) are interior-point residue and dropped.
MIN_REST_S = 1.0

#: Solvers kept per filter set (:meth:`FlownTranscription._solver`): the structures a flight is
#: using now (plans serving all load and shed plans, the padded horizons of a few re-plans), not
#: every one it ever built. A choice of this project.
MAX_CACHED_SOLVERS = 8


@dataclasses.dataclass(frozen=True)
class NonlinearSettings:
    """Settings of the transcription on the flown model.

    Attributes
    ----------
    substep_s : float
        Longest ETD2RK step inside an interval, s (60 s: one step and two half steps differ by
        2e-3 K at rated load on the thesis generator, :func:`~genthermal.discretise.check_step_accuracy`).
    rest_checks : int
        Temperature checks per rest.
    displacement_weight : float
        :math:`w`, s of mission time per A²·h of displaced current squared (as the affine
        transcription's).
    guess_margin_K : float
        Margin of the heuristic plan on the design model that is the initial guess when there is
        no previous plan, K (the affine planner's default, 2.5 K).
    backoff_passes : int
        Solves with the back-off updated from the previous solution's prediction, and the limit
        tightened by what that prediction (every 10 s) exceeded of the limit the NLP held (3: on
        the robustness grid's case 15 the shed plans of the flown model exceeded θmax by 0.1-0.3 K
        after two passes that only updated the back-off, and the manager fell back to the design
        model's shedding).
    max_iter : int
        IPOPT iteration limit.
    mu_init : float
        IPOPT's initial barrier parameter (1e-5: a re-plan warm-started from the previous plan took
        20 iterations instead of 25 at 1e-3 on ``blockage_large``, a cold start 37 either way).
    expand : bool
        Expand the NLP to scalar expressions (SX) before solving.
    """

    substep_s: float = 60.0
    rest_checks: int = 3
    displacement_weight: float = 1.0
    guess_margin_K: float = 2.5
    backoff_passes: int = 3
    max_iter: int = 200
    mu_init: float = 1e-5
    expand: bool = True

    def __post_init__(self):
        if not (np.isfinite(self.substep_s) and self.substep_s > 0):
            raise InputError("substep_s", self.substep_s, "must be a positive number of seconds")
        if not (isinstance(self.rest_checks, int) and self.rest_checks >= 1):
            raise InputError("rest_checks", self.rest_checks, "must be a whole number >= 1")


def _run_function(ekf, n_sub: int) -> ca.Function:
    """``(x, I, dist, u0, eI, h, E, G1, G2) -> (x_end, Y)``: ``n_sub`` ETD2RK steps of length ``h``
    (the step matrices flattened column-major)
    at phase current ``I`` (inputs ``u0 + I eI``) with the disturbances ``dist`` held; ``Y`` the
    outputs after each step. Cached per filter and substep count."""
    cache = ekf.__dict__.setdefault("_planning_run_functions", {})
    if n_sub in cache:
        return cache[n_sub]
    model = ekf.model
    nx, nu, nd = model.n_states, len(model.input_names), len(ekf.disturbance_names)
    x, current, dist = ca.SX.sym("x", nx), ca.SX.sym("I"), ca.SX.sym("dist", nd)
    u0, eI, h = ca.SX.sym("u0", nu), ca.SX.sym("eI", nu), ca.SX.sym("h")
    flat = [ca.SX.sym(name, nx * nx) for name in ("E", "G1", "G2")]
    phis = [ca.reshape(v, nx, nx) for v in flat]
    u = u0 + current * eI
    xs, us, ws = ca.SX.sym("xs", nx), ca.SX.sym("us", nu), ca.SX.sym("ws", nx)
    step = ca.Function("step", [xs, us, ws, h, *flat], [step_expression(model, xs, us, ws, ca.DM(model.p0), h, phis)])

    def one_step(state):
        return step(state, _model_input(ekf, u, dist), ca.DM(ekf.M) @ _heat(ekf, state, u, dist), h, *flat)
    states, outputs = x, []
    for _ in range(n_sub):
        states = one_step(states)
        outputs.append(ca.DM(ekf.C) @ states + ca.DM(ekf.e))
    function = ca.Function("planning_run", [x, current, dist, u0, eI, h, *flat], [states, ca.horzcat(*outputs)])
    cache[n_sub] = function
    return function


def _heat(ekf, x_nodes, u, dist):
    """The filter's disturbance heat flow into each disturbance node (W) at nodes ``x_nodes`` and
    input ``u``, as its transition computes it (:meth:`ExtendedKalmanFilter.basis_values`)."""
    n_nodes, phi = ekf.M.shape[1], ekf.basis_values(x_nodes, u)
    n_bases = len(phi) // n_nodes
    return ca.vertcat(*[sum(dist[b * n_nodes + j] * phi[b * n_nodes + j] for b in range(n_bases))
                        for j in range(n_nodes)])


def _model_input(ekf, u, dist):
    """The inputs the model sees in the filter: the inlet raised by its offset state, if any."""
    if getattr(ekf, "inlet_offset", False):
        return u + dist[-1] * ca.DM([float(name == ekf.coolant_input) for name in ekf.model.input_names])
    return u


class _RestModel:
    """Exact rest of free length for one generator (module docstring): steady state and decay."""

    def __init__(self, ekf, z0: np.ndarray, u_rest: np.ndarray):
        model = ekf.model
        nx = model.n_states
        x, u = ca.SX.sym("x", nx), ca.SX.sym("u", len(model.input_names))
        if ca.depends_on(model.functions["jac_x"](x, u, model.p0), x):
            raise InputError("model", model.name, "a rest of free length needs a model affine in the state at a "
                             "fixed input; plan on the design model (--planner-model affine)")
        dist = ca.DM(z0[nx:])
        u_model = _model_input(ekf, ca.DM(u_rest), dist)
        rate = model.functions["rhs"](x, u_model, model.p0) + ca.DM(ekf.M) @ _heat(ekf, x, ca.DM(u_rest), dist)
        J_f = ca.Function("rest_rate", [x], [ca.jacobian(rate, x), rate])
        J, f0 = (np.asarray(m) for m in J_f(np.zeros(nx)))
        self.x_ss = -np.linalg.solve(J, f0.ravel())
        self.decay = ModalDecay.of(J, model.name)

    def after(self, x, minutes, fraction: float = 1.0):
        """State after ``fraction`` of a rest of ``minutes`` from ``x``: numbers (one state), or
        CasADi (states as columns, ``minutes`` a row, one rest per column)."""
        if not isinstance(x, (ca.SX, ca.MX)):
            return self.x_ss + self.decay.apply(x - self.x_ss, 60.0 * minutes * fraction)
        n, nx = x.size2(), x.size1()
        x_ss = ca.repmat(ca.DM(self.x_ss), 1, n)
        rates = ca.repmat(ca.DM(self.decay.eigenvalues), 1, n) * ca.repmat(60.0 * fraction * minutes, nx, 1)
        return x_ss + ca.DM(self.decay.V) @ (ca.exp(rates) * (ca.DM(self.decay.V_inv) @ (x - x_ss)))


#: The NLP's horizon is padded to a multiple of this many segments (empty segments at the end), so
#: that one solver serves every re-plan of a flight: the mission shrinks by a segment per cycle.
HORIZON_BLOCK = 16
#: Length of a padding segment's step, s (effectively none).
PAD_STEP_S = 1e-3


class FlownTranscription:
    r"""The NLP of one planning problem on the flown model (module docstring).

    Everything numeric (filter states, disturbances, inlet, currents, step matrices, bounds) is a
    parameter or a bound of the NLP, and the horizon is padded to a multiple of
    :data:`HORIZON_BLOCK` segments: the solver is built (expanded to SX, with its exact Hessian)
    once per set of filters and padded horizon, and re-used by the later re-plans of the flight.

    Parameters
    ----------
    problem : PlanningProblem
        With ``flown`` set.
    settings : NonlinearSettings
    minimax : bool
        Minimise the highest backed-off temperature instead (the lowest reachable peak).
    shed : bool
        Let the generators carry less than the demand in total (:math:`\sum_g d_{g,k} \ge 0`, the
        difference not served) at :data:`~genthermal.schedule.planning.price.SHED_PRICE_MIN_PER_AH` per A·h.
    """

    def __init__(self, problem: PlanningProblem, settings: NonlinearSettings, minimax: bool = False,
                 shed: bool = False):
        if problem.flown is None:
            raise InputError("problem.flown", None, "the flown-model transcription needs the filters' states")
        self.problem, self.settings, self.minimax, self.shed = problem, settings, minimax, bool(shed and not minimax)
        flown = problem.flown
        self.n_gen, self.n_seg = problem.n_generators, len(problem.segments)
        self.nx = flown.filters[0].model.n_states
        self.intervals = [(k, length, current) for k, segment in enumerate(problem.segments)
                          for _, length, current in segment.windows(problem.window_s)]
        self.n_int = len(self.intervals)
        self.segment_of = np.array([k for k, _, _ in self.intervals])
        self.n_sub = max(int(np.ceil(problem.window_s / settings.substep_s - 1e-9)), 1)
        # padded sizes: segments and intervals, one interval per padding segment; a longer solver
        # already built for these filters serves (one segment per interval: the closed loop's case)
        self.N_seg = int(np.ceil(self.n_seg / HORIZON_BLOCK)) * HORIZON_BLOCK
        if self.n_int == self.n_seg:
            built = [key[1] for key in self._cache() if key[0] == self._key()[0] and key[2] is None
                     and key[1] >= self.n_seg and key[3:] == self._key()[3:]]
            self.N_seg = min(built, default=self.N_seg)
        self.N_int = self.n_int + (self.N_seg - self.n_seg)
        pad = self.N_seg - self.n_seg
        self.segment_of_padded = np.concatenate([self.segment_of, self.n_seg + np.arange(pad)]).astype(int)
        self.lengths = np.concatenate([[length for _, length, _ in self.intervals],
                                       np.full(pad, PAD_STEP_S * self.n_sub)])
        self.currents = np.concatenate([[current for _, _, current in self.intervals],
                                        np.full(pad, problem.rest_current_A)])
        self.first_interval = np.array([np.flatnonzero(self.segment_of_padded == k)[0] for k in range(self.N_seg)])
        self.last_interval = np.array([np.flatnonzero(self.segment_of_padded == k)[-1] for k in range(self.N_seg)])
        self.rests = [_RestModel(ekf, flown.z0[g], problem.inputs(g, problem.rest_current_A))
                      for g, ekf in enumerate(flown.filters)]
        self.phis = self._phis()

    def _phis(self) -> list:
        """Per generator, the (E, Γ1, Γ2) columns (flattened, 3 × N_int) of every interval's substep."""
        result = []
        for ekf in self.problem.flown.filters:
            model = ekf.model
            L = np.asarray(model.functions["jac_x"](np.zeros(self.nx), np.zeros(len(model.input_names)), model.p0))
            check_step_accuracy(model, float(np.max(self.lengths)) / self.n_sub)
            cache, columns = {}, [[], [], []]
            for length in self.lengths:
                key = round(length / self.n_sub, 9)
                if key not in cache:
                    cache[key] = [m.ravel(order="F") for m in phi_matrices(L, key)]
                for j in range(3):
                    columns[j].append(cache[key][j])
            result.append([np.column_stack(c) for c in columns])
        return result

    # --- layout -----------------------------------------------------------------------------
    def _w_sizes(self):
        n_gen, nx = self.n_gen, self.nx
        return [n_gen * self.N_seg, self.N_seg, n_gen * nx * self.N_seg, n_gen * nx * self.N_int, int(self.minimax)]

    def _p_sizes(self):
        """Per generator: x0, dist, u_zero, eI, x_ss, V, V_inv, eigenvalues, currents, h, E, G1, G2;
        then the segment durations."""
        ekf = self.problem.flown.filters[0]
        nx, nd, nu, N = self.nx, len(ekf.disturbance_names), len(ekf.model.input_names), self.N_int
        return [nx, nd, nu, nu, nx, nx * nx, nx * nx, nx, N, N, nx * nx * N, nx * nx * N, nx * nx * N]

    def _key(self):
        """Structure of the NLP: filters, padded horizon, intervals per segment (None: one each),
        settings."""
        flown = self.problem.flown
        structure = None if self.n_int == self.n_seg else tuple(self.segment_of)
        return (tuple(id(f) for f in flown.filters), getattr(self, "N_seg", 0), structure, self.n_sub,
                self.settings.rest_checks, self.minimax, self.settings.displacement_weight, self.settings.expand,
                self.settings.max_iter, self.settings.mu_init, self.shed)

    def _cache(self) -> dict:
        """Solvers built for the first filter (the key names all of them)."""
        return self.problem.flown.filters[0].__dict__.setdefault("_planning_solvers", {})

    def _solver(self):
        """The cached solver for this structure (built on first use). The cache keeps the
        :data:`MAX_CACHED_SOLVERS` most recently used: a flight whose re-plans keep changing the
        structure (the shed plans of a long mission) built one solver per re-plan and held them all,
        and a robustness-grid worker passed 10 GB."""
        cache = self._cache()
        key = self._key()
        if key in cache:
            cache[key] = cache.pop(key)  # most recently used last
        else:
            while len(cache) >= MAX_CACHED_SOLVERS:
                cache.pop(next(iter(cache)))
            cache[key] = (self._build(), list(self.problem.flown.filters))  # the filters keep their ids
        return cache[key][0]

    def _build(self):
        settings, flown = self.settings, self.problem.flown
        n_gen, N_seg, N_int, nx = self.n_gen, self.N_seg, self.N_int, self.nx
        w_sizes, p_sizes = self._w_sizes(), self._p_sizes()
        w = ca.MX.sym("w", int(sum(w_sizes)))
        p = ca.MX.sym("p", int(n_gen * sum(p_sizes) + N_seg))
        wo = np.concatenate([[0], np.cumsum(w_sizes)])
        D = ca.reshape(w[wo[0]:wo[1]], n_gen, N_seg)
        R = w[wo[1]:wo[2]]
        peak = w[wo[4]] if self.minimax else None
        durations = p[n_gen * sum(p_sizes):]
        equalities, inequalities = [], []
        for g, ekf in enumerate(flown.filters):
            po = g * sum(p_sizes) + np.concatenate([[0], np.cumsum(p_sizes)])
            x0, dist, u_zero, eI, x_ss, V, V_inv, eig, currents, h, E, G1, G2 = (
                p[po[i]:po[i + 1]] for i in range(len(p_sizes)))
            V, V_inv = ca.reshape(V, nx, nx), ca.reshape(V_inv, nx, nx)
            XR = ca.reshape(w[wo[2] + g * nx * N_seg:wo[2] + (g + 1) * nx * N_seg], nx, N_seg)
            XI = ca.reshape(w[wo[3] + g * nx * N_int:wo[3] + (g + 1) * nx * N_int], nx, N_int)
            end_states = ca.horzcat(x0, XI)
            before_rest = end_states[:, [0] + [int(i) + 1 for i in self.last_interval[:-1]]]
            x_ss_all, eig_all = ca.repmat(x_ss, 1, N_seg), ca.repmat(eig, 1, N_seg)
            for j in range(1, settings.rest_checks + 1):
                rates = eig_all * ca.repmat(60.0 * j / settings.rest_checks * R.T, nx, 1)
                states = x_ss_all + V @ (ca.exp(rates) * (V_inv @ (before_rest - x_ss_all)))
                inequalities.append(ca.DM(ekf.C) @ states + ca.repmat(ca.DM(ekf.e), 1, N_seg))
            equalities.append(ca.vec(XR - states))
            starts = ca.horzcat(XR, XI)
            previous = [int(self.segment_of_padded[j]) if j == self.first_interval[self.segment_of_padded[j]]
                        else N_seg + j - 1 for j in range(N_int)]
            run = _run_function(ekf, self.n_sub).map(N_int)
            current = currents.T - D[g, [int(k) for k in self.segment_of_padded]]
            x_end, Y = run(starts[:, previous], current, ca.repmat(dist, 1, N_int), ca.repmat(u_zero, 1, N_int),
                           ca.repmat(eI, 1, N_int), h.T, ca.reshape(E, nx * nx, N_int),
                           ca.reshape(G1, nx * nx, N_int), ca.reshape(G2, nx * nx, N_int))
            equalities.append(ca.vec(XI - x_end))
            inequalities.append(Y)
        self.n_equalities = sum(e.numel() for e in equalities) + N_seg
        temperatures = ca.vertcat(*[ca.vec(i) for i in inequalities])
        if self.minimax:
            temperatures = temperatures - peak
        g_all = ca.vertcat(*equalities, ca.sum1(D).T, temperatures, ca.sum1(R))
        penalty = settings.displacement_weight * ca.sum2(ca.sum1(D ** 2) * (durations / 3600.0).T)
        objective = peak + 1e-3 * ca.sum1(R) if self.minimax else ca.sum1(R) + penalty / 60.0
        if self.shed:  # A·h not served
            objective = objective + SHED_PRICE_MIN_PER_AH * ca.mtimes(ca.sum1(D), durations / 3600.0)
        options = {"print_time": False, "expand": settings.expand,
                   "ipopt": {"print_level": 0, "sb": "yes", "max_iter": settings.max_iter, "tol": 1e-6,
                             "acceptable_tol": 1e-4, "mu_init": settings.mu_init}}
        return ca.nlpsol("flown_schedule", "ipopt", {"x": w, "p": p, "f": objective, "g": g_all}, options)

    # --- numbers of this problem ------------------------------------------------------------
    def _parameters(self) -> np.ndarray:
        problem, flown, nx = self.problem, self.problem.flown, self.nx
        values = []
        for g in range(self.n_gen):
            rest = self.rests[g]
            u_zero = problem.inputs(g, 0.0)
            values += [flown.z0[g][:nx], flown.z0[g][nx:], u_zero, problem.inputs(g, 1.0) - u_zero, rest.x_ss,
                       rest.decay.V.ravel(order="F"), rest.decay.V_inv.ravel(order="F"), rest.decay.eigenvalues,
                       self.currents, self.lengths / self.n_sub, *(m.ravel(order="F") for m in self.phis[g])]
        durations = np.array([s.duration_s for s in problem.segments] + [0.0] * (self.N_seg - self.n_seg))
        return np.concatenate(values + [durations])

    def _bounds(self, backoff_K: np.ndarray):
        """``(lbw, ubw, lbg, ubg)`` for the back-off ``backoff_K`` (n_gen, n_outputs, n_seg), K."""
        problem, settings, n_gen, N_seg = self.problem, self.settings, self.n_gen, self.N_seg
        pad = N_seg - self.n_seg
        sizes = self._w_sizes()
        bounds = [problem.displacement_bounds(k) for k in range(self.n_seg)] + [(0.0, 0.0)] * pad
        longest_rest = np.concatenate([np.full(self.n_seg, problem.max_rest_s / 60.0), np.zeros(pad)])
        longest_rest[0] = max(problem.max_rest_s - problem.rest_taken_s, 0.0) / 60.0
        n_states = sizes[2] + sizes[3]
        lbw = np.concatenate([np.repeat([b[0] for b in bounds], n_gen), np.zeros(N_seg), np.full(n_states, -100.0),
                              [-100.0] * sizes[4]])
        ubw = np.concatenate([np.repeat([b[1] for b in bounds], n_gen), longest_rest, np.full(n_states, 500.0),
                              [500.0] * sizes[4]])
        upper = []
        for g in range(n_gen):
            b = np.concatenate([backoff_K[g], np.full((backoff_K.shape[1], pad), -np.inf)], axis=1)  # padding: free
            limit = 0.0 if self.minimax else problem.limit_C
            upper += [(limit - b).ravel(order="F")] * settings.rest_checks
            upper.append(np.repeat(limit - b[:, self.segment_of_padded], self.n_sub, axis=1).ravel(order="F"))
        upper = np.concatenate(upper)
        if self.minimax:  # y - peak <= -b
            upper = np.where(np.isfinite(upper), upper, np.inf)
        budget = problem.rest_budget_s / 60.0 if np.isfinite(problem.rest_budget_s) else np.inf
        lbg = np.concatenate([np.zeros(self.n_equalities_expected), np.full(upper.size, -np.inf), [-np.inf]])
        ubg = np.concatenate([np.zeros(self.n_equalities_expected), upper, [budget]])
        balance = np.arange(self.n_equalities_expected - N_seg, self.n_equalities_expected)
        if self.shed:  # the load balance rows: sum_g d >= 0
            ubg[balance] = np.inf
        # A segment whose displacements are all fixed (padding, or no room to move load) has a load
        # balance row with no free variable (0 = 0): left as an equality it is a redundant, degenerate
        # constraint that IPOPT must carry and that makes CasADi count more equalities than variables.
        fixed = balance[[low == high for low, high in bounds]]
        lbg[fixed], ubg[fixed] = -np.inf, np.inf
        return lbw, ubw, lbg, ubg

    @property
    def n_equalities_expected(self) -> int:
        """Equality rows: rest and interval states of every generator, and the load balance."""
        return self.n_gen * self.nx * (self.N_seg + self.N_int) + self.N_seg

    def initial_guess(self, schedule: Schedule, peak_C: float = 0.0) -> np.ndarray:
        """Decision vector of ``schedule`` (padded): states run on the same functions."""
        problem, flown, nx, pad = self.problem, self.problem.flown, self.nx, self.N_seg - self.n_seg
        displaced = np.hstack([schedule.displaced_A, np.zeros((self.n_gen, pad))])
        rests = np.concatenate([schedule.rest_before_s, np.zeros(pad)])
        XR_all, XI_all = [], []
        for g, ekf in enumerate(flown.filters):
            run = _run_function(ekf, self.n_sub)
            u_zero = problem.inputs(g, 0.0)
            eI = problem.inputs(g, 1.0) - u_zero
            x = flown.z0[g][:nx].copy()
            XR, XI = np.empty((nx, self.N_seg)), np.empty((nx, self.N_int))
            for j in range(self.N_int):
                k = self.segment_of_padded[j]
                if j == self.first_interval[k]:
                    x = self.rests[g].after(x, rests[k] / 60.0)
                    XR[:, k] = x
                E, G1, G2 = (m[:, j] for m in self.phis[g])
                x = np.asarray(run(x, self.currents[j] - displaced[g, k], flown.z0[g][nx:], u_zero, eI,
                                   self.lengths[j] / self.n_sub, E, G1, G2)[0]).ravel()
                XI[:, j] = x
            XR_all.append(XR.ravel(order="F"))
            XI_all.append(XI.ravel(order="F"))
        return np.concatenate([displaced.ravel(order="F"), rests / 60.0, *XR_all, *XI_all,
                               [peak_C] if self.minimax else []])

    def solve(self, guess: np.ndarray, backoff_K: np.ndarray) -> tuple[Schedule, bool, str]:
        """Run IPOPT from ``guess`` with the back-off ``backoff_K``; the schedule, success flag and
        IPOPT's status."""
        solver = self._solver()
        lbw, ubw, lbg, ubg = self._bounds(backoff_K)
        solution = solver(x0=np.clip(guess, lbw, ubw), p=self._parameters(), lbx=lbw, ubx=ubw, lbg=lbg, ubg=ubg)
        stats = solver.stats()
        self.iterations = getattr(self, "iterations", 0) + int(stats.get("iter_count", 0))
        w = np.asarray(solution["x"]).ravel()
        displaced = w[:self.n_gen * self.N_seg].reshape((self.n_gen, self.N_seg), order="F")[:, :self.n_seg]
        rests = w[self.n_gen * self.N_seg:self.n_gen * self.N_seg + self.n_seg] * 60.0
        return Schedule(displaced, np.where(rests < MIN_REST_S, 0.0, rests)), bool(stats["success"]), \
            str(stats["return_status"])


def _judged(problem: PlanningProblem, schedule: Schedule, method: str, tolerance_K: float = 0.05):
    """``(PlanResult, per-segment back-off, per-segment peak)``: ``schedule`` predicted once on the
    flown model (as :func:`~genthermal.schedule.planning.plan.evaluate`), the largest back-off (K) and the
    highest predicted temperature without it (°C) of each segment, its rest included, both
    (n_gen, n_outputs, n_seg)."""
    prediction = predict(problem, schedule)
    peak, g, k = prediction.peak()
    result = PlanResult(schedule, peak <= problem.limit_C + tolerance_K, peak, g, k, 0.0, method)
    backoff, outputs = prediction.backoff_K[:, :, 1:], prediction.outputs[:, :, 1:]
    per_segment = np.zeros(backoff.shape[:2] + (len(problem.segments),))
    peaks = np.zeros_like(per_segment)
    for segment in range(len(problem.segments)):
        samples = prediction.timeline.segment == segment
        if not samples.any():
            samples = np.ones_like(samples)
        per_segment[:, :, segment] = backoff[:, :, samples].max(axis=2)
        peaks[:, :, segment] = outputs[:, :, samples].max(axis=2)
    result.details["backoff_K"] = float(backoff.max())
    return result, per_segment, peaks


def _guess(problem: PlanningProblem, settings: NonlinearSettings, initial: Schedule | None):
    """The initial guess, judged (:func:`_judged`): the previous plan if given, else the heuristic's
    plan on the design model within the margin ``guess_margin_K``."""
    if initial is not None and initial.displaced_A.shape == (problem.n_generators, len(problem.segments)):
        return _judged(problem, initial, "optimal->previous plan")[:2]
    design = dataclasses.replace(problem, flown=None, limit_C=problem.limit_C - settings.guess_margin_K)
    return _judged(problem, heuristic_plan(design).schedule, "optimal->heuristic")[:2]


def _cost_min(result: PlanResult, segments) -> float:
    """The manager's cost of ``result``'s schedule: rest (min) plus
    :data:`~genthermal.schedule.planning.price.SHED_PRICE_MIN_PER_AH` per A·h not served."""
    return schedule_cost_min(segments, result.schedule)


def _better(candidate: PlanResult, incumbent: PlanResult | None, minimax: bool, segments=()) -> bool:
    """True when ``candidate`` beats ``incumbent``: a lower peak (min-max), else feasible first,
    then less rest and load not served."""
    if incumbent is None:
        return True
    if minimax:
        return candidate.peak_C < incumbent.peak_C - 1e-3
    if candidate.feasible != incumbent.feasible:
        return candidate.feasible
    if not candidate.feasible:
        return candidate.peak_C < incumbent.peak_C - 1e-3
    return _cost_min(candidate, segments) < _cost_min(incumbent, segments) - MIN_REST_S / 60.0


def flown_optimal_plan(problem: PlanningProblem, settings: NonlinearSettings = NonlinearSettings(),
                       initial: Schedule | None = None, minimax: bool = False, shed: bool = False) -> PlanResult:
    """Plan on the flown model (module docstring).

    Parameters
    ----------
    problem : PlanningProblem
        With ``flown`` set; ``limit_C`` is θmax.
    settings : NonlinearSettings
    initial : Schedule, optional
        Warm start (the previous plan in a closed loop); default the heuristic's plan.
    minimax : bool
        Minimise the peak (the lowest reachable peak) instead of the rest.
    shed : bool
        Let load go unserved where nothing else keeps θmax (:class:`FlownTranscription`).

    Returns
    -------
    PlanResult
        ``method`` ``optimal`` (``lowest peak`` for the min-max); the initial guess, named by its
        origin, with a warning when IPOPT fails and the guess when it is better.
        ``details['backoff_K']``: the largest back-off along the plan, K; ``details['ipopt_iterations']``.
    """
    started = time.perf_counter()
    if not (minimax or shed) and initial is None:  # a closed loop re-plans because its plan breaches
        nominal, *_ = _judged(problem, Schedule.nominal(problem.n_generators, len(problem.segments)), "optimal")
        if nominal.feasible:
            nominal.solve_s = time.perf_counter() - started
            return nominal
    guess, backoff = _guess(problem, settings, initial)
    if minimax:
        guess.method = "lowest peak (initial guess)"
    transcription = FlownTranscription(problem, settings, minimax, shed)
    best, status, schedule = None, "not run", guess.schedule
    for _ in range(max(settings.backoff_passes, 1)):
        schedule, success, status = transcription.solve(transcription.initial_guess(schedule, guess.peak_C), backoff)
        if not success:
            break
        method = "lowest peak" if minimax else "shed" if shed else "optimal"
        result, solved_backoff, peaks = _judged(problem, schedule, method)
        if _better(result, best, minimax, problem.segments):
            best = result
        if minimax or result.feasible:
            break
        # what the 10-s prediction exceeds of the limit the NLP held (it checks every substep and
        # a rest at rest_checks points): the next pass holds that much more
        gap = np.clip(peaks + backoff - problem.limit_C, 0.0, None)
        backoff = np.maximum(backoff, solved_backoff) + gap
    if best is None or _better(guess, best, minimax, problem.segments):
        if best is None:
            guess.warnings.append(f"optimal scheduler (flown model) fell back to its initial guess (IPOPT: {status})")
        best = guess
    best.solve_s = time.perf_counter() - started
    best.details["ipopt_iterations"] = getattr(transcription, "iterations", 0)
    return best
