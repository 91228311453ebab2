r"""Open-search terms that change a machine's own modelled loss instead of adding a heat flow.

Two generic forms for a loss the model already has (the copper loss of the windings), used by the
open library of :mod:`genthermal.diagnose.open_search`:

* :func:`loss_temperature_effect` (``loss_theta_<label>``): each node's loss :math:`P_n` grows by a
  fraction :math:`k` per kelvin above the temperature the model evaluates it at,
  :math:`q_n \mathrel{+}= k\,P_n\,(\theta_n - \theta_{ref})` (1/K);
* :func:`loss_reform_effect` (``loss_I2_<label>``, two parameters): the loss refitted on its modelled
  shape and on I², :math:`q_n \mathrel{+}= k_P P_n + k_{I2}\,s_n \sum_p I_p^2` with :math:`s_n` the
  node's share of the heat capacity of the nodes carrying the loss.
"""

from __future__ import annotations

import sympy

from ..effects import Effect, EffectParameter
from ..errors import InputError
from ..losses import input_symbol, mass_shares
from ..machines.interface import Role
from ..model import ThermalModel
from ..network import HeatSource

#: Modelled losses whose temperature dependence is searched: loss label → plain name of the node
#: group that carries it (every node with a loss of that label). The copper loss: a resistance
#: rises by about 0.4 %/K. The iron loss is left out: its temperature dependence is weak (eddy
#: currents fall slowly as the steel's resistivity rises) and, tried, a temperature-dependent iron
#: loss took the place of an I_exc² heat flow into the iron (tests/test_diagnose_joint.py).
LOSS_GROUPS = {"copper": "windings"}
#: Temperature at which a loss is taken to hold when the model's loss does not name one
#: (``theta_ref``): 20 °C, the reference of tabulated resistivities and temperature coefficients
#: (IEC 60028 gives copper's 0.00393 /K at 20 °C).
DEFAULT_LOSS_REFERENCE_C = 20.0
#: Bound on |k| of a temperature-dependent loss, 1/K: five times copper's coefficient.
LOSS_THETA_BOUND = 0.02
#: Modelled losses that are re-formed on I² (``loss_I2``): the copper loss, whose form (I², a line
#: through I², a resistance at one temperature) is a modelling choice. The iron loss of the shipped
#: machines is a constant shared by heat capacity, which the constant heat flow into the stator
#: iron already is.
REFORMED_LOSSES = ("copper",)
#: Bounds on the fraction k_P of the modelled loss added: the loss gone (-1) to three times the
#: model's (+2).
LOSS_FRACTION_BOUNDS = (-1.0, 2.0)
#: Bound on the |k| of a ΣI² heat flow and its typical value, W/A² (a phase resistance of a few
#: ohm at most; the shipped generator's is 1.6 ohm at 90 °C): the ΣI² heat flows of the open
#: library and the I² half of a re-formed loss.
I2_BOUND, I2_TYPICAL = 5.0, 0.2


def _loss_reference(power) -> sympy.Expr:
    """The temperature a modelled loss holds at: the ``theta_ref`` symbol of its expression (a
    resistance evaluated at a reference temperature), else :data:`DEFAULT_LOSS_REFERENCE_C`."""
    named = [symbol for symbol in power.free_symbols if symbol.name == "theta_ref"]
    return named[0] if named else sympy.Float(DEFAULT_LOSS_REFERENCE_C)


def loss_nodes(model: ThermalModel, label: str) -> tuple[str, ...]:
    """The capacitive nodes of ``model`` that carry a modelled loss labelled ``label``."""
    states = set(model.state_names)
    return tuple(dict.fromkeys(s.node for s in model.network.heat_sources if s.label == label and s.node in states))


def loss_temperature_effect(label: str, name: str | None = None) -> Effect:
    r"""The modelled loss ``label`` (``"copper"``) of each node made temperature-dependent:
    :math:`q_n \mathrel{+}= k\,P_n\,(\theta_n - \theta_{ref})` with :math:`P_n` the node's own
    modelled loss of that label and :math:`\theta_{ref}` the temperature the model evaluates it at
    (:func:`_loss_reference`); :math:`k` in 1/K (copper's resistance: about +0.0039 /K).

    Parameters
    ----------
    label : str
        A key of :data:`LOSS_GROUPS` (``"copper"``).
    name : str, optional
        Effect name (default ``loss_theta_<label>``); its parameter is ``k_<name>``.
    """
    if label not in LOSS_GROUPS:
        raise InputError("loss", label, f"must be one of {', '.join(LOSS_GROUPS)}")
    name = name or f"loss_theta_{label}"

    def transform(network, roles, k):
        sources = [s for s in network.heat_sources if s.label == label]
        if not sources:
            raise InputError("loss", label, "the model has no loss of this kind")
        return network.with_heat_sources(
            [HeatSource(s.node, k * s.power * (network.temperature_symbol(s.node) - _loss_reference(s.power)), name)
             for s in sources])

    def requires(model):
        return None if loss_nodes(model, label) else f"the model has no {label} loss"

    group = LOSS_GROUPS[label]
    return Effect(name, f"the {label} loss of the {group} rises by a fraction k per kelvin",
                  r"q_n \mathrel{+}= k\,P_n\,(\theta_n - \theta_{ref})",
                  (EffectParameter(f"k_{name}", 0.0, "1/K", -LOSS_THETA_BOUND, LOSS_THETA_BOUND, 0.004),), transform,
                  f"residual grows with the {group} temperature times their {label} loss", requires=requires)


def loss_reform_effect(label: str, name: str | None = None) -> Effect:
    r"""The modelled loss ``label`` (``"copper"``) re-formed on two shapes: to each node's loss
    :math:`P_n` add a fraction :math:`k_P` of it and :math:`k_{I2}\sum_p I_p^2` shared as the loss
    is, :math:`q_n \mathrel{+}= k_P P_n + k_{I2}\,s_n \sum_p I_p^2` with :math:`s_n` the node's share
    of the heat capacity of the nodes carrying the loss (the copper loss is shared by copper mass).
    :math:`k_P = -1` replaces the modelled form by :math:`k_{I2} I^2` (W/A², a phase resistance);
    :math:`k_{I2} = 0` scales the loss. Two parameters: a missing loss of this form is usually a
    bit of both, and each alone explains little of it (they cancel where the model is right).

    Parameters
    ----------
    label : str
        One of :data:`REFORMED_LOSSES`.
    name : str, optional
        Effect name (default ``loss_I2_<label>``); its parameters are ``k_<name>_P`` and
        ``k_<name>_I2``.
    """
    if label not in REFORMED_LOSSES:
        raise InputError("loss", label, f"must be one of {', '.join(REFORMED_LOSSES)}")
    name = name or f"loss_I2_{label}"

    def transform(network, roles, k_fraction, k_square):
        sources = [s for s in network.heat_sources if s.label == label]
        if not sources:
            raise InputError("loss", label, "the model has no loss of this kind")
        shares = mass_shares(network, tuple(dict.fromkeys(s.node for s in sources)))
        squares = sum(input_symbol(p) ** 2 for p in roles[Role.LOAD_CURRENTS])
        added = [HeatSource(s.node, k_fraction * s.power, name) for s in sources]
        added += [HeatSource(n, k_square * share * squares, name) for n, share in shares.items()]
        return network.with_heat_sources(added)

    def requires(model):
        return None if loss_nodes(model, label) else f"the model has no {label} loss"

    group = LOSS_GROUPS[label]
    return Effect(name, f"the {label} loss of the {group} re-formed: a fraction k_P of it plus k_I2 ΣI²",
                  r"q_n \mathrel{+}= k_P\,P_n + k_{I2}\,s_n \sum_p I_p^2",
                  (EffectParameter(f"k_{name}_P", 0.0, "1", *LOSS_FRACTION_BOUNDS, -0.2),
                   EffectParameter(f"k_{name}_I2", 0.0, "W/A^2", -I2_BOUND, I2_BOUND, I2_TYPICAL)), transform,
                  f"residual follows the {group}' {label} loss and ΣI² in another mix than the model's",
                  requires=requires, needs=(Role.LOAD_CURRENTS,))
