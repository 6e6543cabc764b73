"""Closed-loop experiments: reference trajectories, the compiled runner, the thesis catalogue.

:mod:`.case` types one run (:class:`ExperimentCase`), :mod:`.trajectories` builds
references (:class:`Reference`), :mod:`.closed_loop` runs them
(:func:`run`, :func:`run_batch`, :class:`ExperimentResult`), :mod:`.catalog`
names the thesis experiments and controller variants
(:class:`ControllerVariant`), :mod:`.thesis_data` holds the thesis' tables keyed
by the variants' fields, :mod:`.metrics` measures runs, :mod:`.conclusions`
tests the thesis' qualitative conclusions on those measures.
"""

from .case import ExperimentCase
from .catalog import (ControllerVariant, Family, run_thesis_experiment, thesis_reference,
                      thesis_variants)
from .closed_loop import ExperimentResult, run, run_batch
from .trajectories import Reference, circle, joint_steps, step, trajectory_switch

__all__ = ["ExperimentCase", "ExperimentResult", "run", "run_batch", "Reference", "circle",
           "joint_steps", "step", "trajectory_switch", "ControllerVariant", "Family",
           "thesis_variants", "thesis_reference", "run_thesis_experiment"]
