"""Model against measurement: compare, calibrate, discover the missing physical effect.

:func:`compare` (metrics and where the model fails), :func:`calibrate` (least squares with
confidence intervals), :class:`Discovery` and :func:`diagnose` (the effect a model lacks, ranked
by an information criterion), :func:`open_search` (heat flows no catalogue names),
:func:`separating_experiment` (a rig test that tells two look-alikes apart),
:func:`phase_resolved` and :class:`SensorView` (the sensors a record adds),
:func:`make_hidden_effect_case` (test data with a known answer). Guide:
``docs/guide/calibration-diagnosis.md``.
"""

from .calibrate import CalibrationResult, calibrate
from .catalogue import Catalogue
from .compare import Comparison, compare
from .criterion import AIC, BIC
from .error_model import ErrorModel, WhitenedBIC
from .discover import Diagnosis, diagnose
from .discovery import Discovery
from .experiment import SeparatingExperiment, separating_experiment
from .fitter import OnsetFitter
from .hidden import HiddenEffectCase, Injection, make_hidden_effect_case
from .open_search import describe_term, effect_code, heat_flow_library, open_search
from .phase_winding import phase_resolved
from .sensor_view import SensorView
from .report import run_discovery_demo, write_compare_report, write_diagnosis_report

__all__ = ["AIC", "BIC", "CalibrationResult", "Catalogue", "Comparison", "Diagnosis", "Discovery", "ErrorModel",
           "HiddenEffectCase", "WhitenedBIC",
           "Injection", "OnsetFitter", "SensorView", "SeparatingExperiment", "calibrate", "compare", "describe_term", "diagnose", "effect_code", "heat_flow_library",
           "make_hidden_effect_case", "open_search", "phase_resolved", "run_discovery_demo", "separating_experiment",
           "write_compare_report", "write_diagnosis_report"]
