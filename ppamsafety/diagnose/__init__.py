"""The discrepancy workflow (issue 10): where measurement and model disagree, which effect
is missing, its fitted parameters, and the gap shrinking.

* :mod:`.residuals` -- replay and per-subsystem block residuals of an arm record;
* :mod:`.static` -- rest points of a static-sawtooth record (§3.5.1.6): torque balance,
  static valves, muscle forces, quasi-static equilibria;
* :mod:`.noise` -- the noise level estimated from the data;
* :mod:`.candidates` -- the library of candidate effects;
* :mod:`.selection` -- ranking (BIC), evidence, forward selection with refit, its
  moving-block bootstrap frequency;
* :mod:`.diagnosis` -- :func:`diagnose` and the :class:`Diagnosis` result;
* :mod:`.synthesize` -- the hidden-effect data generator;
* test bench (actuator records): :mod:`.actuator` (pipeline),
  :mod:`.actuator_candidates`, :mod:`.linear_selection` (the naming rule for
  linear residual models), :mod:`.actuator_synthesize`,
  :mod:`.actuator_battery` (blind battery, confusion matrix).

Documentation: ``docs/diagnose.md``.
"""

from .core.result import Diagnosis  # noqa: F401
from .diagnosis import diagnose
from .synthesize import synthesize

__all__ = ["Diagnosis", "diagnose", "synthesize"]
