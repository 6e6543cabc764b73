"""Closed-loop experiments: reference trajectories, the compiled runner, the thesis catalogue.

:mod:`.catalog` names the thesis experiments and controller variants,
:mod:`.metrics` measures runs, :mod:`.conclusions` tests the thesis'
qualitative conclusions on those measures.
"""

from .catalog import run_thesis_experiment, thesis_reference, thesis_variants
from .closed_loop import ExperimentResult, run, run_batch
from .trajectories import Reference, circle, joint_steps, step, trajectory_switch

__all__ = ["ExperimentResult", "run", "run_batch", "Reference", "circle", "joint_steps", "step",
           "trajectory_switch", "thesis_variants", "thesis_reference", "run_thesis_experiment"]
