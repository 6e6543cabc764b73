"""Compile the large kernels once, split between the report's worker processes.

Numba compiles a kernel on its first call and keeps it in an on-disk cache
(:mod:`ppamsafety._jit`).  With a cold cache -- a fresh clone, or after an
edit of code the kernels depend on (see
:func:`~ppamsafety._sourcehash.kernel_source_hash`; an edit of a study or of
the command line keeps the cache) -- the report's worker processes would
otherwise start sections that need the same kernels at the same moment and
compile them side by side: on 2 cores both workers spent their first 31 s
compiling the same closed loop, and the safety scan's own workers compiled
the dense impact engine twice more (measured with numba's compile events).

For the full report :func:`~ppamsafety.report.build.build_report` therefore
first runs the tasks of :data:`TASKS` in its worker pool, each as soon as the
tasks it comes :attr:`~Task.after` have finished, and starts the sections once
every task has started.  The tasks are small enough to keep both workers of a
2-core machine busy: the compiled closed loop calls the controller step and
the plant's RK4 step as functions of their own, so those two compile first,
side by side (:func:`controller_kernels`, :func:`plant_kernels`), and the
closed loop and the collision kernel then load them from the cache instead of
compiling them again.  Each other task calls the public functions on a tiny
problem, so the kernels are compiled for exactly the argument types of the real
calls; ``tests/test_report_warmup.py`` checks that those calls compile nothing
more.  With a warm cache a task only loads kernels (a fraction of a second to
a few seconds).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from numba import types

from ..control import PID
from ..control.dispatch import controller_step
from ..control.estimation import ForceEstimator, estimator_step
from ..experiments import run_batch, ExperimentCase
from ..experiments.catalog import thesis_reference
from ..impact.clamping import simulate_clamping
from ..impact.collision import simulate_collision
from ..impact.model import simulate_impacts
from ..impact.twobody import two_body_impact
from ..params import thesis_arm
from ..plant.model import rk4_step

__all__ = ["TASKS", "Task", "closed_loop_kernels", "collision_kernels", "contact_kernels",
           "controller_kernels", "impact_kernels", "plant_kernels", "run_task"]


def closed_loop_kernels() -> None:
    """The closed loop (:func:`~ppamsafety.experiments.run_batch`) with its sensor models,
    calling the kernels of :func:`controller_kernels` and :func:`plant_kernels`: about 8 s
    on a cold cache once those are compiled."""
    run_batch([_warm_case()])


def collision_kernels() -> None:
    """The head coupled to the closed loop
    (:func:`~ppamsafety.impact.collision.simulate_collision`), which calls the kernels of
    :func:`controller_kernels` and :func:`plant_kernels`: about 10 s on a cold cache once
    those are compiled.  It runs after :func:`closed_loop_kernels`, whose
    small set-up kernels (the rest state, the sensors) it shares."""
    # a head far away: the whole kernel is compiled whatever the run does
    simulate_collision(_warm_case(), head_position=np.array([5.0, 5.0]))


def _warm_case():
    """A 2.05 s PID step with the force estimator (the shortest step experiment)."""
    arm = thesis_arm()
    ref = thesis_reference(arm, "step", duration=2.05)
    return ExperimentCase(arm, PID(), ref, estimator=ForceEstimator(), name="warm-up")


def impact_kernels() -> None:
    """The fixed-step and the dense-output impact engines
    (:func:`~ppamsafety.impact.simulate_impacts`): about 30 s on a cold cache."""
    arm = thesis_arm()
    q, qd, k = np.array([0.9, -1.4]), np.array([1.0, 1.0]), np.array([40.0, 20.0])
    simulate_impacts(arm, q, qd, k, duration=1e-3)
    simulate_impacts(arm, q, qd, k, duration=1e-3, integrator="dense")


def contact_kernels() -> None:
    """Clamping against a wall and the two-body model (:mod:`~ppamsafety.impact.clamping`,
    :mod:`~ppamsafety.impact.twobody`): about 7 s on a cold cache."""
    arm = thesis_arm()
    simulate_clamping(arm, np.array([0.9, -1.4]), np.array([1.0, 1.0]), np.array([40.0, 20.0]),
                      duration=1e-3)
    two_body_impact(1.0, arm_mass=2.0, stiffness=1e7, exponent=1.5, duration=1e-3)


def _compile(dispatcher, codes: str) -> None:
    """Compile ``dispatcher`` for the argument types spelled by ``codes``.

    One letter per argument: ``A`` a float64, C-contiguous, writable 1-d array
    (:func:`~ppamsafety._jit.kernel_array`, and every row the compiled loops
    slice), ``i`` an int64, ``f`` a float64.  These are the types the closed
    loop passes (numba's compile events).  ``compile`` also writes
    the result to the on-disk cache, where the calling kernels find it.
    """
    kinds = {"A": types.Array(types.float64, 1, "C"), "i": types.int64, "f": types.float64}
    dispatcher.compile(tuple(kinds[c] for c in codes))


def controller_kernels() -> None:
    """The controller step of every kind (:func:`~ppamsafety.control.dispatch.controller_step`),
    as the closed loop and the collision kernel call it: about 11 s on a cold cache."""
    _compile(controller_step, "iAAAifAAAAAAAA")


def plant_kernels() -> None:
    """The plant's RK4 step (:func:`~ppamsafety.plant.model.rk4_step`, with the plant derivative)
    and the force estimator's step, as the closed loop calls them: about 8 s on a cold cache."""
    _compile(rk4_step, "AAAAfAA")
    _compile(estimator_step, "AAAifAAAAA")


@dataclass(frozen=True)
class Task:
    """One warm-up task: ``run()`` compiles its kernels once the tasks named in ``after`` are done.

    Attributes
    ----------
    run : callable
        A top-level function of this module without arguments.
    after : tuple of str
        Names (``run.__name__``) of the tasks to wait for: those whose kernels ``run``
        calls or shares, which it then loads from the cache instead of compiling them again.
    """

    run: Callable[[], None]
    after: tuple = ()

    def __post_init__(self):
        if not callable(self.run):
            raise TypeError(f"run must be a callable, got {type(self.run).__name__} "
                            f"{self.run!r}")
        if not (isinstance(self.after, tuple) and all(isinstance(a, str) for a in self.after)):
            raise TypeError(f"after must be a tuple of task names (str), got {self.after!r}")

    @property
    def name(self) -> str:
        """``run.__name__``."""
        return self.run.__name__


#: Warm-up tasks in order of priority (the start of the longest chain first); a task may start
#: once the tasks it comes after have finished.
TASKS = (Task(controller_kernels), Task(plant_kernels), Task(impact_kernels),
         Task(closed_loop_kernels, after=("controller_kernels", "plant_kernels")),
         Task(collision_kernels, after=("closed_loop_kernels",)),
         Task(contact_kernels))


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
    TASKS[index].run()
