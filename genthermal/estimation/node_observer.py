r"""An extended Kalman filter of every node of a model from a chosen subset of its sensors.

:class:`NodeObserver` discretises the model at the record's step (the step of
:func:`genthermal.discretise.parametric_step`, exact ZOH for the affine part), linearises it about
the estimate at each step (:math:`A_k = \partial x_{k+1}/\partial x_k`), and updates with the
sensors named in ``measured`` only (each a node temperature plus a slowly drifting offset state,
which takes up persistent model error at that sensor). The unmeasured nodes (rotor,
winding) are estimated through the network's couplings. :meth:`NodeObserver.run` filters a
:class:`~genthermal.diagnose.multi_record.Record`; :meth:`NodeObserver.predict_errors` predicts
each horizon open loop from the filtered state (the inputs known ahead, as a load plan gives them).
"""

from __future__ import annotations

from typing import Mapping, Sequence

import casadi as ca
import numpy as np

from ..discretise import parametric_step
from ..errors import InputError
from ..model import ThermalModel

#: Standard deviation of the process noise of a node with a sensor, K per step (assumed, not
#: tuned: a model error of a few tenths of a kelvin per 10-s step).
DEFAULT_PROCESS_STD_K = 0.2
#: Random-walk step of each sensor's offset state, K per step (assumed: an offset that drifts by
#: about 0.4 K over an hour of 10-s steps; the real bench motor's folds choose 0.3-1 K, real-motor results page).
DEFAULT_OFFSET_STEP_K = 0.02


class NodeObserver:
    """EKF of the model's nodes from the sensors ``measured``.

    Parameters
    ----------
    model : ThermalModel
    dt_s : float
        Filter step, s (the record's).
    measured : sequence of str
        Model outputs the filter reads (may be empty: open loop).
    process_std_K : float
        Standard deviation of the process noise per node and step, K (model error).
    initial_std_K : float
        Standard deviation of the initial state of the unmeasured nodes, K.
    hidden_share : float
        Process noise of a node without a sensor as a share of ``process_std_K``: the model's
        error shows at the sensors, which absorb it locally instead of pushing the hidden nodes.
    measurement_std_K : float, optional
        Standard deviation of a sensor reading against its node, K: the sensor's noise (default,
        from the machine) or more, when the model's node and the sensor's spot differ.
    bias_std_K : float, mapping of str to float, or None
        Random-walk step, K per filter step, of an offset state per measured sensor (the reading
        is node + offset): a persistent model error at a sensor is absorbed by its offset instead
        of being pushed into the hidden nodes. A mapping gives a measured sensor its own step
        (a sensor it does not name takes ``default_bias_std_K``). None: no offsets.
    default_bias_std_K : float
        Step, K per filter step, of the sensors a ``bias_std_K`` mapping does not name.
    """

    def __init__(self, model: ThermalModel, dt_s: float, measured: Sequence[str],
                 process_std_K: float = DEFAULT_PROCESS_STD_K, initial_std_K: float = 3.0, hidden_share: float = 0.01,
                 measurement_std_K: float | None = None, bias_std_K=DEFAULT_OFFSET_STEP_K,
                 default_bias_std_K: float = DEFAULT_OFFSET_STEP_K):
        for name, value in (("process_std_K", process_std_K), ("hidden_share", hidden_share)):
            if not (np.isfinite(value) and value >= 0):
                raise InputError(name, value, "give a finite number >= 0")
        if not (np.isfinite(initial_std_K) and initial_std_K > 0):
            raise InputError("initial_std_K", initial_std_K, "give a finite standard deviation > 0 K")
        unknown = [m for m in measured if m not in model.output_names]
        if unknown:
            raise InputError("measured", unknown[0], f"not a sensor of {model.name} ({', '.join(model.output_names)})")
        self.model, self.dt_s, self.measured = model, float(dt_s), list(measured)
        nx, nu = model.n_states, len(model.input_names)
        x, u = ca.SX.sym("x", nx), ca.SX.sym("u", nu)
        p = ca.DM(model.p0)
        parts = parametric_step(model, x, u, p, self.dt_s)
        E, G1, G2 = (np.asarray(m) for m in parts.exponential(ca.DM(parts.state_matrix)))
        x_next = ca.substitute([parts.x_next], list(parts.phis), [ca.SX(ca.DM(m)) for m in (E, G1, G2)])[0]
        self._step = ca.Function("step", [x, u], [x_next, ca.jacobian(x_next, x)])
        y = model.functions["outputs"](x, u, p)
        self._outputs = ca.Function("outputs", [x, u], [y])
        C = np.asarray(ca.Function("C", [x, u], [ca.jacobian(y, x)])(np.zeros(nx), np.zeros(nu)))
        rows = [model.output_names.index(m) for m in self.measured]
        self.C = C[rows]
        noise = model.spec.interface.noise_variances_K2
        variances = [noise[i] if measurement_std_K is None else measurement_std_K ** 2 for i in rows]
        self.R = np.diag(variances) if rows else np.zeros((0, 0))
        self.initial_std_K = float(initial_std_K)
        self._output_rows = rows
        measured_nodes = {model.spec.interface.sensors[i].node for i in rows}
        self.Q = np.diag([(process_std_K if n in measured_nodes else hidden_share * process_std_K) ** 2
                          for n in model.state_names])
        steps = self._bias_steps(bias_std_K, default_bias_std_K)
        self.n_bias = len(steps)
        if self.n_bias:
            self.C = np.hstack([self.C, np.eye(self.n_bias)])
            self.Q = np.block([[self.Q, np.zeros((nx, self.n_bias))],
                               [np.zeros((self.n_bias, nx)), np.diag(np.square(steps))]])

    def _bias_steps(self, bias_std_K, default_bias_std_K) -> list:
        """Offset random-walk step of each measured sensor, K per step (empty: no offsets)."""
        if bias_std_K is None:
            return []
        mapping = isinstance(bias_std_K, Mapping)
        by_sensor, default = (dict(bias_std_K), default_bias_std_K) if mapping else ({}, bias_std_K)
        for name in by_sensor:
            if name not in self.measured:
                raise InputError("bias_std_K", name, f"not a sensor the filter reads ({', '.join(self.measured)})")
        steps = [float(by_sensor.get(name, default)) for name in self.measured]
        for name, step in zip(self.measured, steps):
            if not (np.isfinite(step) and step >= 0.0):
                raise InputError(f"bias_std_K[{name}]", step, "give a finite step >= 0 K")
        return steps

    def _initial_covariance(self) -> np.ndarray:
        """Small for nodes with a sensor of their own (their initial value was measured)."""
        sensors = self.model.spec.interface.sensors
        measured_nodes = {sensors[i].node for i in self._output_rows}
        nodes = [(0.2 if n in measured_nodes else self.initial_std_K) ** 2 for n in self.model.state_names]
        return np.diag(nodes + [1.0] * self.n_bias)  # offsets: within about 1 K

    def service_initial_state(self, record) -> np.ndarray:
        """Initial state as in service: nodes the filter measures from their first reading, the
        others from the mean of those readings (the coolant temperature without any)."""
        interface = self.model.spec.interface
        first = record.outputs[self._output_rows, 0]
        by_node: dict = {}
        for i, value in zip(self._output_rows, first):
            if np.isfinite(value):
                by_node.setdefault(interface.sensors[i].node, []).append(float(value))
        fallback = (float(np.mean([v for vs in by_node.values() for v in vs])) if by_node else
                    float(record.inputs[self.model.input_names.index(interface.coolant_input), 0]))
        return np.array([float(np.mean(by_node[n])) if n in by_node else fallback for n in self.model.state_names])

    def run(self, record, x0=None) -> tuple[np.ndarray, np.ndarray]:
        """Filtered states (n_states, N) and outputs (n_outputs, N), °C, on ``record``.

        ``x0``: initial state (default :meth:`service_initial_state`: the hidden nodes are not
        known in service).
        """
        x = self.service_initial_state(record) if x0 is None else np.array(x0, dtype=float)
        nx = x.size
        x = np.concatenate([x, np.zeros(self.n_bias)])
        P = self._initial_covariance()
        n = record.n_samples
        states = np.zeros((nx, n))
        outputs = np.zeros((len(self.model.output_names), n))
        for k in range(n):
            u = record.inputs[:, k]
            y = record.outputs[self._output_rows, k]
            valid = np.isfinite(y)
            if valid.any():
                C, R = self.C[valid], self.R[np.ix_(valid, valid)]
                innovation = y[valid] - C @ x
                S = C @ P @ C.T + R
                K = np.linalg.solve(S, C @ P).T
                x = x + K @ innovation
                P = (np.eye(x.size) - K @ C) @ P
            states[:, k] = x[:nx]
            outputs[:, k] = np.asarray(self._outputs(x[:nx], u)).ravel()  # the nodes, without offsets
            x_next, A = self._step(x[:nx], u)
            A = np.asarray(A)
            if self.n_bias:
                A = np.block([[A, np.zeros((nx, self.n_bias))], [np.zeros((self.n_bias, nx)), np.eye(self.n_bias)]])
            x = np.concatenate([np.asarray(x_next).ravel(), x[nx:]])
            P = A @ P @ A.T + self.Q
        return states, outputs

    def horizon_errors(self, record, states: np.ndarray, horizons_s: Sequence[float], outputs: Sequence[str],
                       every_s: float = 300.0) -> dict:
        """Errors (K, predicted - measured) of each output in ``outputs`` predicted ``h`` s ahead from
        the filtered state, for each horizon ``h`` in ``horizons_s``, starting every ``every_s`` s:
        {output: {h: array}} (empty where the record is shorter than ``h`` or the sensor was not read)."""
        rows = [self.model.output_names.index(o) for o in outputs]
        stride = max(1, int(round(every_s / self.dt_s)))
        errors = {o: {float(h): [] for h in horizons_s} for o in outputs}
        longest = max(int(round(h / self.dt_s)) for h in horizons_s)
        steps = {int(round(h / self.dt_s)): float(h) for h in horizons_s}
        for start in range(0, record.n_samples - 1, stride):
            x = states[:, start]
            for k in range(1, min(longest, record.n_samples - 1 - start) + 1):
                x = np.asarray(self._step(x, record.inputs[:, start + k - 1])[0]).ravel()
                if k in steps:
                    y = np.asarray(self._outputs(x, record.inputs[:, start + k])).ravel()
                    for o, r in zip(outputs, rows):
                        measured = record.outputs[r, start + k]
                        if np.isfinite(measured):
                            errors[o][steps[k]].append(y[r] - measured)
        return {o: {h: np.array(e) for h, e in by_h.items()} for o, by_h in errors.items()}

    def predict_errors(self, record, states: np.ndarray, horizons_s: Sequence[float], outputs: Sequence[str],
                       every_s: float = 300.0) -> dict:
        """RMSE (K) of each output in ``outputs`` predicted ``h`` s ahead from the filtered state,
        for each horizon ``h`` in ``horizons_s``, starting every ``every_s`` s: {output: {h: rmse}}
        (None where :meth:`horizon_errors` has none)."""
        errors = self.horizon_errors(record, states, horizons_s, outputs, every_s)
        return {o: {h: (float(np.sqrt(np.mean(np.square(e)))) if e.size else None) for h, e in by_h.items()}
                for o, by_h in errors.items()}
