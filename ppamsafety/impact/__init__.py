"""Collision and safety analysis (thesis chapter 6).

Modules (one concept each):

* :mod:`.contact` -- Hunt-Crossley contact law and its closed-form solution;
* :mod:`.layers` -- layers in series (covering, soft tissue, bone): one shared force, the
  compiled law, its two-body impact and phase-plane closed form;
* :mod:`.bodies` -- body regions as contacts (a head model, an ISO/TS 15066 Annex A region),
  the Hybrid III head drop of 49 CFR 572.32;
* :mod:`.covering_fit` -- the covering Table 6.1 implies in front of the validated head;
* :mod:`.points` -- the compiled engine of any contact point of the arm against a body;
* :mod:`.anywhere` -- :func:`simulate_contacts`, bounds, and :func:`worst_contact` (the worst
  over contact point x body region x instant);
* :mod:`.engine` -- the compiled batch kernel: flexible-joint arm against a free head;
* :mod:`.model` -- :func:`simulate_impacts`, :class:`ImpactResult`, :func:`effective_mass`;
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

from .anywhere import simulate_contacts, worst_contact
from .engine import JointModel
from .hic import hic
from .instants import evaluate_experiment, worst_instant
from .model import ImpactResult, effective_mass, simulate_impacts

__all__ = ["JointModel", "hic", "evaluate_experiment", "worst_instant", "ImpactResult", "effective_mass", "simulate_impacts", "simulate_contacts", "worst_contact"]
