"""System identification of the arm (thesis §3.5).

* :mod:`.lsq` -- linear least squares with standard errors, t intervals,
  condition number; the result object :class:`LSQResult`.
* :mod:`.static` -- §3.5.1: muscle force law (3.8)-(3.11), valves (3.12),
  gravity parameters from equilibria (3.13)-(3.16), a synthetic static
  experiment.
* :mod:`.dynamic` -- §3.5.2: regressors (B.3)-(B.6), acceleration-free
  filtering (3.21)-(3.28) with the bilinear F(z), LS / two-step WLS,
  validation laid out like Table 3.4.
* :mod:`.consistent` -- physically consistent estimate: LS under the planar
  pseudo-inertia LMIs (Wensing, Kim & Slotine 2017), needs cvxpy
  (extra ``[identify]``).
* :mod:`.excitation` -- §3.5.2.4: 5-harmonic 10 s Fourier Delta-p excitation,
  its simulation and its design for the condition number.
"""

from .consistent import ConsistentResult, identify_dynamic_consistent
from .dynamic import (DynamicData, DynamicResult, filtered_regressor, filtered_system,
                      identify_dynamic, mean_squared_torque_error, validation_table)
from .excitation import (ExcitationDesign, FourierExcitation, design_excitation,
                         simulate_excitation)
from .lsq import LSQResult
from .static import (StaticExperiment, equilibrium_configurations, gravity_base_parameters,
                     identify_gravity, identify_muscle, identify_valve, identify_valves,
                     static_experiment, torques_from_forces)

__all__ = ["LSQResult", "identify_muscle", "identify_valve", "identify_valves", "identify_gravity",
           "gravity_base_parameters", "torques_from_forces", "equilibrium_configurations",
           "StaticExperiment", "static_experiment", "DynamicData", "DynamicResult",
           "filtered_regressor", "filtered_system", "identify_dynamic",
           "identify_dynamic_consistent", "ConsistentResult",
           "mean_squared_torque_error", "validation_table", "FourierExcitation",
           "ExcitationDesign", "design_excitation", "simulate_excitation"]
