"""Schedules and what they do: segments of load demand (:class:`Segment`), displaced current and
rests (:class:`Schedule`), timelines, the planning problem (:class:`PlanningProblem`), predictions
on the design model (:func:`predict`) and a scheduler's answer (:class:`PlanResult`).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd

from ...errors import InputError
from ...exciter import DEFAULT_POWER_FACTOR
from ...machines.interface import GeneratorRole
from ...mission import DEFAULT_GENERATOR, DEFAULT_RATED_CURRENT_A, Mission

#: Default back-off margin below θmax the manager plans to, K.
DEFAULT_MARGIN_K = 2.5
#: Tolerance on the limit when checking a prediction, K.
LIMIT_TOLERANCE_K = 1e-6
#: A plan is feasible when its predicted peak is within this of the planning limit, K
#: (:func:`evaluate`; the re-plan within the lowest reachable peak,
#: :func:`~genthermal.schedule.flight.replanning.plan_with`, judges its plans with the same).
FEASIBLE_TOLERANCE_K = 0.05


@dataclasses.dataclass(frozen=True)
class Segment:
    """A piece of load demand: an action, or what remains of it.

    Attributes
    ----------
    action_index : int
        Index of the action in the mission.
    label : str
        ``"7 landing"``.
    duration_s : float
    levels : tuple of (float, float)
        ``(offset from the segment start, s; phase current, A RMS)``, piecewise constant.
    """

    action_index: int
    label: str
    duration_s: float
    levels: tuple[tuple[float, float], ...]

    def current_at(self, offset_s) -> np.ndarray:
        """Nominal phase current (A) at offsets ``offset_s`` (s) into the segment."""
        starts = np.array([s for s, _ in self.levels])
        currents = np.array([c for _, c in self.levels])
        return currents[np.searchsorted(starts, np.asarray(offset_s) + 1e-9, side="right") - 1]

    @property
    def pieces(self) -> list[tuple[float, float]]:
        """``(length s, current A)`` of each constant piece."""
        ends = [s for s, _ in self.levels[1:]] + [self.duration_s]
        return [(end - start, current) for (start, current), end in zip(self.levels, ends) if end - start > 1e-9]

    def windows(self, window_s: float) -> list[tuple[float, float, float]]:
        """``(start s, length s, current A)``: each constant piece split into equal windows of at
        most ``window_s`` (the management cycle). The robust back-off compares a temperature with
        its value at the start of its window."""
        result, start = [], 0.0
        for length, current in self.pieces:
            n = max(int(np.ceil(length / window_s - 1e-9)), 1)
            result += [(start + j * length / n, length / n, current) for j in range(n)]
            start += length
        return result

    def window_start_steps(self, dt_s: float, window_s: float) -> np.ndarray:
        """For every step of ``dt_s`` of the segment, the index of the first step of its window."""
        n_run = max(int(round(self.duration_s / dt_s)), 1)
        starts = np.array([start for start, _, _ in self.windows(window_s)])
        first_steps = np.ceil(starts / dt_s - 1e-9).astype(int)
        owner = np.searchsorted(starts, np.arange(n_run) * dt_s + 1e-9, side="right") - 1
        return first_steps[owner]

    @property
    def peak_A(self) -> float:
        """Highest nominal current of the segment, A."""
        return max(current for _, current in self.pieces)

    @property
    def low_A(self) -> float:
        """Lowest nominal current of the segment, A."""
        return min(current for _, current in self.pieces)

    def after(self, elapsed_s: float) -> "Segment":
        """What remains of the segment after ``elapsed_s`` (s) of it have been flown."""
        kept = [(max(start - elapsed_s, 0.0), current) for start, current in self.levels
                if start > elapsed_s + 1e-9]
        first = (0.0, float(self.current_at(elapsed_s)))
        return Segment(self.action_index, self.label, self.duration_s - elapsed_s, tuple([first] + kept))


def split_segments(segments, interval_s: float, step_s: float) -> tuple[Segment, ...]:
    """Every segment cut into its windows (:meth:`Segment.windows`) of at most ``interval_s`` (s),
    each a segment of constant current with the action's index and label: a schedule on them
    displaces load per control interval and may rest before any of them.

    The cuts are moved to the nearest whole step of ``step_s`` (s) from the start of their piece of
    constant load, so that every window is a whole number of simulation steps and the windows add up
    to the segment. Equal windows of the 49-min cruise piece of ``blockage_large`` are 294 s; put
    one by one on the 10-s grid (:func:`build_timeline`) they lost 4 s each, and the nonlinear
    planner's flight ended 40 s before the mission, with no rest and no load reported shed."""
    if not (np.isfinite(interval_s) and interval_s > 0):
        raise InputError("interval_s", interval_s, "the control interval must be a positive number of seconds")
    if not (np.isfinite(step_s) and 0 < step_s <= interval_s):
        raise InputError("step_s", step_s, f"the simulation step must be a positive number of seconds no longer "
                         f"than the control interval {interval_s:g} s")
    split = []
    for segment in segments:
        piece_starts = [start for start, _ in segment.levels] + [segment.duration_s]
        cuts = []
        for start, _, _ in segment.windows(interval_s):
            piece = max(p for p in piece_starts if p <= start + 1e-9)
            cuts.append(piece + round((start - piece) / step_s) * step_s)
        for begin, end in zip(cuts, cuts[1:] + [segment.duration_s]):
            if end - begin > 1e-9:
                split.append(Segment(segment.action_index, segment.label, end - begin,
                                     ((0.0, float(segment.current_at(begin))),)))
    return tuple(split)


def mission_segments(mission: Mission) -> tuple[Segment, ...]:
    """One :class:`Segment` per action of ``mission`` (currents in A RMS)."""
    segments = []
    for index, action in enumerate(mission.actions):
        name = action.condition.name if action.condition else f"{action.load_percent:g} %"
        number = f"{action.condition.number} " if action.condition else ""
        levels = tuple((offset, percent / 100.0 * mission.rated_current_A) for offset, percent in action.load_steps()
                       if offset < action.duration_s)
        segments.append(Segment(index, f"{number}{name}", action.duration_s, levels))
    return tuple(segments)


@dataclasses.dataclass(frozen=True)
class Schedule:
    """Displaced current per generator and segment, and rest before each segment.

    Attributes
    ----------
    displaced_A : numpy.ndarray
        Shape (n_generators, n_segments), A RMS; positive: the generator sheds load.
    rest_before_s : numpy.ndarray
        Shape (n_segments,), s.
    switched_off : numpy.ndarray, optional
        Shape (n_generators,), True for a generator switched off (0 A throughout); default none.
    """

    displaced_A: np.ndarray
    rest_before_s: np.ndarray
    switched_off: np.ndarray | None = None

    def __post_init__(self):
        if self.switched_off is None:
            object.__setattr__(self, "switched_off", np.zeros(self.displaced_A.shape[0], dtype=bool))

    @classmethod
    def nominal(cls, n_generators: int, n_segments: int, switched_off=None) -> "Schedule":
        """No displacement, no rest: the mission as planned (with ``switched_off`` generators off)."""
        return cls(np.zeros((n_generators, n_segments)), np.zeros(n_segments),
                   None if switched_off is None else np.array(switched_off, dtype=bool))

    @property
    def added_rest_s(self) -> float:
        """Total rest, s."""
        return float(np.sum(self.rest_before_s))

    def displaced_Ah(self, segments) -> float:
        """Charge moved off the generators that shed load, A·h (phase current × time)."""
        durations = np.array([s.duration_s for s in segments])
        return float(np.sum(np.clip(self.displaced_A, 0.0, None) * durations) / 3600.0)

    def rounded(self, dt_s: float) -> "Schedule":
        """The schedule with rests rounded up to whole steps of ``dt_s`` (s)."""
        return Schedule(self.displaced_A, np.ceil(self.rest_before_s / dt_s - 1e-6) * dt_s, self.switched_off)

    def within_rest_budget(self, budget_s: float, first_max_s: float = np.inf) -> "Schedule":
        """The schedule with the first rest cut to ``first_max_s`` (s) and then its rests cut,
        earliest kept, so that they add up to at most ``budget_s`` (s)."""
        rests = self.rest_before_s.copy()
        if rests.size:
            rests[0] = min(rests[0], max(first_max_s, 0.0))
        allowed = np.clip(budget_s - np.concatenate([[0.0], np.cumsum(rests)[:-1]]), 0.0, None)
        return Schedule(self.displaced_A, np.minimum(rests, allowed), self.switched_off)

    def table(self, segments, generator_names) -> pd.DataFrame:
        """One row per segment: action, rest before (min), duration (min), nominal and applied
        continuous current per generator (A)."""
        rows = []
        for k, segment in enumerate(segments):
            row = {"action": segment.action_index + 1, "condition": segment.label,
                   "rest_before_min": round(self.rest_before_s[k] / 60.0, 2) + 0.0,
                   "duration_min": round(segment.duration_s / 60.0, 2),
                   "nominal_A": round(segment.levels[-1][1], 3)}
            for g, name in enumerate(generator_names):
                carried = 0.0 if self.switched_off[g] else segment.levels[-1][1] - self.displaced_A[g, k]
                row[f"{name}_A"] = round(carried, 3) + 0.0
            rows.append(row)
        return pd.DataFrame(rows)


@dataclasses.dataclass(frozen=True)
class Timeline:
    """A schedule sampled on a uniform grid (value at row i held over ``[t_i, t_i + dt)``).

    Attributes
    ----------
    dt_s : float
    currents_A : numpy.ndarray
        (n_generators, n_steps) phase currents, A RMS.
    segment : numpy.ndarray
        (n_steps,) index of the segment the step belongs to (its rest included).
    resting : numpy.ndarray
        (n_steps,) True during rests.
    offset_s : numpy.ndarray
        (n_steps,) time since the start of the segment (rest: since the start of the rest), s.
    window_start : numpy.ndarray
        (n_steps,) index of the first step of the step's window (see :meth:`Segment.windows`; a
        rest is one window).
    """

    dt_s: float
    currents_A: np.ndarray
    segment: np.ndarray
    resting: np.ndarray
    offset_s: np.ndarray
    window_start: np.ndarray

    @property
    def n_steps(self) -> int:
        """Number of steps."""
        return self.segment.size

    def head(self, n_steps: int) -> "Timeline":
        """The first ``n_steps`` steps."""
        return Timeline(self.dt_s, self.currents_A[:, :n_steps], self.segment[:n_steps], self.resting[:n_steps],
                        self.offset_s[:n_steps], self.window_start[:n_steps])


def rest_then_segment(segment: Segment, rest_s: float, rest_current_A: float, dt_s: float) -> tuple[int, np.ndarray]:
    """``(n_rest, currents)``: the phase currents (A) of a rest of ``rest_s`` (rounded up to whole
    steps of ``dt_s``) at ``rest_current_A`` followed by ``segment``'s nominal load (its duration
    rounded to the nearest step, at least one), and the number of rest steps."""
    n_rest = int(np.ceil(rest_s / dt_s - 1e-6))
    n_run = max(int(round(segment.duration_s / dt_s)), 1)
    return n_rest, np.concatenate([np.full(n_rest, rest_current_A), segment.current_at(np.arange(n_run) * dt_s)])


def build_timeline(segments, schedule: Schedule, rest_current_A: float, dt_s: float,
                   window_s: float = 300.0) -> Timeline:
    """Sample ``schedule`` on a grid of ``dt_s``; rests rounded up to whole steps, segment
    durations to the nearest step; windows of at most ``window_s`` for the robust back-off;
    switched-off generators carry 0 A."""
    n_generators = schedule.displaced_A.shape[0]
    currents, segment_of, resting, offsets, window_start = [], [], [], [], []
    first = 0
    for k, segment in enumerate(segments):
        n_rest = int(np.ceil(schedule.rest_before_s[k] / dt_s - 1e-6))
        n_run = max(int(round(segment.duration_s / dt_s)), 1)
        run_offsets = np.arange(n_run) * dt_s
        nominal = segment.current_at(run_offsets)
        carried = np.hstack([np.full((n_generators, n_rest), rest_current_A),
                             nominal[None, :] - schedule.displaced_A[:, k:k + 1]])
        carried[schedule.switched_off] = 0.0
        currents.append(carried)
        segment_of.append(np.full(n_rest + n_run, k))
        resting.append(np.arange(n_rest + n_run) < n_rest)
        offsets.append(np.concatenate([np.arange(n_rest) * dt_s, run_offsets]))
        window_start.append(np.concatenate([np.full(n_rest, first),
                                            first + n_rest + segment.window_start_steps(dt_s, window_s)]))
        first += n_rest + n_run
    return Timeline(dt_s, np.hstack(currents), np.concatenate(segment_of), np.concatenate(resting),
                    np.concatenate(offsets), np.concatenate(window_start))


def robust_outputs(outputs: np.ndarray, window_start: np.ndarray, rise_backoff: float) -> np.ndarray:
    r"""Temperatures with the rise back-off, :math:`(1+\kappa)\,\theta_{i+1} - \kappa\,\theta_{w(i)}`.

    Parameters
    ----------
    outputs : numpy.ndarray
        (..., n_steps + 1) temperatures at the samples (sample i + 1 after step i), °C.
    window_start : numpy.ndarray
        (n_steps,) first step of each step's window: :math:`\theta_{w(i)}` is the temperature when
        that window began.
    rise_backoff : float
        :math:`\kappa`, the relative error of a temperature *rise* the plan must tolerate.

    Returns
    -------
    numpy.ndarray
        (..., n_steps), °C.
    """
    return (1.0 + rise_backoff) * outputs[..., 1:] - rise_backoff * outputs[..., window_start]


def remaining_after(segments, schedule: Schedule, timeline: Timeline, n_steps: int):
    """Segments and schedule still to fly after the first ``n_steps`` of ``timeline``.

    Returns
    -------
    (tuple of Segment, Schedule)
        Empty when the plan is complete.
    """
    if n_steps >= timeline.n_steps:
        return (), Schedule.nominal(schedule.displaced_A.shape[0], 0, schedule.switched_off)
    k = int(timeline.segment[n_steps])
    rest = schedule.rest_before_s.copy()[k:]
    if timeline.resting[n_steps]:
        rest[0] = max(rest[0] - timeline.offset_s[n_steps], 0.0)
        first = segments[k]
    else:
        rest[0] = 0.0
        first = segments[k].after(float(timeline.offset_s[n_steps]))
    return (first,) + tuple(segments[k + 1:]), Schedule(schedule.displaced_A[:, k:].copy(), rest,
                                                        schedule.switched_off.copy())


def generator_inputs(timeline: Timeline, generator: int, t0_s: float, inlet_C, ambient_C: float,
                     power_factor: float = DEFAULT_POWER_FACTOR, rated_current_A: float = DEFAULT_RATED_CURRENT_A,
                     role: GeneratorRole = DEFAULT_GENERATOR) -> pd.DataFrame:
    """Input frame of one generator (columns of :meth:`Mission.to_inputs`) for ``timeline``
    starting at ``t0_s``; ``inlet_C(t)`` gives the inlet temperature (°C); the exciter current
    follows the load at ``power_factor`` by the exciter law of ``role`` (the machine's generator
    role, default the default machine's). A last row repeats the final input so the frame also
    yields the state at the end."""
    n = timeline.n_steps
    time_s = t0_s + np.arange(n + 1) * timeline.dt_s
    current = np.append(timeline.currents_A[generator], timeline.currents_A[generator, -1])
    columns = {"time_s": time_s, **{phase: current for phase in role.phase_inputs}}
    columns[role.excitation_input] = role.exciter_law(np.clip(current, 0.0, None), power_factor, rated_current_A)
    columns[role.coolant_input] = inlet_C(time_s)
    columns[role.ambient_input] = np.full(n + 1, ambient_C)
    return pd.DataFrame(columns)


@dataclasses.dataclass
class PlanningProblem:
    r"""What a scheduler needs at one planning instant, all on the design model.

    Attributes
    ----------
    segments : tuple of Segment
        Remaining load demand.
    generators : list of AffineGenerator
        Design model of each generator with the faults known now.
    x0 : numpy.ndarray
        (n_generators, n_states) state now, °C.
    inlet_C : numpy.ndarray
        (n_generators,) inlet temperature, held over the prediction (thesis 7.3.6), °C.
    ambient_C : float
    rest_current_A, current_limit_A : float
        Minimum power mode and highest phase current, A RMS.
    limit_C : float
        Planning limit (θmax minus the back-off margin), °C.
    max_rest_s : float
        Longest rest before one segment, s; for the first segment the rest already flown right
        before it (``rest_taken_s``) counts against it (:func:`rest_available_s`).
    dt_s : float
        Prediction grid, s (the design model step).
    rise_backoff : float
        :math:`\kappa`: every temperature must also satisfy
        :math:`\theta + \kappa(\theta - \theta_{window\,start}) \le \theta_{lim}`, a plan robust
        to a design model that underestimates a rise within one window by up to :math:`\kappa`.
    window_s : float
        Longest window of the back-off, s (the management cycle: the filter corrects the state
        once per cycle, so model errors build up over at most one window).
    rest_budget_s : float
        Total rest the plan may add, s (what is left of the flight's rest budget): a constraint of
        the optimal scheduler and of the lowest-peak search; the other schedulers bound each rest
        by ``max_rest_s`` and the manager cuts their total to this, earliest rests kept
        (:meth:`Schedule.within_rest_budget`).
    rest_taken_s : float
        Rest already flown right before the first segment (a rest in progress), s: the rest
        before that segment may add only ``max_rest_s`` minus this.
    flown : FlownPlanning, optional
        Plan on the nonlinear model the manager flies (:mod:`genthermal.schedule.planning.flown`): then
        :func:`predict` runs that model from the filter's state, with a back-off derived from the
        filter's covariance, and ``limit_C`` is θmax itself. Default None: the design models.
    unexplained_rise_K : numpy.ndarray, optional
        (n_generators, n_outputs) rise of each temperature over the last management cycle that the
        filter's prediction did not explain beyond its noise, K (>= 0;
        :func:`~genthermal.schedule.planning.shed.unexplained_rise`): heating of a fault the disturbance
        states have not yet taken up. The shed plan (:func:`~genthermal.schedule.planning.shed.shed_plan`)
        holds every generator within the limit over the next cycle with this rise added. Default
        None: no such rise.
    """

    segments: tuple
    generators: list
    x0: np.ndarray
    inlet_C: np.ndarray
    ambient_C: float
    rest_current_A: float
    current_limit_A: float
    limit_C: float
    max_rest_s: float = 3600.0
    dt_s: float = 10.0
    rise_backoff: float = 0.0
    window_s: float = 300.0
    rest_budget_s: float = np.inf
    rest_taken_s: float = 0.0
    flown: object = None
    unexplained_rise_K: np.ndarray | None = None

    @property
    def n_generators(self) -> int:
        """Number of generators."""
        return len(self.generators)

    def displacement_bounds(self, k: int) -> tuple[float, float]:
        """``(lowest, highest)`` displaced current (A) of any generator in segment ``k``: a
        generator carries between 0 and the current limit."""
        segment = self.segments[k]
        return segment.peak_A - self.current_limit_A, segment.low_A

    def inputs(self, g: int, current_A) -> np.ndarray:
        """Input vectors of generator ``g`` for phase currents ``current_A``."""
        return self.generators[g].input(current_A, self.inlet_C[g], self.ambient_C)


def rest_available_s(problem: PlanningProblem, k: int, earlier_rest_s: float = 0.0) -> float:
    """Rest segment ``k`` of ``problem`` may still add, s (>= 0): the longest rest before one
    action, less for the first segment the rest already flown right before it
    (``rest_taken_s``), and what is left of the flight's rest budget after ``earlier_rest_s`` (s)
    planned before the earlier segments. The rest already flown is counted once: the budget
    left (``rest_budget_s``) has it taken off already."""
    longest = problem.max_rest_s - (problem.rest_taken_s if k == 0 else 0.0)
    return max(min(longest, problem.rest_budget_s - earlier_rest_s), 0.0)


@dataclasses.dataclass
class Prediction:
    """Prediction of a schedule: ``outputs`` (n_generators, n_outputs, n_steps + 1) at ``time_s``
    (from the planning instant), with the ``timeline`` that produced them, the ``rise_backoff`` of
    the problem and, when planning on the flown model, the uncertainty back-off ``backoff_K``
    (same shape as ``outputs``, K)."""

    time_s: np.ndarray
    outputs: np.ndarray
    timeline: Timeline
    rise_backoff: float = 0.0
    backoff_K: np.ndarray | None = None

    def future(self) -> np.ndarray:
        """(n_generators, n_outputs, n_steps) future temperatures with every back-off (the rise
        back-off and the uncertainty back-off) added, °C."""
        backed_off = self.outputs if self.backoff_K is None else self.outputs + self.backoff_K
        return np.maximum(backed_off[:, :, 1:],
                          robust_outputs(backed_off, self.timeline.window_start, self.rise_backoff))

    def peak(self) -> tuple[float, int, int]:
        """``(peak °C, generator, segment)`` over the future samples, the back-offs included
        (the first sample is the present)."""
        future = self.future().max(axis=1)
        g, i = np.unravel_index(np.argmax(future), future.shape)
        return float(future[g, i]), int(g), int(self.timeline.segment[i])


def affine_states(E: np.ndarray, forced: np.ndarray, x0: np.ndarray) -> np.ndarray:
    r"""States after each step of :math:`x_{i+1} = E x_i + f_i` from ``x0``.

    A doubling scan (Hillis-Steele): after the pass of offset :math:`s`, row i holds
    :math:`\sum_{j=i-2s+1}^{i} E^{i-j} f_j` (with :math:`E x_0` folded into :math:`f_0`), so
    :math:`\lceil\log_2 n\rceil` products of all rows with :math:`E^s` replace n matrix-vector
    products in a Python loop: about ten times faster on a 1-h segment at 10 s (the schedulers
    predict thousands of such runs per plan). The sums are the loop's, added in another order.

    Parameters
    ----------
    E : numpy.ndarray
        (n_states, n_states) step matrix.
    forced : numpy.ndarray
        (n_steps, n_states) forcing of each step.
    x0 : numpy.ndarray
        (n_states,) state before the first step.

    Returns
    -------
    numpy.ndarray
        (n_steps, n_states): row i is the state after step i.
    """
    x = np.array(forced, dtype=float)
    if x.shape[0] == 0:
        return x
    x[0] += E @ np.asarray(x0, dtype=float)
    power, offset = np.asarray(E, dtype=float).T, 1
    while offset < x.shape[0]:
        x[offset:] += x[:-offset] @ power  # the right-hand side is evaluated before the rows change
        power, offset = power @ power, 2 * offset
    return x


def predict(problem: PlanningProblem, schedule: Schedule) -> Prediction:
    """Run ``schedule`` on the design models from ``problem.x0`` on the grid ``problem.dt_s``, or
    on the flown models from the filters' states when ``problem.flown`` is set."""
    timeline = build_timeline(problem.segments, schedule, problem.rest_current_A, problem.dt_s, problem.window_s)
    if problem.flown is not None:
        time_s, outputs, backoff = problem.flown.predict(problem, timeline)
        return Prediction(time_s, outputs, timeline, problem.rise_backoff, backoff)
    n = timeline.n_steps
    outputs = np.empty((problem.n_generators, problem.generators[0].Cy.shape[0], n + 1))
    for g, generator in enumerate(problem.generators):
        E, G = generator.step(problem.dt_s)
        u = problem.inputs(g, np.append(timeline.currents_A[g], timeline.currents_A[g, -1]))
        forced = generator.forcing(u[:n]) @ G.T
        x = np.vstack([problem.x0[g], affine_states(E, forced, problem.x0[g])])
        outputs[g] = generator.outputs(x, u).T
    return Prediction(np.arange(n + 1) * problem.dt_s, outputs, timeline, problem.rise_backoff)


@dataclasses.dataclass
class PlanResult:
    """A scheduler's answer.

    Attributes
    ----------
    schedule : Schedule
    feasible : bool
        True when the predicted peak stays within the planning limit.
    peak_C : float
        Predicted peak of the schedule (design model), °C.
    peak_generator, peak_segment : int
        Where the peak occurs.
    solve_s : float
        Wall-clock time of the planning, s.
    method : str
        ``heuristic``, ``optimal``, ``milp`` or a fallback (``optimal->heuristic``).
    warnings : list of str
    details : dict
        Solver facts (the MILP's objective, status and certificate).
    """

    schedule: Schedule
    feasible: bool
    peak_C: float
    peak_generator: int
    peak_segment: int
    solve_s: float
    method: str
    warnings: list = dataclasses.field(default_factory=list)
    details: dict = dataclasses.field(default_factory=dict)


def evaluate(problem: PlanningProblem, schedule: Schedule, method: str, solve_s: float,
             warnings=(), tolerance_K: float = FEASIBLE_TOLERANCE_K) -> PlanResult:
    """Predict ``schedule`` on the design model and wrap it as a :class:`PlanResult`; feasible when
    the peak is within ``tolerance_K`` of the planning limit."""
    peak, g, k = predict(problem, schedule).peak()
    return PlanResult(schedule, within_limit(peak, problem.limit_C, tolerance_K), peak, g, k, solve_s, method,
                      list(warnings))


def within_limit(peak_C: float, limit_C: float, tolerance_K: float = FEASIBLE_TOLERANCE_K) -> bool:
    """Whether a forecast peak (°C) keeps the planning limit ``limit_C`` (°C) within ``tolerance_K``:
    the one test of feasibility, for a scheduler's prediction (:func:`evaluate`) and for the
    open-loop plan's forecast (:func:`~genthermal.schedule.flight.open_loop.judge_forecast`)."""
    return bool(peak_C <= limit_C + tolerance_K)
