"""Model files: a built-in machine, its variant, changed parameters and added effects, as YAML.

:func:`load_model` reads a model file or a machine name (``genco_rf201a``, ``genco_rf201a:linear``,
``genco_rf201a:chapter7``, a plug-in or a trusted ``.py`` machine file); :func:`save_model` writes
the parameters that differ from the machine's, the added effects with their onsets and the
disturbance prior a calibration left. Loading a model file never runs code. The format:
``docs/guide/model.md``.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import yaml

from .design import linear_design_model
from .effects import CATALOGUE, apply_effect
from .errors import InputError
from .yaml_input import load_user_yaml, read_user_text
from .machines import MACHINES, build_model, known_machines
from .machines.registry import is_machine_reference
from .model import ThermalModel
from .outputs import write_text
from .parameters import PROVENANCES
from .resources import shipped_data_file, shipped_data_names

VARIANTS = ("nonlinear", "linear")
#: Shipped parameter sets: ``machine:name`` → model file inside the package.
PARAMETER_SETS = ("chapter7",)
_TOP_KEYS = ("machine", "variant", "parameters", "effects", "disturbance_prior")
#: Parameters the linear design model adds; saved through the variant, not as values.
_DESIGN_PARAMETERS = ("I2_slope", "I2_intercept", "theta_ref")
_PARAMETER_KEYS = ("value", "provenance", "source")
_EFFECT_KEYS = ("name", "parameters", "provenance", "source", "onset_s")


def load_model(spec_or_path: str | os.PathLike, from_data: bool = False) -> ThermalModel:
    """Build a model from a built-in name (``genco_rf201a[:linear|:chapter7]``) or a YAML model file.

    Parameters
    ----------
    spec_or_path : str or path-like
        A machine name with an optional variant (``genco_rf201a:linear``), a ``.py`` machine file,
        or a model file written by :func:`save_model` (``calibrate --out``, ``diagnose --out``).
    from_data : bool
        ``spec_or_path`` was read from a data file (a scenario): a ``.py`` machine file is refused
        unless trusted, as in a model file.

    Returns
    -------
    ThermalModel

    Raises
    ------
    InputError
        Unknown machine or variant, unreadable or too large a file, an untrusted machine file, or a
        bad entry (the field is named, e.g. ``parameters.h_end_air.value`` or ``effects[0].parameters``).
    """
    text = str(spec_or_path)
    head, sep, tail = text.rpartition(":")
    name, variant = (head, tail) if sep and tail in (*VARIANTS, *PARAMETER_SETS) else (text, "")
    if name in MACHINES and variant in PARAMETER_SETS and not Path(text).is_file():
        from .machines.parameter_sets import parameter_file

        return model_from_document(yaml.safe_load(parameter_file(variant).read_text()), text)
    if variant not in PARAMETER_SETS and not (Path(text).is_file() and not name.endswith(".py")) \
            and is_machine_reference(name):
        return _build(name, variant or "nonlinear", from_file=False, from_data=from_data)
    path = shipped_data_file(text, ".yaml") or Path(text)
    if not path.is_file():
        known = ", ".join(f"{m}, {m}:linear" for m in known_machines())
        sets = ", ".join(f"{m}:{v}" for m in MACHINES for v in PARAMETER_SETS)
        plants = ", ".join(shipped_data_names(".yaml"))
        raise InputError("model", text, f"neither a machine ({known}, {sets}, or a .py machine file), a shipped "
                         f"stand-in plant ({plants}) nor a model file")
    try:
        document = load_user_yaml(read_user_text(path, "model file"), str(path))
    except UnicodeDecodeError:
        raise InputError("model file", str(path), "not a text file (UTF-8 YAML expected)") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        raise InputError("model file", str(path), f"not valid YAML{where}: "
                         f"{getattr(exc, 'problem', None) or exc}; check indentation, colons and brackets") from None
    return model_from_document(document, str(path))


def _build(machine: str, variant: str, from_file: bool, from_data: bool = True) -> ThermalModel:
    if variant not in VARIANTS:
        raise InputError("variant" if from_file else "model variant", variant,
                         f"must be one of {', '.join(VARIANTS)}")
    try:
        model = build_model(machine, from_data=from_data)
    except InputError as error:
        field = "machine" if from_file else "model"
        raise InputError(field if error.field == "machine" else f"{field} {error.field}", error.value,
                         error.reason) from None
    return linear_design_model(model) if variant == "linear" else model


def model_from_document(document, source: str = "<document>") -> ThermalModel:
    """Build a model from the parsed YAML of a model file (see the module docstring)."""
    if not isinstance(document, dict):
        raise InputError(source, type(document).__name__, "a model file must be a mapping with a machine")
    unknown = sorted(set(document) - set(_TOP_KEYS))
    if unknown:
        raise InputError(unknown[0], document[unknown[0]], f"unknown key; a model file has {', '.join(_TOP_KEYS)}")
    if "machine" not in document:
        raise InputError("machine", None, f"missing in {source}; e.g. machine: genco_rf201a")
    model = _build(_text(document["machine"], "machine"), _text(document.get("variant", "nonlinear"), "variant"),
                   from_file=True)
    parameters = document.get("parameters") or {}
    if not isinstance(parameters, dict):
        raise InputError("parameters", parameters, "must map parameter names to {value, provenance, source}")
    for name, entry in parameters.items():
        entry = entry if isinstance(entry, dict) else {"value": entry}
        _reject_unknown(entry, f"parameters.{name}", _PARAMETER_KEYS)
        if name not in model.parameters:
            raise InputError(f"parameters.{name}", name, f"not a parameter of {model.name}")
        provenance = str(entry.get("provenance", "assumed"))
        if provenance not in PROVENANCES:
            raise InputError(f"parameters.{name}.provenance", provenance, f"must be one of {', '.join(PROVENANCES)}")
        value = _number(entry.get("value"), f"parameters.{name}.value")
        model = model.with_parameters(provenance=provenance, source=str(entry.get("source", "")) or
                                      f"model file {source}", **{name: value})
    effects = document.get("effects") or []
    if not isinstance(effects, list):
        raise InputError("effects", effects, "must be a list of {name, parameters}")
    onsets = {}
    for i, entry in enumerate(effects):
        if not isinstance(entry, dict) or "name" not in entry:
            raise InputError(f"effects[{i}]", entry, "must be a mapping with a name and parameters")
        _reject_unknown(entry, f"effects[{i}]", _EFFECT_KEYS)
        if entry["name"] not in CATALOGUE:
            raise InputError(f"effects[{i}].name", entry["name"], f"unknown effect; known: {', '.join(CATALOGUE)}")
        values = entry.get("parameters") or {}
        if not isinstance(values, dict):
            raise InputError(f"effects[{i}].parameters", values, "must map parameter names to numbers")
        values = {k: _number(v, f"effects[{i}].parameters.{k}") for k, v in values.items()}
        provenance = str(entry.get("provenance", "fitted"))
        if provenance not in PROVENANCES:
            raise InputError(f"effects[{i}].provenance", provenance, f"must be one of {', '.join(PROVENANCES)}")
        try:
            model = apply_effect(model, entry["name"], provenance=provenance,
                                 source=str(entry.get("source", "")) or f"model file {source}", **values)
        except InputError as exc:
            raise InputError(f"effects[{i}] ({entry['name']}) {exc.field}", exc.value, exc.reason) from None
        if entry.get("onset_s") is not None:
            onsets[entry["name"]] = entry["onset_s"]
            try:
                model.with_onsets({entry["name"]: entry["onset_s"]})
            except InputError as exc:
                raise InputError(f"effects[{i}].onset_s", exc.value, exc.reason) from None
    model = model.with_onsets(onsets) if onsets else model
    if document.get("disturbance_prior") is not None:
        from .estimation.disturbance_prior import DisturbancePrior

        model = model.with_disturbance_prior(DisturbancePrior.from_document(document["disturbance_prior"]))
    return model


def _number(value, field: str) -> float:
    """A finite YAML number; text (even ``"1.5"``), booleans and ``.inf``/``.nan`` are refused."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(field, value, "must be a number written as a number (e.g. 17.2, not '17.2' or true)")
    if not math.isfinite(value):
        raise InputError(field, value, "must be a finite number")
    return float(value)


def _text(value, field: str) -> str:
    if not isinstance(value, str):
        raise InputError(field, value, "must be a name written as text")
    return value


def _reject_unknown(entry: dict, field: str, allowed: tuple[str, ...]) -> None:
    unknown = sorted(str(key) for key in set(entry) - set(allowed))
    if unknown:
        raise InputError(f"{field}.{unknown[0]}", entry[unknown[0]] if unknown[0] in entry else None,
                         f"unknown key; allowed: {', '.join(allowed)}")


def model_document(model: ThermalModel, onsets: dict | None = None) -> dict:
    """The YAML document of ``model``: values that differ from the machine's defaults, effects.

    Parameters
    ----------
    model : ThermalModel
    onsets : dict, optional
        Effect name → onset in s after a record's first sample; default the onsets the model
        carries (``spec.onsets``).
    """
    onsets = dict(model.spec.onsets) if onsets is None else onsets
    machine = model.spec.machine_source or model.spec.name
    defaults = build_model(machine).parameters
    effect_parameters = {p.name: effect for effect in model.spec.effects for p in CATALOGUE[effect].all_parameters}
    parameters = {}
    for name in model.parameter_names:
        if name in effect_parameters or name in _DESIGN_PARAMETERS:
            continue
        parameter = model.parameters[name]
        if name not in defaults or parameter.value != defaults.value(name) or \
                parameter.provenance != defaults[name].provenance:
            parameters[name] = {"value": parameter.value, "provenance": parameter.provenance,
                                "source": parameter.source}
    effects = []
    for effect in model.spec.effects:
        names = [p.name for p in CATALOGUE[effect].all_parameters]
        first = model.parameters[names[0]] if names else None
        entry = {"name": effect, "parameters": {n: model.parameters.value(n) for n in names}}
        if first is not None:
            entry.update(provenance=first.provenance, source=first.source)
        if onsets and effect in onsets:
            entry["onset_s"] = float(onsets[effect])
        effects.append(entry)
    document = {"machine": machine, "variant": model.spec.variant, "parameters": parameters, "effects": effects}
    if model.disturbance_prior is not None:
        document["disturbance_prior"] = model.disturbance_prior.to_document()
    return document


def save_model(model: ThermalModel, path: str | os.PathLike, onsets: dict | None = None) -> Path:
    """Write ``model`` as a YAML model file (see :func:`model_document`); return the path.

    Parameters
    ----------
    model : ThermalModel
        The model to keep: its machine, variant, parameters with provenance, effects and
        disturbance prior.
    path : path-like
        The YAML file to write (whole or not at all).
    onsets : dict, optional
        Effect name -> onset, s, for effects that switch on during a record.

    Returns
    -------
    pathlib.Path
    """
    return write_text(path, yaml.safe_dump(model_document(model, onsets), sort_keys=False))
