"""Estimation: data-driven models and state estimation for the generator temperatures.

:mod:`genthermal.estimation.arx` identifies ARX models of the winding and iron temperatures from
measurements (thesis 5.3); :mod:`genthermal.estimation.arx_search` chooses their structure and input.
:mod:`genthermal.estimation.kalman` is the thesis's linear Kalman filter on the design model (6.2),
:mod:`genthermal.estimation.ekf` the extended Kalman filter on any model with disturbance heat
flows (starting from the disturbances a calibration left, :mod:`genthermal.estimation.disturbance_prior`),
and :mod:`genthermal.estimation.prediction` the n-step prediction study of either (6.3).
"""
