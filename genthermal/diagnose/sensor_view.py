"""Which sensors of a record a discovery fits: the model's own, and every other one the record has.

A :class:`SensorView` turns a model (with its effects) into one whose outputs are the sensors to
fit: ``phases`` (one winding node per phase, :func:`~genthermal.diagnose.phase_winding.phase_resolved`)
and ``outlet`` (the coolant outlet sensor as one more output); :func:`view_for` chooses the view
from what the record holds. Guide: ``docs/guide/calibration-diagnosis.md``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import InputError
from ..model import ThermalModel
from .phase_winding import phase_resolved, phase_sensor, phases_differ


def with_outlet_sensor(model: ThermalModel) -> ThermalModel:
    """``model`` with its coolant outlet sensor (``interface.outlet_sensor``, the Genco's
    ``T_outlet``) as one more output."""
    interface = model.spec.interface
    if interface.outlet_sensor is None:
        raise InputError("interface.outlet_sensor", None, f"{model.name} has no coolant outlet sensor to read")
    fitted = dataclasses.replace(interface, sensors=(*interface.sensors, interface.outlet_sensor), outlet_sensor=None)
    return model.with_network(model.network, interface=fitted)


@dataclasses.dataclass(frozen=True)
class SensorView:
    """The sensors fitted beyond a model's own (module docstring); a value, usable as a memo key.

    Attributes
    ----------
    phases : bool
        Fit the three winding phase sensors to a phase-resolved winding.
    outlet : bool
        Fit the cooling-air outlet sensor as well.
    """

    phases: bool = False
    outlet: bool = False

    def __call__(self, model: ThermalModel) -> ThermalModel:
        if self.phases:
            model = phase_resolved(model)
        if self.outlet:
            model = with_outlet_sensor(model)
        return model

    @property
    def changes_model(self) -> bool:
        """True when the view differs from the model as it is."""
        return self.phases or self.outlet


def view_for(model: ThermalModel, frame, dt_s: float, phases: str = "auto", outlet: bool | None = None) -> SensorView:
    """The view that uses the sensors of a record.

    Parameters
    ----------
    model : ThermalModel
    frame : pandas.DataFrame
        The record (rig CSV schema columns).
    dt_s : float
        Its sample period, s.
    phases : {"auto", "resolved", "lumped"}
        ``"auto"``: per phase when the record's phase readings differ by more than noise
        (:func:`~genthermal.diagnose.phase_winding.phases_differ`).
    outlet : bool or None
        None: when the record has outlet readings and the model an outlet node.
    """
    if phases not in ("auto", "resolved", "lumped"):
        raise InputError("phases", phases, "must be one of auto, resolved, lumped")
    reader = phase_sensor(model)
    resolve = phases == "resolved" or (phases == "auto" and reader is not None
                                       and phases_differ(frame, dt_s, reader.columns))
    outlet_sensor = model.spec.interface.outlet_sensor
    if outlet is None:
        outlet = outlet_sensor is not None and all(
            c in frame and bool(np.isfinite(frame[c].to_numpy(dtype=float)).any()) for c in outlet_sensor.columns)
    return SensorView(bool(resolve), bool(outlet))
