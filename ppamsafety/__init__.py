"""ppamsafety: safety and impact analysis of compliant arms driven by pneumatic muscles.

The everyday entry points are here, loaded on first use (``import ppamsafety`` stays fast)::

    import ppamsafety as ps

    arm = ps.thesis_arm()                       # or ps.load_arm("my_arm.toml")
    run = ps.simulate(arm, ps.JointPSMC(lam=0.4), ps.step(arm))
    worst = ps.worst_instant(run, arm)          # the worst impact over every instant

=============================  ========================================================
the arm                        :func:`thesis_arm`, :func:`load_arm`, :class:`ArmParameters`
simulation                     :func:`simulate`, :func:`run_batch`, :class:`ExperimentCase`,
                               the references :func:`step`, :func:`trajectory_switch`,
                               :func:`circle`, :func:`joint_steps`
controllers                    :class:`PID`, :class:`JointPSMC`, :class:`TaskPSMC`,
                               :class:`SlidingModeControl`, :class:`AdmittancePSMC`,
                               :class:`GravityCompensation`, sensors :class:`SensorConfig`
impacts                        :func:`simulate_impacts`, :func:`evaluate_experiment`,
                               :func:`worst_instant`, :func:`hic`
sweeps                         :func:`safety_case`, :func:`safety_sweep`,
                               :func:`safety_envelope`, :func:`run_study_file`
diagnosis                      :func:`diagnose`, :func:`synthesize`, :func:`load_measured`
=============================  ========================================================

Everything else lives in the subpackages (``ppamsafety.plant``, ``ppamsafety.impact``, ...;
``docs/architecture.md``), and ``ppamsafety report`` writes the whole report.
"""

from __future__ import annotations

import importlib

from ._version import __version__

#: Public name -> (module, attribute) of the lazily loaded entry points.
_ENTRY_POINTS = {
    "thesis_arm": ("ppamsafety.params", "thesis_arm"),
    "load_arm": ("ppamsafety.design", "load_arm"),  # data and physics checked, as the commands
    "ArmParameters": ("ppamsafety.params", "ArmParameters"),
    "simulate": ("ppamsafety.experiments", "run"),
    "run_batch": ("ppamsafety.experiments", "run_batch"),
    "ExperimentCase": ("ppamsafety.experiments", "ExperimentCase"),
    "step": ("ppamsafety.experiments", "step"),
    "trajectory_switch": ("ppamsafety.experiments", "trajectory_switch"),
    "circle": ("ppamsafety.experiments", "circle"),
    "joint_steps": ("ppamsafety.experiments", "joint_steps"),
    "PID": ("ppamsafety.control", "PID"),
    "JointPSMC": ("ppamsafety.control", "JointPSMC"),
    "TaskPSMC": ("ppamsafety.control", "TaskPSMC"),
    "SlidingModeControl": ("ppamsafety.control", "SlidingModeControl"),
    "AdmittancePSMC": ("ppamsafety.control", "AdmittancePSMC"),
    "GravityCompensation": ("ppamsafety.control", "GravityCompensation"),
    "SensorConfig": ("ppamsafety.control", "SensorConfig"),
    "simulate_impacts": ("ppamsafety.impact", "simulate_impacts"),
    "evaluate_experiment": ("ppamsafety.impact", "evaluate_experiment"),
    "worst_instant": ("ppamsafety.impact", "worst_instant"),
    "hic": ("ppamsafety.impact", "hic"),
    "safety_case": ("ppamsafety.sweep_cases", "safety_case"),
    "safety_sweep": ("ppamsafety.sweep_cases", "safety_sweep"),
    "safety_envelope": ("ppamsafety.envelope", "safety_envelope"),
    "run_study_file": ("ppamsafety.study_files", "run_study_file"),
    "diagnose": ("ppamsafety.diagnose", None),     # the package, callable as its front door
    "synthesize": ("ppamsafety.diagnose", "synthesize"),
    "load_measured": ("ppamsafety.data", "load_measured"),
}

__all__ = ["__version__", *_ENTRY_POINTS]


def __getattr__(name: str):
    """Load an entry point of :data:`_ENTRY_POINTS` on first use (PEP 562)."""
    try:
        module, attribute = _ENTRY_POINTS[name]
    except KeyError:
        raise AttributeError(f"module 'ppamsafety' has no attribute {name!r}") from None
    value = importlib.import_module(module)
    if attribute is not None:
        value = getattr(value, attribute)
        globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_ENTRY_POINTS))
