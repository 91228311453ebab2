"""A power system of N ≥ 2 generators sharing one mission's load demand, with faults at onsets,
the true plants and the design model as matrices. Main objects: :class:`PowerSystem`,
:class:`AffineGenerator`, :class:`Fault`. Method: docs/guide/flight-methods.md.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
from typing import Any, Mapping

import casadi as ca
import numpy as np

from ..coolant import OUTLET_DIAMETER_MM, inlet_rise, outlet_flow_fraction
from ..conditions import LOAD_CONDITIONS, checked_number, reject_unknown_keys
from ..design import linear_design_model
from ..discretise import ModalDecay, phi_matrices
from ..effects import get_effect
from ..errors import InputError
from ..estimation.ekf import node_heat_capacities
from ..machines import DEFAULT_MACHINE
from ..model_file import PARAMETER_SETS, load_model
from ..exciter import DEFAULT_POWER_FACTOR, exciter_line
from ..mission import Mission
from .planning.shed import INFEASIBLE_RESPONSES
from .system_frame import SystemFrame, TruePlants

#: Minimum power mode: the continuous level of condition 1 (loading and preparation), % of rated.
DEFAULT_REST_PERCENT = LOAD_CONDITIONS[0].continuous_percent
#: Assumed model mismatch of the true plant against the design model (parameter factors).
DEFAULT_PLANT_MISMATCH = {"h_end_air": 0.9, "R0": 1.05}
FAULT_KINDS = ("coolant_blockage", "inlet_rise", "effect")
def _filter_name(config: Mapping) -> str | None:
    """``generators.filter`` of a scenario, None when it names none; InputError for a name that is
    not a key of :data:`genthermal.schedule.state_estimator.FLIGHT_FILTERS`."""
    from .state_estimator import FLIGHT_FILTERS# monitor imports this module

    if "filter" not in config:
        return None
    if config["filter"] not in FLIGHT_FILTERS:
        raise InputError("generators.filter", config["filter"], f"must be one of {', '.join(FLIGHT_FILTERS)}")
    return str(config["filter"])


def _infeasible_response(value, field: str = "generators.when_infeasible") -> str | None:
    """``value`` checked against :data:`genthermal.schedule.planning.shed.INFEASIBLE_RESPONSES` (None
    passes: the manager's own); InputError naming ``field`` otherwise."""
    if value is None:
        return None
    if not isinstance(value, str) or value not in INFEASIBLE_RESPONSES:
        raise InputError(field, value, f"must be one of {', '.join(INFEASIBLE_RESPONSES)}")
    return value


#: The keys of a scenario's ``generators:`` that set one of the manager's settings of the same name.
MANAGER_KEYS = ("margin_K", "filter", "when_infeasible")
_GENERATOR_KEYS = ("count", "names", "rest_percent", "limit_C", "current_limit_percent", "margin_K",
                   "filter", "plant_mismatch", "machine", "when_infeasible")
_INLET_KEYS = ("inlet_rise_C", "inlet_rise_tau_min", "inlet_load_share")
_FAULT_KEYS = {"coolant_blockage": ("k_flow", "outlet_diameter_mm", "n_flow") + _INLET_KEYS,
               "inlet_rise": _INLET_KEYS,
               "effect": ("effect", "values") + _INLET_KEYS}


@dataclasses.dataclass(frozen=True)
class Fault:
    """A fault on one generator from an onset time on.

    Attributes
    ----------
    generator : int
        Index of the generator (0-based).
    onset_s : float
        Onset, s since the mission start (absolute time: rests do not move it).
    kind : str
        One of :data:`FAULT_KINDS`.
    inlet_rise_C : float
        Rise of the coolant inlet temperature from the onset on, K.
    effect : str or None
        Catalogue effect applied to the plant and design models (``coolant_flow_reduction`` for a
        blockage), None for an inlet rise alone.
    values : dict
        Parameter values of ``effect`` (``{"k_flow": 0.2}``).
    inlet_rise_tau_s : float
        Time constant of the inlet rise, s (0: a step; :func:`genthermal.coolant.inlet_rise`).
    inlet_load_share : float
        Share of the inlet rise that follows the generator's load, in [0, 1]
        (:func:`genthermal.coolant.inlet_load_factor`; 0: the rise of the fault alone).
    """

    generator: int
    onset_s: float
    kind: str
    inlet_rise_C: float = 0.0
    effect: str | None = None
    values: Mapping[str, float] = dataclasses.field(default_factory=dict)
    inlet_rise_tau_s: float = 0.0
    inlet_load_share: float = 0.0

    def describe(self, names: tuple[str, ...]) -> str:
        """One line: what happens to which generator when."""
        what = ", ".join(f"{k}={v:g}" for k, v in self.values.items())
        effect = f"{self.effect}({what})" if self.effect else ""
        rise = f"inlet +{self.inlet_rise_C:g} K" if self.inlet_rise_C else ""
        if rise and self.inlet_load_share:
            rise += f" ({self.inlet_load_share:g} of it following the load)"
        return f"{names[self.generator]}: {self.kind} at {self.onset_s / 60:g} min " + \
            " and ".join(part for part in (effect, rise) if part)


def _number(entry, key, path, low, high, unit, default=None):
    if key not in entry:
        if default is None:
            raise InputError(f"{path}.{key}", None, f"missing: give {key} ({unit})")
        return default
    value = checked_number(entry[key], f"{path}.{key}", f"a number ({unit})")
    if not low <= value <= high:
        raise InputError(f"{path}.{key}", entry[key], f"must lie in {low:g}..{high:g} {unit}")
    return value


def _generator_index(value, names, path) -> int:
    if isinstance(value, int) and not isinstance(value, bool) and 1 <= value <= len(names):
        return value - 1
    if isinstance(value, str) and value in names:
        return names.index(value)
    raise InputError(f"{path}.generator", value,
                     f"must be a generator number 1..{len(names)} or a name among {', '.join(names)}")


def parse_fault(entry: Any, names: tuple[str, ...], path: str) -> Fault:
    """Build a :class:`Fault` from a scenario entry (schema in the module docstring).

    Raises
    ------
    InputError
        Naming the field (``faults[0].k_flow``).
    """
    if not isinstance(entry, Mapping):
        raise InputError(path, entry, "each fault must be a mapping such as {generator: 1, kind: "
                         "coolant_blockage, onset_min: 66, k_flow: 0.2, inlet_rise_C: 31}")
    kind = entry.get("kind")
    if kind not in FAULT_KINDS:
        raise InputError(f"{path}.kind", kind, f"must be one of {', '.join(FAULT_KINDS)}")
    reject_unknown_keys(entry, ("generator", "kind", "onset_min") + _FAULT_KEYS[kind], prefix=f"{path}.")
    if "generator" not in entry:
        raise InputError(f"{path}.generator", None, "missing: which generator (number 1.. or name)")
    generator = _generator_index(entry["generator"], names, path)
    onset_s = 60.0 * _number(entry, "onset_min", path, 0.0, 1e5, "min")
    rise = _number(entry, "inlet_rise_C", path, -50.0, 100.0, "K", default=0.0)
    tau_s = 60.0 * _number(entry, "inlet_rise_tau_min", path, 0.0, 600.0, "min", default=0.0)
    share = _number(entry, "inlet_load_share", path, 0.0, 1.0, "(share of the rise following the load)", default=0.0)
    if kind == "inlet_rise":
        return Fault(generator, onset_s, kind, _number(entry, "inlet_rise_C", path, -50.0, 100.0, "K"),
                     inlet_rise_tau_s=tau_s, inlet_load_share=share)
    if kind == "coolant_blockage":
        if ("k_flow" in entry) == ("outlet_diameter_mm" in entry):
            raise InputError(f"{path}.k_flow", entry.get("k_flow"),
                             "give exactly one of k_flow (flow fraction) and outlet_diameter_mm")
        if "k_flow" in entry:
            k_flow = _number(entry, "k_flow", path, 0.05, 1.0, "(flow fraction)")
        else:
            k_flow = outlet_flow_fraction(_number(entry, "outlet_diameter_mm", path, 7.0, OUTLET_DIAMETER_MM, "mm"))
        values = {"k_flow": k_flow}
        if "n_flow" in entry:  # exponent of the internal convection, h ∝ flow^n (effect default 0.8)
            values["n_flow"] = _number(entry, "n_flow", path, 0.0, 1.5, "(convection exponent)")
        return Fault(generator, onset_s, kind, rise, "coolant_flow_reduction", values, tau_s, share)
    try:
        effect = get_effect(entry.get("effect"))
    except InputError as error:
        raise InputError(f"{path}.effect", error.value, error.reason) from None
    values = entry.get("values", {})
    if not isinstance(values, Mapping):
        raise InputError(f"{path}.values", values, "must be a mapping of the effect's parameters")
    bounds = {p.name: p for p in effect.parameters}
    checked = {}
    for name, value in values.items():
        if name not in bounds:
            raise InputError(f"{path}.values.{name}", value, f"unknown; {effect.name} takes {', '.join(bounds)}")
        checked[name] = _number(values, name, f"{path}.values", bounds[name].lower, bounds[name].upper,
                                bounds[name].unit)
    return Fault(generator, onset_s, kind, rise, effect.name, checked, tau_s, share)


class AffineGenerator:
    r"""A linear design model as matrices: :math:`\dot x = Lx + Bu + c`, :math:`y = C_yx + D_yu + e_y`.

    The phase current :math:`I` enters affinely, :math:`u = u_0 + I\,e_I` with
    :math:`e_I = (1, 1, 1, g_{exc}, 0, 0)` (balanced phases; :math:`I_{exc} \approx I_{exc,0} + g_{exc} I`,
    the least-squares line of the AVR exciter law at the load's power factor,
    :func:`genthermal.exciter.exciter_line`). Time stepping is :mod:`genthermal.discretise`'s:
    :meth:`step` is its exact zero-order hold (:func:`~genthermal.discretise.phi_matrices`), and
    ``decay`` (:class:`~genthermal.discretise.ModalDecay`) gives a rest of free length :math:`h` at
    constant input exactly, :math:`x(h) = x_{ss} + e^{hL}(x(0) - x_{ss})`.

    :meth:`with_disturbances` adds the heat flows a filter estimates the model lacks (offset-free
    planning, :func:`genthermal.schedule.state_estimator.planning_generator`).

    **Rest current and the copper-loss floor.** The matrices are those of the design model's
    *affine branch*: its copper loss per phase :math:`\max(aI + b, 0)` (thesis eq. 5.3,
    :class:`~genthermal.losses.LossFloor`) is taken as :math:`aI + b` everywhere. With the default
    line over 27.3-100 % of the rated 7 A (:math:`a` = 8.911 A, :math:`b` = -17.69 A²) the floor
    acts below :math:`-b/a` = 1.985 A, so at the rest current 1.911 A (27.3 %) the planner counts
    :math:`aI + b` = -0.66 A² per phase where the floored model counts 0. Measured at steady
    state in the rest mode (nominal thesis generator, ambient 20 °C): winding 25.0 °C against the
    floored model's 26.0 °C at inlet 20 °C, 54.5 °C against 55.5 °C at inlet 51 °C (iron 0.5 K);
    from 2 A up both agree. The nonlinear model is 4.5-5 K warmer still there (30.5 °C and
    60.5 °C): the line misses :math:`I^2` = 3.65 A² by 4.3 A² at the ends of its range, far more
    than the floor does. The error sits in the rest mode only, tens of kelvin below any limit,
    and is left as it is.

    Parameters
    ----------
    model : ThermalModel
        An affine (linear design) model.
    power_factor : float
        Lagging load power factor, (0, 1].
    rated_current_A : float
        Rated phase current, A.
    """

    def __init__(self, model, power_factor: float = DEFAULT_POWER_FACTOR, rated_current_A: float | None = None):
        generator = model.spec.interface.generator
        if not model.is_affine:
            raise InputError("model", model.name, "the scheduler plans on the linear design model")
        rated_current_A = model.spec.rated_current_A if rated_current_A is None else rated_current_A
        names = list(model.input_names)
        nx, nu = model.n_states, len(names)
        x, u = ca.SX.sym("x", nx), ca.SX.sym("u", nu)
        # the affine branch (every copper-loss floor taken as the identity): see "Rest current and
        # the copper-loss floor" in the class docstring
        xdot = model.functions["rhs_affine_branch"](x, u, model.p0)
        y = model.functions["outputs"](x, u, model.p0)
        matrices = ca.Function("m", [x, u], [ca.jacobian(xdot, x), ca.jacobian(xdot, u),
                                             ca.jacobian(y, x), ca.jacobian(y, u), xdot, y])
        L, B, Cy, Dy, c, ey = (np.asarray(m) for m in matrices(np.zeros(nx), np.zeros(nu)))
        self.model, self.L, self.B, self.c, self.Cy, self.Dy, self.ey = model, L, B, c.ravel(), Cy, Dy, ey.ravel()
        self.e_I = np.zeros(nu)
        self.e_I[[names.index(p) for p in generator.phase_inputs]] = 1.0
        self.exciter_no_load_A, self.e_I[names.index(generator.excitation_input)] = exciter_line(
            power_factor, rated_current_A, law=generator.exciter_law)
        self._generator, self._names = generator, names
        self.decay = ModalDecay.of(L, model.name)
        self._steps: dict = {}

    def input(self, current_A, inlet_C: float, ambient_C: float) -> np.ndarray:
        """Input vectors for phase currents ``current_A`` (A RMS), shape ``(..., n_inputs)``."""
        generator, names = self._generator, self._names
        u0 = np.zeros(len(names))
        u0[names.index(generator.excitation_input)] = self.exciter_no_load_A
        u0[names.index(generator.coolant_input)] = inlet_C
        u0[names.index(generator.ambient_input)] = ambient_C
        return u0 + np.multiply.outer(np.asarray(current_A, dtype=float), self.e_I)

    def with_disturbances(self, heat_W, load_heat_W, rated_current_A: float) -> "AffineGenerator":
        r"""This generator with known extra heat flows: what a filter's disturbance states say the
        model lacks, for offset-free predictions.

        Node :math:`i` receives :math:`q_i + \ell(I)\,m_i` (W) on top of the model's own heat
        flows, :math:`\ell = \overline{I_p^2}/I_{rated}^2` the load squared as the extended Kalman
        filter defines it (:mod:`genthermal.estimation.ekf`). :math:`\ell` is not affine in the
        current; along the design model's own loss line :math:`I^2 \approx aI + b` (thesis eq. 5.3,
        parameters ``I2_slope``, ``I2_intercept``) it is :math:`\ell \approx (aI + b)/I_{rated}^2`,
        the same approximation the copper loss of the design model makes. So

        .. math::
            c \mathrel{+}= M (q + \tfrac{b}{I_{rated}^2} m), \qquad
            B_{:,p} \mathrel{+}= \tfrac{a}{n_p I_{rated}^2} M m \ \text{for each of the } n_p
            \text{ phase inputs},

        :math:`M = \mathrm{diag}(1/C_i)` (J/K). State matrix, outputs, steps and rest decay are
        unchanged (shared with this generator), so every scheduler that predicts with
        :meth:`forcing`, :attr:`B` and :attr:`c` plans with the heat flows.

        Parameters
        ----------
        heat_W : array_like
            (n_states,) constant extra heat flow into each node, W.
        load_heat_W : array_like
            (n_states,) extra heat flow into each node at rated current, W; scales with the load
            squared.
        rated_current_A : float
            :math:`I_{rated}` of the load factor, A RMS (the filter's).

        Returns
        -------
        AffineGenerator
            A new generator; ``disturbance_heat_W`` and ``disturbance_load_heat_W`` hold the
            heat flows it was given.
        """
        nx = self.L.shape[0]
        heat = np.asarray(heat_W, dtype=float)
        load_heat = np.asarray(load_heat_W, dtype=float)
        for name, value in (("heat_W", heat), ("load_heat_W", load_heat)):
            if value.shape != (nx,) or not np.all(np.isfinite(value)):
                raise InputError(name, value.tolist(), f"must be {nx} finite heat flows in W, one per node of "
                                 f"{self.model.name} ({', '.join(self.model.state_names)})")
        if not (np.isfinite(rated_current_A) and rated_current_A > 0):
            raise InputError("rated_current_A", rated_current_A, "must be a current > 0 A")
        if "I2_slope" not in self.model.parameters:
            raise InputError("model", self.model.name, "has no loss line I2_slope/I2_intercept (thesis eq. 5.3): "
                             "build it with genthermal.design.linear_design_model")
        slope_A = self.model.parameters.value("I2_slope")
        intercept_A2 = self.model.parameters.value("I2_intercept")
        inverse_capacity = 1.0 / self.heat_capacities_J_K
        scale = rated_current_A ** 2
        disturbed = copy.copy(self)
        disturbed.c = self.c + inverse_capacity * (heat + intercept_A2 / scale * load_heat)
        B = self.B.copy()
        phases = [self._names.index(p) for p in self._generator.phase_inputs]
        B[:, phases] += (slope_A / (len(phases) * scale) * inverse_capacity * load_heat)[:, None]
        disturbed.B = B
        disturbed.disturbance_heat_W, disturbed.disturbance_load_heat_W = heat, load_heat
        return disturbed

    @functools.cached_property
    def heat_capacities_J_K(self) -> np.ndarray:
        """Heat capacity of every node, J/K, in ``model.state_names`` order."""
        return node_heat_capacities(self.model)

    def forcing(self, u: np.ndarray) -> np.ndarray:
        """:math:`Bu + c`, K/s, for inputs of shape ``(..., n_inputs)``."""
        return u @ self.B.T + self.c

    def step(self, h_s: float) -> tuple[np.ndarray, np.ndarray]:
        r"""Exact ZOH step of length ``h_s`` (s): :math:`x^+ = Ex + \Gamma(Bu + c)` → ``(E, Γ)``,
        by :func:`genthermal.discretise.phi_matrices` (cached per length)."""
        key = round(float(h_s), 9)
        if key not in self._steps:
            self._steps[key] = phi_matrices(self.L, key)[:2]
        return self._steps[key]

    def steady_state(self, u: np.ndarray) -> np.ndarray:
        """Steady state (°C) for constant input ``u``."""
        return -np.linalg.solve(self.L, self.forcing(u))

    def outputs(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        """Sensor temperatures (°C) for states ``(..., n_states)`` and inputs ``(..., n_inputs)``."""
        return x @ self.Cy.T + u @ self.Dy.T + self.ey


@functools.lru_cache(maxsize=4)
def _nominal_models(machine: str):
    """The nominal simulation model and its linear design model (built once per machine; models
    are not changed after they are built). ``machine`` comes from a scenario: a data file."""
    model = load_model(machine, from_data=True)
    return model, linear_design_model(model)


@dataclasses.dataclass
class PowerSystem:
    """N generators flying one mission, with faults, a rest mode and a temperature limit.

    Parameters
    ----------
    mission : Mission
        The load demand of every generator (balanced phases).
    generator_names : tuple of str
        At least two.
    faults : tuple of Fault
    rest_percent : float
        Minimum power mode during a rest, % of rated current.
    limit_C : float, optional
        :math:`\theta_{max}` for the winding and the iron, °C; default the machine's limit of the
        sensor its generator role protects (``spec.interface``).
    current_limit_percent : float
        Highest phase current a generator may carry, % of rated (100: rated 7 A).
    plant_mismatch : dict
        Parameter name → factor applied to the nominal value in the true plant.
    machine : str
        Machine of every generator (a model name for :func:`~genthermal.model_file.load_model`); it
        must have the generator role.
    model : ThermalModel, optional
        The model the manager plans on and filters with (``--model``: a calibrated or identified
        model file); default the machine's nominal simulation model.
    plant : ThermalModel, optional
        The true plant of every generator before its faults (``--plant``); default the planning
        model with ``plant_mismatch`` applied.
    margin_K : float, optional
        The scenario's back-off margin of the load manager below ``limit_C``, K; None (default):
        the manager's own (:attr:`~genthermal.schedule.flight.manager_settings.ManagerSettings.margin_K`).
    filter : str, optional
        The scenario's filter in the loop (``generators.filter``: ``"ekf"`` or ``"kf"``, e.g. the
        thesis's linear filter in the thesis-reproduction scenarios); None (default): the manager's
        own (:attr:`~genthermal.schedule.flight.manager_settings.ManagerSettings.filter`).
    when_infeasible : str, optional
        The scenario's response when even the lowest reachable peak is above ``limit_C``
        (``generators.when_infeasible``, one of :data:`~genthermal.schedule.planning.shed.INFEASIBLE_RESPONSES`:
        ``shed`` or ``best_effort``, e.g. the thesis heuristic's best effort in the
        thesis-reproduction scenarios); None (default): the manager's own
        (:attr:`~genthermal.schedule.flight.manager_settings.ManagerSettings.when_infeasible`).
    """

    mission: Mission
    generator_names: tuple[str, ...] = ("gen1", "gen2")
    faults: tuple[Fault, ...] = ()
    rest_percent: float = DEFAULT_REST_PERCENT
    limit_C: float | None = None
    current_limit_percent: float = 100.0
    plant_mismatch: Mapping[str, float] = dataclasses.field(default_factory=lambda: dict(DEFAULT_PLANT_MISMATCH))
    machine: str = DEFAULT_MACHINE
    model: Any = None
    plant: Any = None
    margin_K: float | None = None
    filter: str | None = None
    when_infeasible: str | None = None

    def __post_init__(self):
        _infeasible_response(self.when_infeasible)
        if len(self.generator_names) < 2 or len(set(self.generator_names)) != len(self.generator_names):
            raise InputError("generators.names", list(self.generator_names), "need at least two distinct names")
        for index, action in enumerate(self.mission.actions):
            if len(set(action.phase_share)) != 1:
                raise InputError(f"actions[{index}].phase_share", list(action.phase_share),
                                 "the load manager handles balanced loads only")
        for index, fault in enumerate(self.faults):
            if fault.effect and any(f.effect == fault.effect and f.generator == fault.generator
                                    for f in self.faults[:index]):
                raise InputError(f"faults[{index}].kind", fault.kind,
                                 f"{self.generator_names[fault.generator]} already has {fault.effect}")
        self._models: dict = {}
        interface = self.planning_model.spec.interface
        try:
            generator = interface.generator
        except InputError as error:
            raise InputError("machine", self.planning_model.name, error.reason) from None
        if self.limit_C is None:
            self.limit_C = interface.limits_C[generator.limited_sensor]

    @classmethod
    def from_mission(cls, mission: Mission) -> "PowerSystem":
        """Read the ``generators`` and ``faults`` keys of a mission (schema in the module docstring)."""
        config = mission.extras.get("generators", {}) or {}
        if not isinstance(config, Mapping):
            raise InputError("generators", config, "must be a mapping such as {count: 2}")
        reject_unknown_keys(config, _GENERATOR_KEYS, prefix="generators.")
        if "names" in config:
            names = config["names"]
            if not isinstance(names, list) or not all(isinstance(n, str) and n for n in names):
                raise InputError("generators.names", names, "must be a list of at least two names")
            names = tuple(names)
        else:
            count = config.get("count", 2)
            if isinstance(count, bool) or not isinstance(count, int) or not 2 <= count <= 8:
                raise InputError("generators.count", count, "must be a whole number 2..8")
            names = tuple(f"gen{i + 1}" for i in range(count))
        machine = config.get("machine", DEFAULT_MACHINE)
        if not isinstance(machine, str) or machine.endswith(":linear"):
            raise InputError("generators.machine", machine, "give a simulation model: a machine name, optionally "
                             f"with a parameter set ({', '.join(PARAMETER_SETS)}), or a machine file")
        try:
            _nominal_models(machine)
        except InputError as error:
            raise InputError("generators.machine", machine, error.reason) from None
        mismatch = config.get("plant_mismatch", DEFAULT_PLANT_MISMATCH)
        if not isinstance(mismatch, Mapping):
            raise InputError("generators.plant_mismatch", mismatch, "must map parameter names to factors")
        factors = {str(k): _number(mismatch, k, "generators.plant_mismatch", 0.2, 5.0, "(factor)") for k in mismatch}
        fault_entries = mission.extras.get("faults", []) or []
        if not isinstance(fault_entries, list):
            raise InputError("faults", fault_entries, "must be a list of faults")
        faults = tuple(parse_fault(e, names, f"faults[{i}]") for i, e in enumerate(fault_entries))
        for i, fault in enumerate(faults):
            if fault.onset_s >= mission.duration_s:
                raise InputError(f"faults[{i}].onset_min", fault.onset_s / 60.0, f"is not before the mission's end "
                                 f"({mission.duration_s / 60.0:g} min): the fault would never happen")
        return cls(mission, names, faults,
                   rest_percent=_number(config, "rest_percent", "generators", 0.0, 100.0, "%", DEFAULT_REST_PERCENT),
                   limit_C=_number(config, "limit_C", "generators", 40.0, 250.0, "degC")
                   if "limit_C" in config else None,
                   current_limit_percent=_number(config, "current_limit_percent", "generators", 50.0, 150.0,
                                                 "%", 100.0),
                   plant_mismatch=factors, machine=machine,
                   margin_K=_number(config, "margin_K", "generators", 0.0, 50.0, "K") if "margin_K" in config else None,
                   filter=_filter_name(config), when_infeasible=_infeasible_response(config.get("when_infeasible")))

    # --- what the flight's parts receive ---------------------------------------------------
    @property
    def manager_say(self) -> dict:
        """The scenario's say over the manager's settings: the keys of :data:`MANAGER_KEYS` it gives
        → their values (:meth:`ManagerSettings.with_scenario
        <genthermal.schedule.flight.manager_settings.ManagerSettings.with_scenario>`)."""
        say = {key: getattr(self, key) for key in MANAGER_KEYS if getattr(self, key) is not None}
        return {**say, "margin_K": float(say["margin_K"])} if "margin_K" in say else say

    def frame(self) -> SystemFrame:
        """This system without its models and faults (:class:`~genthermal.schedule.system_frame.SystemFrame`)."""
        model = self.planning_model
        return SystemFrame(tuple(self.generator_names), self.limit_C, self.rated_current_A, self.rest_current_A,
                           self.current_limit_A, self.mission.T_ambient_C, self.mission.power_factor,
                           tuple(model.input_names), tuple(model.output_names), model.spec.interface.generator,
                           self.inlet_C)

    def true_plants(self) -> TruePlants:
        """Its true plants (:class:`~genthermal.schedule.system_frame.TruePlants`)."""
        return TruePlants(self.n_generators, self.plant_model, self.faults_known_at, self.plant_switches)

    # --- quantities -------------------------------------------------------------------------
    @property
    def n_generators(self) -> int:
        """Number of generators."""
        return len(self.generator_names)

    @property
    def rated_current_A(self) -> float:
        """Rated phase current of the mission, A RMS."""
        return self.mission.rated_current_A

    @property
    def rest_current_A(self) -> float:
        """Phase current in the minimum power mode, A RMS."""
        return self.rest_percent / 100.0 * self.rated_current_A

    @property
    def current_limit_A(self) -> float:
        """Highest phase current a generator may carry, A RMS."""
        return self.current_limit_percent / 100.0 * self.rated_current_A

    def faults_known_at(self, t_s: float) -> tuple[int, ...]:
        """Indices of the faults whose onset is at or before ``t_s``."""
        return tuple(i for i, f in enumerate(self.faults) if f.onset_s <= t_s + 1e-9)

    def inlet_C(self, generator: int, t_s, currents_A=None) -> np.ndarray:
        """Coolant inlet temperature of ``generator`` at times ``t_s`` (°C): mission value plus the
        rises of the faults that have started.

        Parameters
        ----------
        generator : int
            Index of the generator.
        t_s : float or array_like
            Times, s since the mission start.
        currents_A : array_like, optional
            (n_generators, n) phase currents of every generator at ``t_s``, A RMS: a fault's rise
            with an ``inlet_load_share`` follows the generator's current against its undisplaced
            share, the mean over the generators (:func:`genthermal.coolant.inlet_load_factor`).
            None: every generator carries its equal share (the undisplaced load), so every rise is
            the fault's stated one.
        """
        t = np.asarray(t_s, dtype=float)
        inlet = np.full(t.shape, self.mission.T_inlet_C)
        if currents_A is not None:
            currents = np.asarray(currents_A, dtype=float)
            if currents.shape != (self.n_generators,) + t.shape:
                raise InputError("currents_A", list(currents.shape), f"must have the shape "
                                 f"{(self.n_generators,) + t.shape}: the phase current of every generator at "
                                 "each time of t_s")
            own, share = currents[generator], currents.mean(axis=0)
        else:
            own = share = np.ones(t.shape)  # every generator at its share: the factor is exactly 1
        for fault in self.faults:
            if fault.generator == generator:
                inlet = inlet + inlet_rise(t, fault.onset_s, fault.inlet_rise_C, fault.inlet_rise_tau_s,
                                           fault.inlet_load_share, own, share)
        return inlet

    # --- models -----------------------------------------------------------------------------
    def _cached(self, key, build):
        if key not in self._models:
            self._models[key] = build()
        return self._models[key]

    def _with_faults(self, model, generator: int, fault_indices) -> Any:
        for index in fault_indices:
            fault = self.faults[index]
            if fault.generator == generator and fault.effect:
                try:
                    model = model.with_effect(fault.effect, **fault.values)
                except InputError as error:
                    raise InputError(f"faults[{index}].effect", fault.effect, error.reason) from None
        return model

    @property
    def nominal_model(self):
        """Nonlinear simulation model of the machine with its nominal parameters."""
        return _nominal_models(self.machine)[0]

    @property
    def planning_model(self):
        """The model the manager plans on (``model``, default the nominal simulation model)."""
        return self.nominal_model if self.model is None else self.model

    def plant_model(self, generator: int, fault_indices=()):
        """True plant: ``plant`` (default the planning model with ``plant_mismatch``) with the
        given faults applied."""
        def build():
            if self.plant is not None:
                return self._with_faults(self.plant, generator, fault_indices)
            base = self.planning_model
            try:
                values = {name: base.parameters.value(name) * factor for name, factor in self.plant_mismatch.items()}
                plant = base.with_parameters("assumed", "plant mismatch of the closed-loop test", **values)
            except (InputError, KeyError) as error:
                raise InputError("generators.plant_mismatch", dict(self.plant_mismatch), str(error)) from None
            return self._with_faults(plant, generator, fault_indices)
        relevant = tuple(i for i in fault_indices if self.faults[i].generator == generator and self.faults[i].effect)
        return self._cached(("plant", generator, relevant), build)

    def plant_switches(self, generator: int) -> tuple[Any, list]:
        """The plant of ``generator`` before any fault and its ``(onset_s, model)`` switches."""
        onsets = sorted({f.onset_s for f in self.faults if f.generator == generator and f.effect})
        return self.plant_model(generator), [(t, self.plant_model(generator, self.faults_known_at(t))) for t in onsets]

    def design_generator(self, generator: int, fault_indices=()) -> AffineGenerator:
        """Design model (thesis 5.2) of the planning model with the given faults, as matrices."""
        relevant = [self.faults[i] for i in fault_indices
                    if self.faults[i].generator == generator and self.faults[i].effect]
        return self.design_generator_for(tuple((f.effect, tuple(f.values.items())) for f in relevant))

    def design_generator_for(self, effects=(), base=None) -> AffineGenerator:
        """Design model of ``base`` (default the planning model) with ``effects`` (``(name,
        ((parameter, value), ...))`` pairs, applied in order), linearised by
        :func:`~genthermal.schedule.planning.linearise.planning_design_model`. ``base`` may differ from the
        planning model in parameter values only (a recalibration): its values are set on the
        planning model's design model, which shares its compiled functions."""
        from .planning.linearise import planning_design_model

        def build_planning():
            if not effects and self.model is None:
                return AffineGenerator(_nominal_models(self.machine)[1], *self._exciter_operating_point())
            model = self.planning_model
            for name, values in effects:
                model = model.with_effect(name, **dict(values))
            return AffineGenerator(planning_design_model(model), *self._exciter_operating_point())
        planning = self._cached(("affine", tuple(effects)), build_planning)
        if base is None or base is self.planning_model:
            return planning
        changed = {name: value for name, value in base.parameters.values().items()
                   if value != self.planning_model.parameters.value(name)}
        self._models.setdefault(("base", id(base)), base)  # keeps ``base`` alive while its key is used
        return self._cached(("affine", tuple(effects), id(base)), lambda: AffineGenerator(
            planning.model.with_parameters("fitted", "recalibrated in flight", **changed),
            *self._exciter_operating_point()))

    def _exciter_operating_point(self) -> tuple[float, float]:
        """Power factor and rated current (A) the AVR exciter law of every design generator uses."""
        return self.mission.power_factor, self.rated_current_A

    def describe(self) -> str:
        """Several lines: generators, rest mode, limit, faults."""
        lines = [f"{self.n_generators} generators ({', '.join(self.generator_names)}) flying {self.mission.name}; "
                 f"rest mode {self.rest_percent:g} % of rated, limit {self.limit_C:g} °C, current limit "
                 f"{self.current_limit_A:g} A"]
        lines += [f"  fault {fault.describe(self.generator_names)}" for fault in self.faults]
        return "\n".join(lines)
