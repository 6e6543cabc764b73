"""Compile the large kernels once, split between the report's worker processes.

Numba compiles a kernel on its first call and keeps it in an on-disk cache
(:mod:`ppamsafety._jit`).  With a cold cache -- a fresh clone, or after any
edit of the package -- the report's worker processes would otherwise start
sections that need the same kernels at the same moment and compile them side
by side: on 2 cores both workers spent their first 31 s compiling the same
closed loop, and the safety scan's own workers compiled the dense impact
engine twice more (measured with numba's compile events, issue 11).

For the full report :func:`~ppamsafety.report.build.build_report` therefore
first runs the tasks of :data:`TASKS` in its worker pool and starts the
sections once all have finished (on 2 cores: the closed loop and the
collision kernel in one worker, the impact engines and the contact models in
the other, about 50 s).  Each task calls the public functions on a tiny
problem, so the kernels are compiled for exactly the argument types of the
real calls; the other workers then load them from the cache in a fraction of
a second.  With a warm cache a task only loads kernels (a few seconds).
"""

from __future__ import annotations

import numpy as np

__all__ = ["TASKS", "closed_loop_kernels", "contact_kernels", "impact_kernels", "run_task"]


def closed_loop_kernels() -> None:
    """The closed loop (:func:`~ppamsafety.experiments.run_batch`) with its controller, plant,
    sensor and estimator kernels (about 30 s on a cold cache), then the head coupled to it
    (:func:`~ppamsafety.impact.collision.simulate_collision`, about 14 s more), which calls
    those kernels: in one task, so that they are never compiled twice at the same time."""
    from ..experiments import run_batch
    from ..impact.collision import simulate_collision

    case = _warm_case()
    run_batch([case])
    # a head far away: the whole kernel is compiled whatever the run does
    simulate_collision(case, head_position=np.array([5.0, 5.0]))


def _warm_case():
    """A 2.05 s PID step with the force estimator (the shortest step experiment)."""
    from ..control import PID
    from ..control.estimation import ForceEstimator
    from ..experiments import ExperimentCase
    from ..experiments.catalog import thesis_reference
    from ..params import thesis_arm

    arm = thesis_arm()
    ref = thesis_reference(arm, "step", duration=2.05)
    return ExperimentCase(arm, PID(), ref, estimator=ForceEstimator(), name="warm-up")


def impact_kernels() -> None:
    """The fixed-step and the dense-output impact engines
    (:func:`~ppamsafety.impact.simulate_impacts`): about 30 s on a cold cache."""
    from ..impact.model import simulate_impacts
    from ..params import thesis_arm

    arm = thesis_arm()
    q, qd, k = np.array([0.9, -1.4]), np.array([1.0, 1.0]), np.array([40.0, 20.0])
    simulate_impacts(arm, q, qd, k, duration=1e-3)
    simulate_impacts(arm, q, qd, k, duration=1e-3, integrator="dense")


def contact_kernels() -> None:
    """Clamping against a wall and the two-body model (:mod:`~ppamsafety.impact.clamping`,
    :mod:`~ppamsafety.impact.twobody`): about 7 s on a cold cache."""
    from ..impact.clamping import simulate_clamping
    from ..impact.twobody import two_body_impact
    from ..params import thesis_arm

    arm = thesis_arm()
    simulate_clamping(arm, np.array([0.9, -1.4]), np.array([1.0, 1.0]), np.array([40.0, 20.0]),
                      duration=1e-3)
    two_body_impact(1.0, arm_mass=2.0, stiffness=1e7, exponent=1.5, duration=1e-3)


#: Warm-up tasks, longest first; they share no kernel, so they can run at the same time.
TASKS = (closed_loop_kernels, impact_kernels, contact_kernels)


def run_task(index: int) -> None:
    """Run the warm-up task ``TASKS[index]`` (a top-level function: picklable for a pool).

    Parameters
    ----------
    index : int
        Position in :data:`TASKS`.
    """
    if isinstance(index, bool) or not isinstance(index, (int, np.integer)):
        raise TypeError(f"index must be an int, got {type(index).__name__} {index!r}")
    if not 0 <= index < len(TASKS):
        raise ValueError(f"index = {index} is not a task; allowed 0..{len(TASKS) - 1}")
    TASKS[index]()
