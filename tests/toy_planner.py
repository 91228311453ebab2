"""A scheduler of one file, as a user would write it: rest every generator before the first
segment the plan would breach, doubling the rest until the prediction keeps the limit.

Not a test module (no ``test_`` prefix): it registers its planner when run
(``fly --scheduler tests/toy_planner.py``); tests/test_planner_registry.py flies it.
"""

import time

import numpy as np

from genthermal.schedule.planning.plan import Schedule, evaluate, predict, rest_available_s
from genthermal.schedule.planning.registry import register_planner

NAME = "rest_first"


def rest_first_plan(problem, settings, previous):
    """Rest before the first breaching segment: 60 s, doubled up to what the segment may rest."""
    started = time.perf_counter()
    n_segments = len(problem.segments)
    schedule = Schedule.nominal(problem.n_generators, n_segments)
    _, _, breaching = predict(problem, schedule).peak()
    rest_s = settings["first_rest_s"]
    while predict(problem, schedule).peak()[0] > problem.limit_C and rest_s <= rest_available_s(problem, breaching):
        rests = np.zeros(n_segments)
        rests[breaching] = rest_s
        schedule = Schedule(np.zeros((problem.n_generators, n_segments)), rests)
        rest_s *= 2.0
    return evaluate(problem, schedule, NAME, time.perf_counter() - started)


ENTRY = register_planner(NAME, rest_first_plan, settings={"first_rest_s": 60.0})
