"""Optimal load schedule by direct transcription in CasADi, solved by IPOPT with exact derivatives
(thesis eq. 7.5), and the lowest reachable peak (min-max). Main objects: :func:`optimal_plan`,
:func:`lowest_reachable_peak`, :class:`OptimalSettings`.
"""

from __future__ import annotations

import dataclasses
import time

import casadi as ca
import numpy as np
import scipy.sparse

from .engineer import engineer_plan
from .heuristic import heuristic_plan
from .optimal_nlp import NonlinearSettings, flown_optimal_plan
from .plan import PlanningProblem, PlanResult, Schedule, evaluate
from .shed import NOT_SERVED_TOLERANCE_A
from .price import schedule_cost_min


#: Rests shorter than this (s) are interior-point residue and dropped.
MIN_REST_S = 1.0


@dataclasses.dataclass(frozen=True)
class OptimalSettings:
    """Settings of the transcription.

    Attributes
    ----------
    check_s : float
        Longest interval between temperature checks inside a grid interval, s (the checks use the
        exact affine map from the interval's first state; the result is verified every
        ``problem.dt_s`` afterwards).
    rest_substeps : int
        Grid intervals per rest.
    displacement_weight : float
        :math:`w`, s of mission time per A²·h of displaced current squared (small: displacement
        adds no mission time, the penalty only picks the least displacement among equal missions).
    max_iter : int
        IPOPT iteration limit.
    nonlinear : NonlinearSettings
        The transcription on the flown model, used when the problem carries it (``problem.flown``,
        :mod:`genthermal.schedule.planning.optimal_nlp`).
    """

    check_s: float = 60.0
    rest_substeps: int = 3
    displacement_weight: float = 1.0
    max_iter: int = 300
    nonlinear: NonlinearSettings = NonlinearSettings()


def sparse_dm(matrix) -> ca.DM:
    """A scipy sparse matrix as a CasADi sparse DM."""
    csc = scipy.sparse.csc_matrix(matrix)
    csc.sort_indices()
    pattern = ca.Sparsity(csc.shape[0], csc.shape[1], csc.indptr.tolist(), csc.indices.tolist())
    return ca.DM(pattern, csc.data)


class LinearRows:
    """Rows :math:`lb \\le A w \\le ub` assembled block by block as sparse triplets."""

    def __init__(self):
        self.rows, self.cols, self.vals, self.lb, self.ub = [], [], [], [], []
        self.count = 0

    def add(self, terms, lb, ub) -> None:
        """Add ``len(lb)`` rows; ``terms`` is a list of ``(column indices, matrix or column)``."""
        lb = np.atleast_1d(np.asarray(lb, dtype=float))
        for cols, block in terms:
            block = np.asarray(block, dtype=float).reshape(lb.size, -1)
            r, c = np.nonzero(block)
            self.rows.append(r + self.count)
            self.cols.append(np.atleast_1d(cols)[c])
            self.vals.append(block[r, c])
        self.lb.append(lb)
        self.ub.append(np.broadcast_to(np.asarray(ub, dtype=float), lb.shape))
        self.count += lb.size

    def matrix(self, n_cols: int) -> scipy.sparse.csc_matrix:
        """The assembled :math:`A`."""
        return scipy.sparse.csc_matrix((np.concatenate(self.vals), (np.concatenate(self.rows),
                                        np.concatenate(self.cols))), shape=(self.count, n_cols))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(lb, ub)``."""
        return np.concatenate(self.lb), np.concatenate(self.ub)


class _Transcription:
    """The NLP for one planning problem: linear rows (segment steps, path, load balance) as one
    sparse matrix, and the rest transitions (nonlinear in the free rest length) in SX."""

    def __init__(self, problem: PlanningProblem, settings: OptimalSettings, minimax: bool):
        self.problem, self.settings, self.minimax = problem, settings, minimax
        n_gen, n_seg = problem.n_generators, len(problem.segments)
        self.nx = nx = problem.x0.shape[1]
        self.intervals = self._intervals()
        self.n_nodes = len(self.intervals)
        self.n_w = n_gen * n_seg + n_seg + n_gen * self.n_nodes * nx + int(minimax)
        w = ca.SX.sym("w", self.n_w)
        linear, nonlinear = LinearRows(), []
        def peak(rows: int) -> list:  # the min-max variable on the right of every path row
            return [(self.n_w - 1, -np.ones(rows))] if minimax else []

        for g, generator in enumerate(problem.generators):
            u_rest = problem.inputs(g, problem.rest_current_A)
            xss = generator.steady_state(u_rest)
            y_rest = generator.Dy @ u_rest + generator.ey
            b_I = generator.B @ generator.e_I
            for i, (k, h, current) in enumerate(self.intervals):
                x, d = self.x_index(g, i), self.d_index(g, k)
                previous = problem.x0[g] if i == 0 else w[self.x_index(g, i - 1)]
                n_y = generator.Cy.shape[0]
                if current is None:  # rest substep of free length h = r_k / M
                    h_s = 60.0 * w[self.r_index(k)] / settings.rest_substeps
                    nonlinear.append(w[x] - xss - generator.decay.apply(previous - xss, h_s))
                    linear.add([(x, generator.Cy)] + peak(n_y), [-np.inf] * n_y,
                               (0.0 if minimax else problem.limit_C) - y_rest)
                    continue
                u0 = problem.inputs(g, current)  # exact ZOH over h; checks every <= dt_s inside
                E, G = generator.step(h)
                f0 = generator.forcing(u0)
                linear.add([(x, np.eye(nx)), (self.x_index(g, i - 1), -E), (d, G @ b_I)], G @ f0, G @ f0)
                for P, Q_f, Q_d in self._checks(g, h, u0, f0, b_I):
                    linear.add([(self.x_index(g, i - 1), P), (d, Q_d)] + peak(len(Q_f)), np.full(len(Q_f), -np.inf),
                               (0.0 if minimax else problem.limit_C) - Q_f)
        for k in range(n_seg):
            linear.add([([self.d_index(g, k) for g in range(n_gen)], np.ones((1, n_gen)))], [0.0], [0.0])
        if np.isfinite(problem.rest_budget_s):  # the flight's rest budget: total rest, minutes
            linear.add([([self.r_index(k) for k in range(n_seg)], np.ones((1, n_seg)))], [-np.inf],
                       [problem.rest_budget_s / 60.0])
        self.nonlinear = ca.vertcat(*nonlinear)
        A = sparse_dm(linear.matrix(self.n_w))
        lb, ub = linear.bounds()
        self.lbg = np.concatenate([np.zeros(self.nonlinear.numel()), lb])
        self.ubg = np.concatenate([np.zeros(self.nonlinear.numel()), ub])
        durations = np.array([s.duration_s for s in problem.segments])
        d_all = ca.reshape(w[:n_gen * n_seg], n_gen, n_seg)
        penalty = settings.displacement_weight * ca.sum2(ca.sum1(d_all ** 2) * ca.DM(durations / 3600.0).T)
        rest_minutes = ca.sum1(w[n_gen * n_seg:n_gen * n_seg + n_seg])
        objective = w[-1] + 1e-3 * rest_minutes if minimax else rest_minutes + penalty / 60.0
        parts = ca.Function("parts", [w], [self.nonlinear, objective])
        self.w = ca.MX.sym("w", self.n_w)
        g_nonlinear, self.f = parts(self.w)
        self.g = ca.vertcat(g_nonlinear, ca.mtimes(A, self.w))
        bounds = [problem.displacement_bounds(k) for k in range(n_seg)]
        self.lbw = np.concatenate([np.repeat([b[0] for b in bounds], n_gen), np.zeros(n_seg),
                                   np.full(n_gen * nx * self.n_nodes, -100.0), [-100.0] * int(minimax)])
        longest_rest = np.full(n_seg, problem.max_rest_s / 60.0)
        longest_rest[0] = max(problem.max_rest_s - problem.rest_taken_s, 0.0) / 60.0  # a rest under way counts
        self.ubw = np.concatenate([np.repeat([b[1] for b in bounds], n_gen), longest_rest,
                                   np.full(n_gen * nx * self.n_nodes, 500.0), [500.0] * int(minimax)])

    def d_index(self, g: int, k: int) -> int:
        """Index of :math:`d_{g,k}` in the decision vector."""
        return g + self.problem.n_generators * k

    def r_index(self, k: int) -> int:
        """Index of :math:`r_k` (minutes) in the decision vector."""
        return self.problem.n_generators * len(self.problem.segments) + k

    def x_index(self, g: int, i: int) -> np.ndarray:
        """Indices of the state of generator ``g`` at grid node ``i``."""
        first = (self.problem.n_generators + 1) * len(self.problem.segments) + (g * self.n_nodes + i) * self.nx
        return np.arange(first, first + self.nx)

    def _checks(self, g: int, h: float, u0: np.ndarray, f0: np.ndarray, b_I: np.ndarray):
        r"""Temperatures at check points :math:`t_j = jh/m` (:math:`m = \lceil h/t_{check}\rceil`)
        inside an interval, stacked over j as :math:`y = Px + q_f + q_d\,d` from the interval's
        first state :math:`x`; a second block with the rise back-off
        :math:`(1+\kappa)y_j - \kappa y_{start}` when :math:`\kappa > 0`."""
        generator, kappa = self.problem.generators[g], self.problem.rise_backoff
        m = max(int(np.ceil(h / max(self.settings.check_s, self.problem.dt_s) - 1e-9)), 1)
        steps = [generator.step(h * j / m) for j in range(1, m + 1)]
        y_u = generator.Dy @ u0 + generator.ey
        P = np.vstack([generator.Cy @ E for E, _ in steps])
        Q = np.vstack([generator.Cy @ G for _, G in steps])
        plain = (P, Q @ f0 + np.tile(y_u, m), -(Q @ b_I + np.tile(generator.Dy @ generator.e_I, m)))
        if kappa == 0:
            return [plain]
        start = (np.tile(generator.Cy, (m, 1)), np.tile(y_u, m), -np.tile(generator.Dy @ generator.e_I, m))
        return [plain, tuple((1 + kappa) * a - kappa * b for a, b in zip(plain, start))]

    def _intervals(self) -> list[tuple[int, float | None, float | None]]:
        """``(segment, length s or None for a rest substep, current A or None)`` of every interval:
        the rest substeps, then the segment's windows (:meth:`Segment.windows`)."""
        intervals = []
        for k, segment in enumerate(self.problem.segments):
            intervals += [(k, None, None)] * self.settings.rest_substeps
            intervals += [(k, length, current) for _, length, current in segment.windows(self.problem.window_s)]
        return intervals

    def initial_guess(self, schedule: Schedule, peak_C: float = 0.0) -> np.ndarray:
        """Decision vector of ``schedule`` (and ``peak_C`` for the min-max): states propagated
        exactly on the grid."""
        problem = self.problem
        states = []
        for g, generator in enumerate(problem.generators):
            x = problem.x0[g].copy()
            X = np.empty((x.size, len(self.intervals)))
            for i, (k, h, current) in enumerate(self.intervals):
                if current is None:
                    h, current = schedule.rest_before_s[k] / self.settings.rest_substeps, problem.rest_current_A
                else:
                    current = current - schedule.displaced_A[g, k]
                E, G = generator.step(h)
                x = E @ x + G @ generator.forcing(problem.inputs(g, current))
                X[:, i] = x
            states.append(X.ravel(order="F"))
        peak = [peak_C] if self.minimax else []
        return np.concatenate([schedule.displaced_A.ravel(order="F"), schedule.rest_before_s / 60.0,
                               *states, peak])

    def solve(self, guess: np.ndarray) -> tuple[Schedule, bool, str]:
        """Run IPOPT from ``guess``; return the schedule, success flag and IPOPT's status."""
        options = {"print_time": False, "ipopt": {"print_level": 0, "sb": "yes", "max_iter": self.settings.max_iter,
                                                  "tol": 1e-6, "acceptable_tol": 1e-4, "mu_init": 1e-3}}
        solver = ca.nlpsol("schedule", "ipopt", {"x": self.w, "f": self.f, "g": self.g}, options)
        solution = solver(x0=guess, lbx=self.lbw, ubx=self.ubw, lbg=self.lbg, ubg=self.ubg)
        stats = solver.stats()
        w = np.asarray(solution["x"]).ravel()
        n_gen, n_seg = self.problem.n_generators, len(self.problem.segments)
        displaced = w[:n_gen * n_seg].reshape((n_gen, n_seg), order="F")
        rests = w[n_gen * n_seg:n_gen * n_seg + n_seg] * 60.0
        rests = np.where(rests < MIN_REST_S, 0.0, rests)
        return Schedule(displaced, rests), bool(stats["success"]), str(stats["return_status"])


def optimal_plan(problem: PlanningProblem, settings: OptimalSettings = OptimalSettings(),
                 initial: Schedule | None = None) -> PlanResult:
    """Plan by direct transcription and IPOPT.

    Parameters
    ----------
    problem : PlanningProblem
    settings : OptimalSettings
    initial : Schedule, optional
        Initial guess (the previous plan in a closed loop, the lowest-peak schedule when planning
        within the lowest reachable peak); default: the heuristic's plan.

    Returns
    -------
    PlanResult
        The feasible plan that costs least (:func:`least_cost`: rest, and load not served at the
        manager's price) of IPOPT's schedule, ``initial``, the heuristic's
        and the engineer's heuristic's, all judged on ``problem`` (``method``
        ``optimal``, ``details["chosen_from"]`` naming the plan when it is not IPOPT's; when IPOPT
        failed, ``optimal->`` that plan's origin and a warning). When none of the candidates is
        feasible: the heuristic's plan, ``method`` ``optimal->heuristic``, with a warning. With
        ``problem.flown``: :func:`~genthermal.schedule.planning.optimal_nlp.flown_optimal_plan`.
    """
    if problem.flown is not None:
        return flown_optimal_plan(problem, settings.nonlinear, initial)
    started = time.perf_counter()
    heuristic = heuristic_plan(problem)
    if heuristic.feasible and heuristic.schedule.added_rest_s == 0 and not np.any(heuristic.schedule.displaced_A):
        heuristic.method = "optimal"
        return heuristic  # the nominal mission is already feasible
    guesses = [heuristic, engineer_plan(problem)]
    if serves_all_load(problem, initial):
        guesses.insert(0, evaluate(problem, initial, "previous plan", 0.0))
    if not any(g.feasible for g in guesses):  # nothing to optimise within the limit: say so via the heuristic
        heuristic.method = "optimal->heuristic"
        heuristic.warnings.append("no feasible schedule found for the optimiser to improve")
        return heuristic
    transcription = _Transcription(problem, settings, minimax=False)
    schedule, success, status = transcription.solve(transcription.initial_guess(initial or heuristic.schedule))
    result = evaluate(problem, schedule, "optimal", time.perf_counter() - started)
    best = least_cost([result if success and result.feasible else None] + guesses, problem.segments)
    best.solve_s = time.perf_counter() - started
    if best is not result:  # IPOPT failed, or its local optimum rests more than another plan on this model
        if not success:
            best.warnings.append(f"optimal scheduler fell back to the {best.method}'s plan (IPOPT: {status})")
        best.details["chosen_from"] = best.method
        best.method = "optimal" if success else f"optimal->{best.method}"
    return best


def serves_all_load(problem: PlanningProblem, schedule: Schedule | None) -> bool:
    """True when ``schedule`` is a plan of ``problem``'s segments that serves all load: no generator
    switched off and the displacements of every segment adding up to zero (a shed plan's do not)."""
    if schedule is None or schedule.displaced_A.shape != (problem.n_generators, len(problem.segments)):
        return False
    return not np.any(schedule.switched_off) and bool(np.all(np.abs(schedule.displaced_A.sum(axis=0))
                                                              <= NOT_SERVED_TOLERANCE_A))


def least_cost(candidates, segments) -> PlanResult:
    """The feasible plan of ``candidates`` (PlanResult or None, in order of preference) that costs
    the manager least over ``segments``: added rest (min) plus
    :data:`~genthermal.schedule.planning.price.SHED_PRICE_MIN_PER_AH` per A·h not served
    (:func:`~genthermal.schedule.planning.price.schedule_cost_min`); a later one replaces an earlier one only
    when it costs at least :data:`MIN_REST_S` of rest less (IPOPT's interior-point residue is no
    saving).

    The optimal scheduler's rule against its baselines: the engineer's heuristic's plan and the
    heuristic's, judged on the same problem and belief, are candidates, so the plan flown never
    costs more than theirs, that is, never rests more than the engineer's would unless it leaves
    less load unserved (the affine scheduler's candidates all serve the whole load, so there it
    never rests more). A safeguard of the local optimiser too: IPOPT's optimum of the non-convex
    transcription (the free rest lengths enter the exponential decay) depends on its initial guess,
    so a baseline's plan judged on the same problem (:func:`~genthermal.schedule.planning.plan.evaluate`) may
    rest less. Measured on the robustness grid's case 28, where the optimal flight rests one 10-s
    step more than the engineer's: at each of its six re-plans IPOPT's plan rested less (0-443 s)
    than the engineer's (130-1450 s); the difference is the closed loop's, not one plan's.
    """
    feasible = [c for c in candidates if c is not None and c.feasible]
    if not feasible:
        raise ValueError("least_cost needs at least one feasible plan")
    costs = [schedule_cost_min(segments, c.schedule) for c in feasible]
    best = 0
    for i in range(1, len(feasible)):
        if costs[i] < costs[best] - MIN_REST_S / 60.0:
            best = i
    return feasible[best]


def lowest_reachable_peak(problem: PlanningProblem, settings: OptimalSettings = OptimalSettings()) -> PlanResult:
    """The schedule with the lowest predicted peak (min-max over every grid point and generator).

    Used to report an infeasible case: if its peak is above the limit, no schedule keeps
    θ ≤ θmax, and ``peak_C``, ``peak_generator`` and ``peak_segment`` say how close one can get
    and where. With ``problem.flown``, the min-max on the flown model.
    """
    if problem.flown is not None:
        return flown_optimal_plan(problem, settings.nonlinear, minimax=True)
    started = time.perf_counter()
    heuristic = heuristic_plan(problem)
    transcription = _Transcription(problem, settings, minimax=True)
    schedule, success, status = transcription.solve(transcription.initial_guess(heuristic.schedule, heuristic.peak_C))
    result = evaluate(problem, schedule, "lowest peak", time.perf_counter() - started)
    if not success or result.peak_C > heuristic.peak_C:
        heuristic.method = "lowest peak (heuristic)"
        return heuristic
    return result
