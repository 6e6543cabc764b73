"""The report's warm-up compiles the large kernels with the argument types of the real calls."""

import numpy as np
import pytest

from ppamsafety.control import PID, JointPSMC
from ppamsafety.control.estimation import ForceEstimator
from ppamsafety.experiments import ExperimentCase, run_batch
from ppamsafety.experiments.catalog import thesis_reference
from ppamsafety.experiments.closed_loop import _run_batch
from ppamsafety.impact import clamping, collision, engine, twobody
from ppamsafety.impact.clamping import simulate_clamping
from ppamsafety.impact.collision import Reaction, simulate_collision
from ppamsafety.impact.model import simulate_impacts
from ppamsafety.impact.twobody import two_body_impact
from ppamsafety.params import thesis_arm
from ppamsafety.report import warmup
from ppamsafety.units import BAR

KERNELS = {"closed_loop_kernels": [_run_batch, collision._run_collision],
           "impact_kernels": [engine.impact_batch, engine.impact_batch_dense],
           "contact_kernels": [clamping.clamp_batch, twobody._twobody_batch]}


def test_each_task_compiles_its_kernels():
    for i, task in enumerate(warmup.TASKS):
        warmup.run_task(i)
        for k in KERNELS[task.__name__]:
            assert len(k.signatures) >= 1, (task.__name__, k.py_func.__name__)


def test_real_calls_use_the_warm_up_types():
    """Study-sized calls after the warm-up (other controllers, references, batch sizes) find
    their kernels compiled for exactly their types: one signature per kernel, so the warm-up
    compiled what the report runs and nothing is compiled twice."""
    for i in range(len(warmup.TASKS)):
        warmup.run_task(i)
    arm = thesis_arm()
    ref = thesis_reference(arm, "step", duration=2.5)
    case = ExperimentCase(arm, JointPSMC(lam=0.4, ki=2.0 * BAR), ref, name="psmc")
    run_batch([case, ExperimentCase(arm, PID(), ref, estimator=ForceEstimator(), name="pid")])
    simulate_collision(case, head_position=np.array([4.0, -4.0]), reaction=Reaction.RETRACT)
    q = np.array([[0.8, -1.2], [1.0, -1.6]])
    for integrator in ("fixed", "dense"):
        simulate_impacts(arm, q, np.ones((2, 2)), np.array([[40.0, 20.0]] * 2), duration=0.01,
                         integrator=integrator)
    simulate_clamping(arm, q[0], np.ones(2), np.array([40.0, 20.0]), duration=2e-3)
    two_body_impact(np.array([0.5, 1.0]), arm_mass=1.5, stiffness=5e6, exponent=1.5,
                    duration=2e-3)
    for task, kernels in KERNELS.items():
        for k in kernels:
            assert len(k.signatures) == 1, (task, k.py_func.__name__, k.signatures)


@pytest.mark.parametrize("index, exc", [(-1, ValueError), (len(warmup.TASKS), ValueError),
                                        ("0", TypeError), (True, TypeError), (0.0, TypeError)])
def test_bad_task_index_is_named(index, exc):
    with pytest.raises(exc, match="index"):
        warmup.run_task(index)
