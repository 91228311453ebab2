"""Model against measurement: compare, calibrate, discover the missing physical effect.

* :func:`~genthermal.diagnose.compare.compare` — simulate on the measured inputs; metrics and where
  the model fails;
* :func:`~genthermal.diagnose.calibrate.calibrate` — least squares (IPOPT, exact derivatives) over
  named parameters with confidence intervals and identifiability warnings;
* :func:`~genthermal.diagnose.discover.diagnose` — fit every catalogue effect the model lacks,
  rank by ΔBIC, verdict, ``iterate``;
* :func:`~genthermal.diagnose.hidden.make_hidden_effect_case` — test data with a known hidden effect;
* :func:`~genthermal.diagnose.report.run_discovery_demo` — compare → diagnose → add → error falls.
"""

from .calibrate import CalibrationResult, calibrate
from .compare import Comparison, compare
from .discover import Diagnosis, diagnose
from .hidden import HiddenEffectCase, Injection, make_hidden_effect_case
from .report import run_discovery_demo, write_compare_report, write_diagnosis_report

__all__ = ["CalibrationResult", "Comparison", "Diagnosis", "HiddenEffectCase", "Injection", "calibrate", "compare",
           "diagnose", "make_hidden_effect_case", "run_discovery_demo", "write_compare_report",
           "write_diagnosis_report"]
