"""A generator plant written in plain numpy, not a genthermal model: a plant of one's own to fly.

Four lumped nodes per generator, a structure genthermal's network does not have: the copper (the
stator winding, end windings folded in), the stator iron and frame, the rotor with its exciter, and
the cooling air, which is mixed in the machine (one temperature for the air inside, heated by the
three solids and carried out by the fan's flow). Losses: copper ``3 I^2 R(T)`` with copper's
temperature coefficient, iron and rotor losses growing with the square of the exciter current. The
values are round figures for a 7-A aircraft generator; at the rated current this machine settles at
115 °C, 13 K hotter than genthermal's ``genco_rf201a`` (a 16 % larger winding rise), with a winding
time constant of 24 min against the model's 15 and a cooler iron at rest (31 against 37 °C). Stepped with
implicit Euler on sub-steps of at most 2 s.

Fly it with ``genthermal fly SCENARIO --plant examples/numpy_plant/plant.py``.
"""

from __future__ import annotations

import numpy as np

ALPHA_CU = 0.00393      # 1/K, copper's temperature coefficient of resistance
R20_OHM = 0.66          # phase resistance at 20 °C, ohm
K_IRON_W_A2 = 95.0      # iron loss per exciter current squared, W/A^2
K_ROTOR_W_A2 = 60.0     # rotor and exciter loss per exciter current squared, W/A^2
C_J_K = np.array([900.0, 9000.0, 3500.0, 60.0])   # copper, iron, rotor, air heat capacities, J/K
G_CU_FE, G_CU_AIR, G_FE_AIR, G_ROTOR_AIR = 1.0, 1.4, 5.5, 3.0   # conductances, W/K
G_FRAME_AMBIENT = 0.8   # iron and frame to the ambient, W/K
FLOW_W_K = 8.0          # fan mass flow times the air's heat capacity, W/K
MAX_SUBSTEP_S = 2.0


class LumpedPlant:
    """One four-node machine per generator (module docstring), with the plant protocol of genthermal
    (``sensor_names``, ``reset(setup)``, ``step(t_s, dt_s, inputs) -> Readings``)."""

    sensor_names = ("T_winding", "T_iron")

    def __init__(self, hotter_copper: float = 1.0):
        self.r20_ohm = R20_OHM * hotter_copper
        self.temperatures = None

    def reset(self, setup) -> None:
        self.temperatures = np.full((len(setup.generator_names), 4), float(setup.initial_C))

    def _conductance_matrix(self) -> np.ndarray:
        """(4, 4) heat flow matrix between the nodes, W/K (copper, iron, rotor, air)."""
        G = np.zeros((4, 4))
        for a, b, g in ((0, 1, G_CU_FE), (0, 3, G_CU_AIR), (1, 3, G_FE_AIR), (2, 3, G_ROTOR_AIR)):
            G[a, a] -= g
            G[b, b] -= g
            G[a, b] += g
            G[b, a] += g
        G[1, 1] -= G_FRAME_AMBIENT
        G[3, 3] -= FLOW_W_K
        return G

    def step(self, t_s, dt_s, inputs):
        from genthermal.plants import Readings

        n = inputs["I_u"].shape[1]
        n_sub = max(int(np.ceil(dt_s / MAX_SUBSTEP_S)), 1)
        h = dt_s / n_sub
        G = self._conductance_matrix()
        values = np.empty((self.temperatures.shape[0], 2, n))
        for g, x in enumerate(self.temperatures):
            for i in range(n):
                current_sq = np.mean([inputs[p][g, i] ** 2 for p in ("I_u", "I_v", "I_w")])
                exciter_sq = inputs["I_exc"][g, i] ** 2
                for _ in range(n_sub):
                    # losses at the copper's present temperature, the conduction implicit
                    copper_W = 3.0 * current_sq * self.r20_ohm * (1.0 + ALPHA_CU * (x[0] - 20.0))
                    heat = np.array([copper_W, K_IRON_W_A2 * exciter_sq + G_FRAME_AMBIENT * inputs["T_ambient"][g, i],
                                     K_ROTOR_W_A2 * exciter_sq, FLOW_W_K * inputs["T_inlet"][g, i]])
                    x = np.linalg.solve(np.diag(C_J_K / h) - G, C_J_K / h * x + heat)
                values[g, :, i] = x[0], x[1]
            self.temperatures[g] = x
        return Readings(t_s + dt_s * np.arange(1, n + 1), values, self.sensor_names)


def make_plant():
    """The plant ``genthermal fly --plant`` flies."""
    return LumpedPlant()
