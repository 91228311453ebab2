"""genthermal: lumped-parameter thermal models of electrical generators.

One symbolic network, many consumers: simulation, generated C, Kalman filter, ARX identification.
"""

__version__ = "0.1.0"
