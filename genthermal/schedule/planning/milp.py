"""Discrete load schedule as a mixed-integer linear program (thesis 8.3.1): rests in whole blocks,
loads moved in whole chunks, solved by HiGHS with a certificate. Main objects: :func:`milp_plan`,
:class:`MilpSettings`.
"""

from __future__ import annotations

import dataclasses
import time

import casadi as ca
import numpy as np
import scipy.optimize
import scipy.sparse

from .engineer import engineer_plan
from .heuristic import heuristic_plan
from .optimal import LinearRows, sparse_dm
from .plan import PlanningProblem, PlanResult, Schedule, evaluate, predict


@dataclasses.dataclass(frozen=True)
class MilpSettings:
    """Settings of the discrete schedule.

    Attributes
    ----------
    block_s : float
        Rest block, s.
    chunk_A : float
        Smallest movable load, A RMS per phase (0.35 A = 5 % of the rated 7 A).
    max_rest_s : float
        Longest rest before one segment, s (whole blocks; at most ``problem.max_rest_s``).
    check_s : float
        Longest interval between temperature checks inside a segment, s.
    displacement_weight : float
        :math:`w`, s of mission time per A·h of displaced load.
    time_limit_s : float
        HiGHS time limit, s; a solution without a proof of optimality is reported as not certified.
    relative_gap : float
        HiGHS stops, and the plan is ``certified``, when the incumbent is within this fraction of
        the proven bound (issue 9's target: 1 %).
    warm_start : bool
        Round the heuristic's and engineer's plans to the MILP's grid (adding rest blocks until the
        design model keeps the limit) and use the better one as the incumbent to beat: a cutoff on
        the objective, and the plan flown when HiGHS stops without a better one.
    """

    block_s: float = 300.0
    chunk_A: float = 0.35
    max_rest_s: float = 3600.0
    check_s: float = 60.0
    displacement_weight: float = 1.0
    time_limit_s: float = 30.0
    relative_gap: float = 0.01
    warm_start: bool = True


class _Variables:
    """Allocates columns of the MILP with bounds, costs and integrality."""

    def __init__(self):
        self.lower, self.upper, self.cost, self.integer = [], [], [], []

    def take(self, count: int, lower, upper, cost=0.0, integer: bool = False) -> np.ndarray:
        first = sum(len(b) for b in self.lower)
        for store, value in ((self.lower, lower), (self.upper, upper), (self.cost, cost)):
            store.append(np.broadcast_to(np.asarray(value, dtype=float), (count,)).copy())
        self.integer.append(np.full(count, integer))
        return np.arange(first, first + count)

    def arrays(self):
        return tuple(np.concatenate(v) for v in (self.lower, self.upper, self.cost, self.integer))


def _segment_maps(problem: PlanningProblem, g: int, k: int, check_s: float):
    r"""Affine maps of segment ``k`` for generator ``g`` from its start state :math:`s` and shed
    current :math:`d`: temperatures at the check points :math:`y = \Psi_y s + \phi_y - d\sigma_y`
    (stacked; with the rise back-off rows when ``problem.rise_backoff`` > 0) and the end state
    :math:`x = \Psi s + \phi - d\sigma`."""
    generator, kappa = problem.generators[g], problem.rise_backoff
    nx = problem.x0.shape[1]
    state = (np.eye(nx), np.zeros(nx), np.zeros(nx))  # Psi, phi, sigma of the state now
    plain, robust = [], []
    for _, length, current in problem.segments[k].windows(problem.window_s):
        u0 = problem.inputs(g, current)
        offsets = (generator.Dy @ u0 + generator.ey, generator.Dy @ generator.e_I)
        start = _output_maps(generator, state, offsets)
        n = max(int(np.ceil(length / check_s - 1e-9)), 1)
        E, G = generator.step(length / n)
        for _ in range(n):
            Psi, phi, sigma = state
            state = (E @ Psi, E @ phi + G @ generator.forcing(u0), E @ sigma + G @ (generator.B @ generator.e_I))
            y = _output_maps(generator, state, offsets)
            plain.append(y)
            robust.append(tuple((1 + kappa) * a - kappa * b for a, b in zip(y, start)))
    rows = plain + (robust if kappa > 0 else [])
    return (np.vstack([r[0] for r in rows]), np.concatenate([r[1] for r in rows]),
            np.concatenate([r[2] for r in rows])), state


def _output_maps(generator, state, offsets):
    """Output maps ``(C Psi, C phi + y_u, C sigma + y_d)`` of a state map ``(Psi, phi, sigma)``."""
    Psi, phi, sigma = state
    return generator.Cy @ Psi, generator.Cy @ phi + offsets[0], generator.Cy @ sigma + offsets[1]


@dataclasses.dataclass(frozen=True)
class MilpOutcome:
    """What HiGHS returned.

    Attributes
    ----------
    x : numpy.ndarray or None
        Best integer-feasible point found (the incumbent), or None when there is none.
    status : str
        Solver and its status text.
    proven : bool
        True when HiGHS proved the incumbent optimal within ``mip_rel_gap``.
    objective : float
        Incumbent objective, min (NaN without an incumbent).
    bound : float
        Best proven lower bound of the objective (dual bound), min (NaN when the solver gives none).
    """

    x: np.ndarray | None
    status: str
    proven: bool
    objective: float
    bound: float

    @property
    def gap(self) -> float:
        """Relative gap ``(incumbent - bound) / max(|incumbent|, 1 min)``; NaN without both."""
        if not (np.isfinite(self.objective) and np.isfinite(self.bound)):
            return float("nan")
        return max(self.objective - self.bound, 0.0) / max(abs(self.objective), 1.0)


def _solve_highs(c, A_sparse, lba, uba, lbx, ubx, integer, time_limit_s, relative_gap) -> MilpOutcome:
    """Solve the MILP with HiGHS through ``scipy.optimize.milp``, which returns the incumbent and
    the dual bound when the time limit stops the search; through CasADi's ``conic`` plugin (no
    bound reported) only when this SciPy has no ``milp``."""
    if hasattr(scipy.optimize, "milp"):
        result = scipy.optimize.milp(c, constraints=scipy.optimize.LinearConstraint(A_sparse, lba, uba),
                                     bounds=scipy.optimize.Bounds(lbx, ubx), integrality=integer.astype(int),
                                     options={"time_limit": float(time_limit_s), "mip_rel_gap": relative_gap})
        x = None if result.x is None else np.asarray(result.x)
        objective = float(c @ x) if x is not None else float("nan")
        bound = getattr(result, "mip_dual_bound", None)
        bound = float(bound) if bound is not None and np.isfinite(bound) else float("nan")
        proven = result.status == 0 and x is not None
        if proven and not np.isfinite(bound):
            bound = objective - relative_gap * max(abs(objective), 1.0)  # what "Optimal" guarantees
        return MilpOutcome(x, f"HiGHS (scipy): {result.message}", proven, objective, bound)
    A = sparse_dm(A_sparse)
    options = {"discrete": integer.tolist(), "error_on_fail": False,
               "highs": {"output_flag": False, "mip_rel_gap": relative_gap, "time_limit": float(time_limit_s)}}
    solver = ca.conic("schedule_milp", "highs", {"h": ca.Sparsity(len(c), len(c)), "a": A.sparsity()}, options)
    result = solver(g=c, a=A, lba=lba, uba=uba, lbx=lbx, ubx=ubx)
    stats = solver.stats()
    status = str(stats.get("return_status"))
    x = np.asarray(result["x"]).ravel() if stats.get("primal_solution_status") == "Feasible" else None
    objective = float(c @ x) if x is not None else float("nan")
    proven = status == "Optimal" and x is not None
    bound = objective - relative_gap * max(abs(objective), 1.0) if proven else float("nan")
    return MilpOutcome(x, f"HiGHS (CasADi): {status}", proven, objective, bound)


def milp_plan(problem: PlanningProblem, settings: MilpSettings = MilpSettings()) -> PlanResult:
    """Plan the best discrete schedule (rest blocks, load chunks) by a MILP on the design model.

    Returns
    -------
    PlanResult
        ``details``: HiGHS ``status``; ``certified`` (the plan is proven within
        ``settings.relative_gap`` of the optimum); ``mip_gap``, ``incumbent_objective_min`` and
        ``bound_min`` (None when unknown); ``plan_used`` (``milp incumbent``, ``rounded heuristic
        (MILP start)``/``rounded engineer (MILP start)`` when HiGHS found nothing better, or
        ``heuristic`` when there is no discrete schedule at all: then ``method`` is
        ``milp->heuristic``); the problem size. Every plan that is not certified carries a warning
        saying how far the MILP got and which plan is flown.
    """
    started = time.perf_counter()
    n_gen, n_seg, nx = problem.n_generators, len(problem.segments), problem.x0.shape[1]
    n_blocks = int(min(settings.max_rest_s, problem.max_rest_s) // settings.block_s)
    block_min = settings.block_s / 60.0
    durations_h = np.array([s.duration_s for s in problem.segments]) / 3600.0
    hot, cold = _state_range(problem)
    cols, rows = _Variables(), LinearRows()
    rest = [cols.take(n_blocks + 1, 0.0, 1.0, block_min * np.arange(n_blocks + 1), integer=True) for _ in range(n_seg)]
    chunks = [[None] * n_seg for _ in range(n_gen)]
    for k in range(n_seg):
        low, high = problem.displacement_bounds(k)
        for g in range(n_gen):
            chunks[g][k] = cols.take(1, np.ceil(low / settings.chunk_A - 1e-9),
                                     np.floor(high / settings.chunk_A + 1e-9), integer=True)
            size = cols.take(1, 0.0, np.inf, settings.displacement_weight / 60.0 * durations_h[k] * settings.chunk_A)
            rows.add([(size, [1.0]), (chunks[g][k], [-1.0])], [0.0], [np.inf])
            rows.add([(size, [1.0]), (chunks[g][k], [1.0])], [0.0], [np.inf])
        rows.add([(rest[k], np.ones((1, n_blocks + 1)))], [1.0], [1.0])
        rows.add([(np.concatenate([chunks[g][k] for g in range(n_gen)]), np.ones((1, n_gen)))], [0.0], [0.0])
    for g, generator in enumerate(problem.generators):
        u_rest = problem.inputs(g, problem.rest_current_A)
        xss = generator.steady_state(u_rest)
        y_rest = generator.Dy @ u_rest + generator.ey
        powers = [generator.step(n * settings.block_s)[0] for n in range(n_blocks + 1)]  # Phi^n
        entry_terms, entry_value = [], problem.x0[g]
        for k in range(n_seg):
            z = [cols.take(nx, -np.inf, np.inf) for _ in range(n_blocks + 1)]  # bounded by hot/cold rows
            rows.add([(np.concatenate(z), np.tile(np.eye(nx), n_blocks + 1))] + entry_terms, entry_value, entry_value)
            for n in range(n_blocks + 1):  # z = 0 unless this rest length is chosen
                rows.add([(z[n], np.eye(nx)), (rest[k][n], -hot[g])], np.full(nx, -np.inf), 0.0)
                rows.add([(z[n], np.eye(nx)), (rest[k][n], -cold[g])], np.zeros(nx), np.inf)
            for j in range(1, n_blocks + 1):  # temperatures at the end of block j of any rest of >= j blocks
                offset = generator.Cy @ (np.eye(nx) - powers[j]) @ xss + y_rest - problem.limit_C
                rows.add([(z[n], generator.Cy @ powers[j]) for n in range(j, n_blocks + 1)]
                         + [(rest[k][n], offset[:, None]) for n in range(j, n_blocks + 1)],
                         np.full(len(offset), -np.inf), 0.0)
            start = cols.take(nx, -np.inf, np.inf)
            terms = [(z[n], -powers[n]) for n in range(n_blocks + 1)]
            terms += [(rest[k][n], -(np.eye(nx) - powers[n]) @ xss) for n in range(n_blocks + 1)]
            rows.add([(start, np.eye(nx))] + terms, np.zeros(nx), np.zeros(nx))
            (P_y, phi_y, sigma_y), (P, phi, sigma) = _segment_maps(problem, g, k, settings.check_s)
            rows.add([(start, P_y), (chunks[g][k], -settings.chunk_A * sigma_y)], np.full(len(phi_y), -np.inf),
                     problem.limit_C - phi_y)
            entry_terms = [(start, -P), (chunks[g][k], settings.chunk_A * sigma)]
            entry_value = phi
    lbx, ubx, cost, integer = cols.arrays()
    start_name, start_schedule = _discrete_start(problem, settings, n_blocks) if settings.warm_start else (None,
                                                                                                          None)
    start_objective = np.inf if start_schedule is None else milp_objective(problem, start_schedule, settings)
    if np.isfinite(start_objective):  # cutoff: only schedules at least as good as the start
        rows.add([(np.arange(len(cost)), cost[None, :])], [-np.inf], [start_objective + 1e-6])
    lba, uba = rows.bounds()
    matrix = rows.matrix(len(cost))
    outcome = _solve_highs(cost, matrix, lba, uba, lbx, ubx, integer, settings.time_limit_s, settings.relative_gap)
    if start_schedule is not None and (outcome.x is None or outcome.objective > start_objective):
        outcome = dataclasses.replace(outcome, x=None, objective=start_objective,
                                      proven=bool(np.isfinite(outcome.bound)
                                                  and start_objective - outcome.bound
                                                  <= settings.relative_gap * max(abs(start_objective), 1.0)))
    size = {"n_rows": int(matrix.shape[0]), "n_columns": int(matrix.shape[1]), "n_integers": int(integer.sum())}
    facts = {"status": outcome.status, "certified": bool(outcome.proven),
             "mip_gap": None if np.isnan(outcome.gap) else float(outcome.gap),
             "incumbent_objective_min": None if np.isnan(outcome.objective) else float(outcome.objective),
             "bound_min": None if np.isnan(outcome.bound) else float(outcome.bound),
             "time_limit_s": float(settings.time_limit_s), **size}
    if outcome.x is None and start_schedule is not None:
        facts.update(certified=bool(outcome.proven), mip_gap=None if np.isnan(outcome.gap) else float(outcome.gap),
                     incumbent_objective_min=float(start_objective))
        warnings = [] if outcome.proven else [
            f"MILP not certified ({outcome.status}): its incumbent is the {start_name} plan rounded to whole "
            f"rest blocks and load chunks, {_minutes(start_objective)}, bound {_minutes(outcome.bound)}, gap "
            f"{_percent(outcome.gap)}; flying it"]
        result = evaluate(problem, start_schedule, "milp", time.perf_counter() - started, warnings)
        result.details = {**facts, "plan_used": f"rounded {start_name} (MILP start)", "objective_min": start_objective}
        return result
    if outcome.x is None:
        fallback = heuristic_plan(problem)
        fallback.method, fallback.solve_s = "milp->heuristic", time.perf_counter() - started
        fallback.warnings.append(f"MILP stopped without any discrete schedule ({outcome.status}, bound "
                                 f"{_minutes(outcome.bound)}); flying the thesis heuristic's plan instead, "
                                 "which is not a MILP solution")
        fallback.details = {**facts, "plan_used": "heuristic", "objective_min": None}
        return fallback
    x = outcome.x
    rests = np.array([settings.block_s * np.argmax(x[r]) for r in rest])
    displaced = np.array([[settings.chunk_A * round(x[chunks[g][k][0]]) for k in range(n_seg)] for g in range(n_gen)])
    schedule = Schedule(displaced, rests)
    warnings = [] if outcome.proven else [
        f"MILP not certified ({outcome.status}): incumbent {_minutes(outcome.objective)}, bound "
        f"{_minutes(outcome.bound)}, gap {_percent(outcome.gap)}; flying the incumbent"]
    result = evaluate(problem, schedule, "milp", time.perf_counter() - started, warnings)
    result.details = {**facts, "plan_used": "milp incumbent", "objective_min": float(outcome.objective)}
    return result


def _discrete_start(problem: PlanningProblem, settings: MilpSettings, n_blocks: int):
    """The best of the heuristic's and engineer's plans rounded to the MILP's grid (rests up to
    whole blocks, sheds up to whole chunks, takers balanced in whole chunks) that the design model
    predicts within the limit: ``(name, Schedule)``, or ``(None, None)`` when none is."""
    best, best_objective = (None, None), np.inf
    for name, planner in (("heuristic", heuristic_plan), ("engineer", engineer_plan)):
        try:
            schedule = _rounded(problem, planner(problem).schedule, settings, n_blocks)
        except ValueError:
            continue
        schedule = _rest_until_within(problem, schedule, settings, n_blocks)
        if schedule is None:
            continue
        objective = milp_objective(problem, schedule, settings)
        if objective < best_objective:
            best, best_objective = (name, schedule), objective
    return best


def _rest_until_within(problem: PlanningProblem, schedule: Schedule, settings: MilpSettings, n_blocks: int):
    """Add rest blocks, one at a time before the segment of the predicted peak (or the latest
    earlier segment with room), until the design model keeps the limit; None when it cannot."""
    rests = schedule.rest_before_s.copy()
    for _ in range(n_blocks * len(rests) + 1):
        candidate = Schedule(schedule.displaced_A, rests)
        peak, _, segment = predict(problem, candidate).peak()
        if peak <= problem.limit_C:
            return candidate
        room = np.flatnonzero(rests[:segment + 1] + settings.block_s <= n_blocks * settings.block_s + 1e-6)
        if room.size == 0:
            return None
        rests = rests.copy()
        rests[room[-1]] += settings.block_s
    return None


def _rounded(problem: PlanningProblem, schedule: Schedule, settings: MilpSettings, n_blocks: int) -> Schedule:
    """``schedule`` on the MILP's grid; ValueError when it does not fit (a rest longer than
    ``n_blocks`` blocks, or no balanced whole-chunk split within the displacement bounds)."""
    blocks = np.ceil(schedule.rest_before_s / settings.block_s - 1e-6)
    if np.any(blocks > n_blocks):
        raise ValueError("rest longer than the MILP's longest rest")
    chunk = settings.chunk_A
    chunks = np.zeros(schedule.displaced_A.shape, dtype=int)
    for k in range(schedule.displaced_A.shape[1]):
        low, high = problem.displacement_bounds(k)
        lowest, highest = int(np.ceil(low / chunk - 1e-9)), int(np.floor(high / chunk + 1e-9))
        d = schedule.displaced_A[:, k] / chunk
        m = np.clip(np.ceil(d - 1e-6), lowest, highest).astype(int)  # sheds up, takes down
        excess = int(m.sum())  # > 0: takers take whole chunks more, the most room first
        while excess != 0:
            step = -1 if excess > 0 else 1
            room = (m - lowest) if step < 0 else (highest - m)
            candidates = np.flatnonzero((room > 0) & ((d <= 0) if step < 0 else (d >= 0)))
            if candidates.size == 0:  # the takers are full: the shedders shed a chunk less
                candidates = np.flatnonzero(room > 0)
            if candidates.size == 0:
                raise ValueError("no balanced whole-chunk split")
            g = candidates[np.argmax(room[candidates])]
            m[g] += step
            excess += step
        chunks[:, k] = m
    return Schedule(chunk * chunks, settings.block_s * blocks + 0.0)


def _minutes(value: float) -> str:
    return "unknown" if not np.isfinite(value) else f"{value:.2f} min"


def _percent(value: float) -> str:
    return "unknown" if not np.isfinite(value) else f"{100.0 * value:.1f} %"


#: Slack of the state range beyond the extreme steady states and the state now, K: trajectories of
#: the stable LPTN overshoot neither by more than their start's distance from steady state; the
#: slack covers the exciter's and iron loss's dependence on current between the extremes.
STATE_RANGE_SLACK_K = 10.0


def _state_range(problem: PlanningProblem) -> tuple[list, list]:
    """Per generator, (hot, cold) bounds (°C, one value for every state) for the disaggregation
    rows: the extremes of the state now, the steady states at no current and at the current limit,
    the inlet and the ambient, widened by :data:`STATE_RANGE_SLACK_K`. Much tighter than fixed
    bounds, so the LP relaxation of the rest choice is tighter."""
    hot, cold = [], []
    nx = problem.x0.shape[1]
    for g, generator in enumerate(problem.generators):
        extremes = np.concatenate([problem.x0[g], generator.steady_state(problem.inputs(g, problem.current_limit_A)),
                                   generator.steady_state(problem.inputs(g, 0.0)),
                                   [problem.inlet_C[g], problem.ambient_C]])
        hot.append(np.full(nx, extremes.max() + STATE_RANGE_SLACK_K))
        cold.append(np.full(nx, extremes.min() - STATE_RANGE_SLACK_K))
    return hot, cold


def milp_objective(problem: PlanningProblem, schedule: Schedule, settings: MilpSettings = MilpSettings()) -> float:
    """The MILP objective (min) of any discrete ``schedule``: rest minutes plus the displacement
    penalty, for comparing against the MILP's certified optimum."""
    durations_h = np.array([s.duration_s for s in problem.segments]) / 3600.0
    penalty = settings.displacement_weight / 60.0 * np.sum(np.abs(schedule.displaced_A) * durations_h)
    return schedule.added_rest_s / 60.0 + float(penalty)
