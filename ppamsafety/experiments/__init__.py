"""Closed-loop experiments: reference trajectories and the compiled runner."""

from .closed_loop import ExperimentResult, run, run_batch
from .trajectories import Reference, circle, joint_steps, step, trajectory_switch

__all__ = ["ExperimentResult", "run", "run_batch", "Reference", "circle", "joint_steps", "step",
           "trajectory_switch"]
