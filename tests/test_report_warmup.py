"""The report's warm-up compiles the large kernels with the argument types of the real calls."""

import numpy as np
import pytest

from ppamsafety.experiments.closed_loop import _run_batch
from ppamsafety.impact import clamping, collision, engine, twobody
from ppamsafety.impact.model import simulate_impacts
from ppamsafety.params import thesis_arm
from ppamsafety.report import warmup

KERNELS = {"closed_loop_kernels": [_run_batch], "collision_kernels": [collision._run_collision],
           "impact_kernels": [engine.impact_batch, engine.impact_batch_dense],
           "contact_kernels": [clamping.clamp_batch, twobody._twobody_batch]}


def test_each_task_compiles_its_kernels():
    for i, task in enumerate(warmup.TASKS):
        warmup.run_task(i)
        for k in KERNELS[task.__name__]:
            assert len(k.signatures) >= 1, (task.__name__, k.py_func.__name__)


def test_real_calls_need_no_further_compilation():
    """A study-sized call after the warm-up finds its kernel already compiled for its types."""
    for i in range(len(warmup.TASKS)):
        warmup.run_task(i)
    before = {k: len(k.signatures) for ks in KERNELS.values() for k in ks}
    arm = thesis_arm()
    q = np.array([[0.8, -1.2], [1.0, -1.6]])
    simulate_impacts(arm, q, np.ones((2, 2)), np.array([[40.0, 20.0]] * 2), duration=0.01)
    simulate_impacts(arm, q, np.ones((2, 2)), np.array([[40.0, 20.0]] * 2), duration=0.01,
                     integrator="dense")
    assert {k: len(k.signatures) for k in before} == before


@pytest.mark.parametrize("index, exc", [(-1, ValueError), (len(warmup.TASKS), ValueError),
                                        ("0", TypeError), (True, TypeError), (0.0, TypeError)])
def test_bad_task_index_is_named(index, exc):
    with pytest.raises(exc, match="index"):
        warmup.run_task(index)
