"""Closed-loop experiments: reference trajectories, the compiled runner, the thesis catalogue.

:mod:`.case` types one run (:class:`ExperimentCase`), :mod:`.catalog` names
the thesis experiments and controller variants (:class:`ControllerVariant`),
:mod:`.thesis_data` holds the thesis' tables keyed by the variants' fields,
:mod:`.metrics` measures runs, :mod:`.conclusions` tests the thesis'
qualitative conclusions on those measures.

The names below are imported lazily, so that low-level modules (e.g. the
controller kernels reading the offsets of :mod:`.trajectories`) can import
``ppamsafety.experiments.trajectories`` without importing the runner.
"""

import importlib

_EXPORTS = {
    "ExperimentCase": "case",
    "ExperimentResult": "closed_loop", "run": "closed_loop", "run_batch": "closed_loop",
    "Reference": "trajectories", "circle": "trajectories", "joint_steps": "trajectories",
    "step": "trajectories", "trajectory_switch": "trajectories",
    "ControllerVariant": "catalog", "Family": "catalog", "thesis_variants": "catalog",
    "thesis_reference": "catalog", "run_thesis_experiment": "catalog",
}


def __getattr__(name):
    mod = _EXPORTS.get(name)
    if mod is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{mod}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_EXPORTS))


__all__ = ["ExperimentCase", "ExperimentResult", "run", "run_batch", "Reference", "circle",
           "joint_steps", "step", "trajectory_switch", "ControllerVariant", "Family",
           "thesis_variants", "thesis_reference", "run_thesis_experiment"]
