"""The planner role: schedules (:mod:`.plan`) and the schedulers that make them.

Thesis heuristic (:mod:`.heuristic`), the engineer's heuristic (:mod:`.engineer`), the optimal
scheduler (:mod:`.optimal`, :mod:`.optimal_nlp`), the MILP (:mod:`.milp`) and load shedding
(:mod:`.shed`, :mod:`.optimal_shed`), with the price of a schedule (:mod:`.price`).
"""
