"""The discrepancy workflow: where measurement and model disagree, which effect
is missing, its fitted parameters, and the gap shrinking.

* :mod:`.diagnosis` -- the front door :func:`diagnose` (an arm record, a muscle record
  on the test bench or a cylinder campaign) and :mod:`.synthesize`, the hidden-effect
  data generator;
* :mod:`.arm` -- arm records: block residuals, static sawtooth rest points (§3.5.1.6),
  the candidate library, forward selection with its bootstrap, the pipeline;
* :mod:`.bench` -- actuator records on the test bench (muscles) and cylinder campaigns;
* :mod:`.core` -- what both share: noise levels, selection criteria and the naming
  rule, linear selection, parameters and the :class:`Diagnosis` result.

Documentation: ``docs/diagnose.md``.
"""

import inspect
import sys
import types

from .core.result import Diagnosis  # noqa: F401
from .diagnosis import diagnose
from .synthesize import synthesize

__all__ = ["Diagnosis", "diagnose", "synthesize"]


class _FrontDoorPackage(types.ModuleType):
    """This package, callable as its front door: ``ppamsafety.diagnose(data, ...)`` is
    :func:`diagnose` whether the name resolves to the package (once it is imported, the import
    system binds it in ``ppamsafety``) or to the function."""

    def __call__(self, *args, **kwargs):
        return diagnose(*args, **kwargs)


sys.modules[__name__].__class__ = _FrontDoorPackage
__signature__ = inspect.signature(diagnose)
