"""Collision and safety analysis (thesis chapter 6).

Modules (one concept each):

* :mod:`.contact` -- Hunt-Crossley contact law and its closed-form solution;
* :mod:`.engine` -- the compiled batch kernel: flexible-joint arm against a free head;
* :mod:`.model` -- :func:`simulate_impacts`, :class:`ImpactResults`, :func:`effective_mass`;
* :mod:`.instants` -- impact cases from a closed-loop experiment (four instants or all;
  :func:`worst_instant`: the exact worst of every instant, pruned by rigorous bounds);
* :mod:`.bounds` -- a-priori upper bounds on F_max and HIC of an impact (energy, momentum);
* :mod:`.directions` -- the worst head placement around the tool point, over every instant
  (two-body predictor, rigorous instant bounds, Brent refinement with the engine);
* :mod:`.hic` -- Head Injury Criterion: exact fast evaluation and closed forms;
* :mod:`.twobody` -- the one-dimensional effective-mass impact;
* :mod:`.head_fit` -- reconstruction of the thesis' head contact parameters;
* :mod:`.reference` -- the same impact with scipy's adaptive integrator;
* :mod:`.pymunk_engine` -- the same impact built from pymunk bodies, pivots and rotary
  springs, an independent cross-check of the main engine;
* :mod:`.thesis_data` -- Table 6.1 and fig. 6.3 reference values.
"""

from .engine import JointModel
from .hic import hic
from .instants import evaluate_experiment, worst_instant
from .model import ImpactResults, effective_mass, simulate_impacts

__all__ = ["JointModel", "hic", "evaluate_experiment", "worst_instant", "ImpactResults", "effective_mass", "simulate_impacts"]
