"""Model against measurement: compare, calibrate, discover the missing physical effect.

* :func:`~genthermal.diagnose.compare.compare` — simulate on the measured inputs; metrics and where
  the model fails;
* :class:`~genthermal.diagnose.error_model.ErrorModel` — the calibrated model's error on a healthy
  baseline (AR(1) per sensor, the discrepancy floor) and :class:`~genthermal.diagnose.error_model.WhitenedBIC`,
  the evidence on effective samples that scores every hypothesis of a diagnosis with a baseline;
* :func:`~genthermal.diagnose.calibrate.calibrate` — least squares (IPOPT, exact derivatives) over
  named parameters with confidence intervals and identifiability warnings;
* :class:`~genthermal.diagnose.discovery.Discovery` — candidates (a :class:`Catalogue`), a
  criterion (:class:`BIC`) and a fitter (:class:`OnsetFitter`) behind ``fit(model, data)``: every
  candidate the model lacks and pairs of them jointly, ranked, verdict, "something is still
  missing", ``iterate``; :func:`~genthermal.diagnose.discover.diagnose` is one call of it;
* :func:`~genthermal.diagnose.open_search.open_search` — the same search over a generic library of
  heat flows and conductance changes, for physics no catalogue names;
* :func:`~genthermal.diagnose.experiment.separating_experiment` — a short rig test that tells two
  look-alike explanations apart;
* :func:`~genthermal.diagnose.phase_winding.phase_resolved` — one winding node per phase, fitted
  to the phase sensors when they differ (:class:`~genthermal.diagnose.sensor_view.SensorView`);
* :func:`~genthermal.diagnose.hidden.make_hidden_effect_case` — test data with a known hidden effect;
* :func:`~genthermal.diagnose.report.run_discovery_demo` — compare → diagnose → add → error falls.
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
