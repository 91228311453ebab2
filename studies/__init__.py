"""Studies that use genthermal but are not part of it: the chapter-7 calibration of the thesis generator.

The benchmarks (``benchmarks/fit_chapter7.py``, ``chapter7_feasibility.py``, ``managed_blockage.py``,
``reproduce_thesis.py``) and their tests import these with the repository root on ``sys.path``;
the parameter set they write, ``genco_rf201a:chapter7``, ships with the package
(:mod:`genthermal.machines.parameter_sets`).
"""
