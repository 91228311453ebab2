"""Estimation: data-driven models and state estimation for the generator temperatures.

:mod:`genthermal.estimation.arx` identifies ARX models of the winding and iron temperatures from
measurements (thesis 5.3); :mod:`genthermal.estimation.arx_search` chooses their structure and input.
"""
