"""What a machine tells its consumers: inputs, sensors, ratings, thermal limits, roles and input
laws. Main objects: :class:`MachineInterface`, :class:`Machine`, :class:`Sensor`, :class:`Role`.
"""

from __future__ import annotations

import dataclasses
import enum
from typing import Callable

from ..errors import InputError


class InputKind(enum.Enum):
    """Physical kind of a model input (decides checks on measured data and defaults)."""

    CURRENT = "current"          # A (RMS per phase, or a d/q component)
    TEMPERATURE = "temperature"  # °C
    SPEED = "speed"              # rpm


class Role(enum.Enum):
    """Parts of a machine that effects, schedulers and discovery look for.

    The value a machine gives each role is, by role:

    * node roles (``SLOT_WINDING``: a node; ``END_WINDINGS``, ``IRON``, ``ROTOR``, ``FRAME``,
      ``BEARING``: tuples of nodes),
    * link roles (``WINDING_INSULATION``, ``FRAME_TO_AMBIENT``, ``AIR_GAP``, ``END_SPACE_CONVECTION``:
      tuples of (node, node) links; ``END_SPACE_CONVECTION`` the convection paths of the end-space air),
    * ``INTERNAL_CONVECTION``: names of convection-coefficient parameters swept by the coolant flow,
    * ``COOLANT_FLOW``: True when the coolant is modelled as advected air streams,
    * input roles (``LOAD_CURRENTS``: the current inputs whose squares sum is proportional to the
      copper loss; ``PHASE_CURRENTS``: the three per-phase RMS currents; ``EXCITATION_CURRENT``:
      the exciter field current input),
    * ``SPEED``: a :class:`SpeedRole` (the rotor speed input and the operating point the
      speed-dependent effects refer to),
    * ``GENERATOR``: a :class:`GeneratorRole` (the power system and load scheduler need it).
    """

    SLOT_WINDING = "slot_winding"
    END_WINDINGS = "end_windings"
    IRON = "iron"
    ROTOR = "rotor"
    FRAME = "frame"
    WINDING_INSULATION = "winding_insulation"
    FRAME_TO_AMBIENT = "frame_to_ambient"
    INTERNAL_CONVECTION = "internal_convection"
    COOLANT_FLOW = "coolant_flow"
    LOAD_CURRENTS = "load_currents"
    PHASE_CURRENTS = "phase_currents"
    EXCITATION_CURRENT = "excitation_current"
    GENERATOR = "generator"
    SPEED = "speed"
    AIR_GAP = "air_gap"
    END_SPACE_CONVECTION = "end_space_convection"
    BEARING = "bearing"


@dataclasses.dataclass(frozen=True)
class ModelInput:
    """One input of the model (a column of the input frame and of the CSV schema).

    Attributes
    ----------
    name : str
        Column and symbol name (``"I_u"``, ``"T_coolant"``).
    unit : str
        ``"A"``, ``"degC"``, ``"rpm"`` ...
    kind : InputKind
    description : str
    default : float
        Value used when a caller does not give the input (0 A, 0 rpm, 20 °C).
    signed : bool
        True for a current that may be negative (a d/q component); RMS currents are >= 0.
    """

    name: str
    unit: str
    kind: InputKind
    description: str
    default: float = 0.0
    signed: bool = False


@dataclasses.dataclass(frozen=True)
class Sensor:
    """A measured temperature: the model output it is, where it sits, its CSV columns and noise.

    Attributes
    ----------
    output : str
        Model output name (``"T_winding"``).
    node : str
        Network node whose temperature the sensor reads.
    columns : tuple of str
        CSV columns measuring it; the output is their mean over the columns present at a sample
        (three phase PT100s give one winding temperature).
    noise_variance_K2 : float
        Measurement noise variance, K², used by ``synth`` and as the filter's default R.
    limit_C : float or None
        Thermal limit θmax of this sensor, °C (None: no limit enforced on it).
    description : str
    """

    output: str
    node: str
    columns: tuple
    noise_variance_K2: float
    limit_C: float | None = None
    description: str = ""


@dataclasses.dataclass(frozen=True)
class SpeedRole:
    """The rotor speed of a machine whose losses and convection depend on it.

    Attributes
    ----------
    input : str
        The speed input (kind :attr:`InputKind.SPEED`), rpm.
    reference_rpm : float
        Speed the speed-dependent effects' sizes refer to (their loss or conductance rise at this
        speed), rpm: the machine's top speed in service.
    reference_current_A : float
        Current amplitude of the load currents the current-dependent parts refer to, A.
    """

    input: str
    reference_rpm: float
    reference_current_A: float

    def __post_init__(self):
        for field in ("reference_rpm", "reference_current_A"):
            value = getattr(self, field)
            if not (isinstance(value, (int, float)) and value > 0):
                raise InputError(f"SpeedRole.{field}", value, "must be a number > 0")


@dataclasses.dataclass(frozen=True)
class GeneratorRole:
    """What the generator power system and load scheduler need from a machine.

    Attributes
    ----------
    phase_inputs : tuple of str
        The three per-phase RMS current inputs, A.
    excitation_input : str
        Exciter field current input, A, set by the AVR law ``exciter_law``.
    coolant_input, ambient_input : str
        Cooling-air inlet and ambient temperature inputs, °C.
    exciter_law : callable
        ``exciter_law(mean_phase_current_A, power_factor, rated_current_A) -> I_exc`` (A): the one
        place the AVR law is called from (mission inputs, planners, power system).
    limited_sensor : str
        Output whose limit the load management protects (the hot spot, ``T_winding``).
    """

    phase_inputs: tuple
    excitation_input: str
    coolant_input: str
    ambient_input: str
    exciter_law: Callable
    limited_sensor: str


#: The coolant media a machine declares (:attr:`MachineInterface.coolant_medium`).
COOLANT_MEDIA = ("room_air", "water")


@dataclasses.dataclass(frozen=True)
class MachineInterface:
    """Everything consumers read from a machine besides its network and parameters.

    Attributes
    ----------
    inputs : tuple of ModelInput
        Model inputs in the order of the input vector ``u``.
    sensors : tuple of Sensor
        Measured temperatures in model-output order.
    boundary_inputs : dict
        Boundary node → the temperature input that sets it.
    rated_current_A : float
        Rated RMS current of the load-current inputs, A (load percentages refer to it).
    ambient_input : str
        Temperature input a machine at rest settles towards (initial states, steady-state guess).
    coolant_input : str
        Temperature input of the coolant the losses leave through (the reference of a soaked
        machine when an initial state is matched to measurements).
    roles : dict
        :class:`Role` → the machine's value for it (see :class:`Role`).
    rated_inputs : dict
        Input name → value at the machine's rating point (inputs not named take their default):
        the load at which accuracy checks step the model.
    linearisation_inputs : dict
        Input name → value at which the discrete step takes its linear part (inputs not named: 0;
        :mod:`genthermal.discretise`). A machine whose conductances rise steeply with an input
        (convection with speed) names a mid-range value: the step treats the change from there
        explicitly, which stays stable where a change from zero would not.
    outlet_sensor : Sensor or None
        The coolant leaving the machine (its node reported as an extra simulation column, its CSV
        column read when present); not a model output. None: not reported.
    coolant_medium : str
        What the coolant input reads (:data:`COOLANT_MEDIA`): ``"room_air"`` when the cooling air
        is drawn from the room the ambient sensor is in (then the two read the same air, and the
        diagnosis checks one against the other), ``"water"`` for a liquid circuit with its own
        temperature (water or water-glycol; each reading is judged on its own evidence).
    """

    inputs: tuple
    sensors: tuple
    boundary_inputs: dict
    rated_current_A: float
    ambient_input: str
    coolant_input: str
    roles: dict = dataclasses.field(default_factory=dict)
    rated_inputs: dict = dataclasses.field(default_factory=dict)
    linearisation_inputs: dict = dataclasses.field(default_factory=dict)
    outlet_sensor: Sensor | None = None
    coolant_medium: str = "room_air"

    def __post_init__(self):
        names = [i.name for i in self.inputs]
        if len(set(names)) != len(names):
            raise InputError("interface.inputs", names, "input names must be unique")
        for field in ("ambient_input", "coolant_input"):
            if getattr(self, field) not in names:
                raise InputError(f"interface.{field}", getattr(self, field), f"not an input ({', '.join(names)})")
        if self.coolant_medium not in COOLANT_MEDIA:
            raise InputError("interface.coolant_medium", self.coolant_medium,
                             f"must be one of {', '.join(COOLANT_MEDIA)}")
        if not (isinstance(self.rated_current_A, (int, float)) and self.rated_current_A > 0):
            raise InputError("interface.rated_current_A", self.rated_current_A, "must be a current > 0 A")
        for role in self.roles:
            if not isinstance(role, Role):
                raise InputError("interface.roles", role, f"roles are genthermal.machines.Role members, "
                                 f"e.g. Role.IRON; known: {', '.join(r.name for r in Role)}")
        for role in (Role.LOAD_CURRENTS, Role.PHASE_CURRENTS, Role.EXCITATION_CURRENT):
            for name in self._as_tuple(self.roles.get(role, ())):
                if name not in names:
                    raise InputError(f"interface.roles[{role.name}]", name, "not an input of the machine")
        speed = self.roles.get(Role.SPEED)
        if speed is not None:
            kinds = {i.name: i.kind for i in self.inputs}
            if not isinstance(speed, SpeedRole):
                raise InputError("interface.roles[SPEED]", speed, "must be a genthermal.machines.SpeedRole")
            if kinds.get(speed.input) is not InputKind.SPEED:
                raise InputError("interface.roles[SPEED].input", speed.input, "not a speed input of the machine")
        for field in ("rated_inputs", "linearisation_inputs"):
            unknown = sorted(set(getattr(self, field)) - set(names))
            if unknown:
                raise InputError(f"interface.{field}", unknown[0], f"not an input ({', '.join(names)})")
        for sensor in self.sensors:
            if not (sensor.noise_variance_K2 > 0):
                raise InputError(f"sensor {sensor.output}.noise_variance_K2", sensor.noise_variance_K2, "must be > 0 K²")

    @staticmethod
    def _as_tuple(value) -> tuple:
        return (value,) if isinstance(value, str) else tuple(value)

    # --- names -----------------------------------------------------------------------------
    @property
    def input_names(self) -> tuple:
        """Input names in input-vector order."""
        return tuple(i.name for i in self.inputs)

    @property
    def output_names(self) -> tuple:
        """Sensor output names in model-output order."""
        return tuple(s.output for s in self.sensors)

    @property
    def sensor_nodes(self) -> dict:
        """Output name → node."""
        return {s.output: s.node for s in self.sensors}

    def inputs_of_kind(self, kind: InputKind) -> tuple:
        """Names of the inputs of ``kind``."""
        return tuple(i.name for i in self.inputs if i.kind is kind)

    @property
    def rms_currents(self) -> tuple:
        """Current inputs that are RMS values (>= 0; averaged as RMS, their losses go with the square)."""
        return tuple(i.name for i in self.inputs if i.kind is InputKind.CURRENT and not i.signed)

    def sensor(self, output: str) -> Sensor:
        """The sensor of model output ``output``."""
        for sensor in self.sensors:
            if sensor.output == output:
                return sensor
        raise InputError("sensor", output, f"not a sensor of the machine ({', '.join(self.output_names)})")

    @property
    def sensor_columns(self) -> tuple:
        """Every CSV sensor column, in sensor order."""
        return tuple(c for s in self.sensors for c in s.columns)

    @property
    def noise_variances_K2(self) -> tuple:
        """Noise variance of each sensor, K², in output order."""
        return tuple(s.noise_variance_K2 for s in self.sensors)

    @property
    def limits_C(self) -> dict:
        """Output name → thermal limit θmax (°C) for the sensors that have one."""
        return {s.output: s.limit_C for s in self.sensors if s.limit_C is not None}

    @property
    def outlet_node(self) -> str | None:
        """Node of the outlet sensor, or None."""
        return self.outlet_sensor.node if self.outlet_sensor else None

    @property
    def optional_columns(self) -> tuple:
        """CSV sensor columns read when present (the outlet)."""
        return self.outlet_sensor.columns if self.outlet_sensor else ()

    # --- roles -----------------------------------------------------------------------------
    def has_role(self, role: Role) -> bool:
        """True when the machine gives a value for ``role``."""
        return role in self.roles

    def role(self, role: Role, needed_by: str = ""):
        """The machine's value for ``role``, or InputError naming the role and who needs it."""
        if role not in self.roles:
            who = f"{needed_by} needs it; " if needed_by else ""
            raise InputError("machine role", role.value, f"the machine has no {role.value} role ({who}roles: "
                             f"{', '.join(r.value for r in self.roles) or 'none'})")
        return self.roles[role]

    @property
    def generator(self) -> GeneratorRole:
        """The :class:`GeneratorRole`; InputError "machine has no generator role" otherwise."""
        return self.role(Role.GENERATOR, "the generator power system and load scheduler")

    @property
    def load_currents(self) -> tuple:
        """Inputs whose squares sum is proportional to the copper loss."""
        return self._as_tuple(self.role(Role.LOAD_CURRENTS, "the copper loss"))

    def default_input_values(self) -> dict:
        """Input name → default value."""
        return {i.name: float(i.default) for i in self.inputs}


@dataclasses.dataclass(frozen=True)
class Machine:
    """A machine definition: what a plug-in provides.

    Attributes
    ----------
    name : str
        Machine name (``"genco_rf201a"``).
    description : str
        One line.
    interface : MachineInterface
    default_parameters : callable
        ``default_parameters() -> ParameterSet`` with the provenance of every value.
    build_network : callable
        ``build_network(parameters) -> Network`` from the symbols of a parameter set.
    column_map : dict or None
        How the machine's own logger writes its CSV (:class:`genthermal.column_map.ColumnMap`
        form), used when a command reads a file without ``--columns``; None: the CSV schema.
    """

    name: str
    description: str
    interface: MachineInterface
    default_parameters: Callable
    build_network: Callable
    column_map: dict | None = None
