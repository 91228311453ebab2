"""The robustness grid: closed-loop flights on plants the manager does not know (:mod:`.sweep`),
run in single-thread worker processes (:mod:`.sweep_workers`), scored against the best baseline
(:mod:`.baseline_comparison`) and the hindsight plan (:mod:`.hindsight`).
"""
