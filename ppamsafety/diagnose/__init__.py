"""The discrepancy workflow: where measurement and model disagree, which effect
is missing, its fitted parameters, and the gap shrinking.

* :mod:`.diagnosis` -- the front door :func:`diagnose` (an arm record, a muscle record
  on the test bench or a cylinder campaign) and :mod:`.synthesize`, the hidden-effect
  data generator;
* :mod:`.arm` -- arm records: block residuals, static sawtooth rest points (§3.5.1.6),
  the candidate library, forward selection with its bootstrap, the pipeline;
* :mod:`.bench` -- actuator records on the test bench (muscles) and cylinder campaigns;
* :mod:`.core` -- what both share: noise levels, selection criteria and the naming
  rule, linear selection, parameters and the :class:`Diagnosis` result (its named
  :class:`Effect` with each parameter an :class:`Estimate`, its :class:`ConfoundedGroup`);
* :mod:`.scenarios` -- the randomized batteries that measure what "high" means.

``__all__`` is the public face: a report section or a user's script reaches the diagnosis
through it, never through the subpackages (the engine).

Documentation: ``docs/diagnose.md``.
"""

import inspect
import sys
import types

from .core.result import ConfoundedGroup, Diagnosis, Effect, Estimate
from .diagnosis import diagnose
from .synthesize import check_effect, effect_unit, synthesize
from .arm.synthesize import noise_variances
from .arm.kind import assumed_arm_note, other_arm
from .arm.pipeline import REPLAY_RHO, REPLAY_RHO_STATIC
from .arm.static import static_record
from .bench.calibration import (CAMPAIGN_MEASURE, campaign_calibration_table,
                                run_campaign_calibration)
from .bench.result import BenchDiagnosis
from .bench.scenarios import single_effect_outcomes
from .core.battery import HIGH_PRECISION
from .core.omitted import HINT_P
from .core.power import POWER
from .core.regions import largest_regions
from .scenarios import (ARM_BATTERY, BENCH_RESULTS_FILE, DECLARED_MEASURE_SEEDS,
                        DECLARED_RESULTS_FILE, P_DECLARED_CHANGE, by_effect, calibration_table,
                        declared_names, detection_curve, failures, interval_widening,
                        load_results, run_battery, scores)

__all__ = [
    # the front door and its results
    "diagnose", "synthesize", "Diagnosis", "BenchDiagnosis", "Effect", "Estimate",
    "ConfoundedGroup",
    # the thresholds a reader of a diagnosis meets
    "REPLAY_RHO", "REPLAY_RHO_STATIC", "HINT_P", "POWER", "HIGH_PRECISION",
    # the effects synthesize makes: their units and their check; the noise it adds
    "effect_unit", "check_effect", "noise_variances",
    # the arm a record names against the arm given (or assumed); a static sawtooth's rest points
    "other_arm", "assumed_arm_note", "static_record",
    # the regions where a diagnosis' remaining residual is largest
    "largest_regions",
    # the randomized batteries, their shipped rows and their scores
    "ARM_BATTERY", "run_battery", "load_results", "scores", "calibration_table",
    "detection_curve", "by_effect", "failures", "interval_widening", "declared_names",
    "single_effect_outcomes", "BENCH_RESULTS_FILE", "DECLARED_RESULTS_FILE",
    "DECLARED_MEASURE_SEEDS", "P_DECLARED_CHANGE",
    # the calibration of a cylinder campaign's "high"
    "CAMPAIGN_MEASURE", "run_campaign_calibration", "campaign_calibration_table",
]


class _FrontDoorPackage(types.ModuleType):
    """This package, callable as its front door: ``ppamsafety.diagnose(data, ...)`` is
    :func:`diagnose` whether the name resolves to the package (once it is imported, the import
    system binds it in ``ppamsafety``) or to the function."""

    def __call__(self, *args, **kwargs):
        return diagnose(*args, **kwargs)


sys.modules[__name__].__class__ = _FrontDoorPackage
__signature__ = inspect.signature(diagnose)
