"""Mission documents shared by the closed-loop tests (imported by test modules, not a test)."""

#: One hour, two generators, gen1's coolant nearly blocked from 10 min (internal convection held,
#: inlet +31 K): a short flight that still needs the load manager.
SHORT = """name: short_blockage
generators: {count: 2}
faults:
  - {generator: 1, kind: coolant_blockage, onset_min: 10, k_flow: 0.2, n_flow: 0.0, inlet_rise_C: 31}
actions:
  - {condition: taxi, duration_min: 15}
  - {condition: cruise_combat, duration_min: 30}
  - {condition: landing, duration_min: 15}
"""
