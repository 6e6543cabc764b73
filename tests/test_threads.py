"""The closed-loop batch on several threads (``run_batch(threads=...)``, ``_jit.run_threaded``).

Every case of a batch writes only its own rows, so the results must not depend on the
number of threads: checked bit for bit on a mixed batch (controllers, sensors, a plant with
hysteresis, an estimator, a diverging case), and the helper that splits a batch is checked
on its own (every row exactly once, errors raised, bad thread counts refused).
"""

import threading

import numpy as np
import pytest

from ppamsafety import _jit
from ppamsafety.control import PID, JointPSMC, SensorConfig, TaskPSMC
from ppamsafety.control.estimation import ForceEstimator
from ppamsafety.experiments import ExperimentCase, run_batch
from ppamsafety.experiments.catalog import thesis_reference
from ppamsafety.params import thesis_arm
from ppamsafety.units import BAR


def _cases():
    arm = thesis_arm()
    hyst = arm.replace(effects=arm.effects.replace(hysteresis_delta=(0.2,) * 4))
    ref = thesis_reference(arm, "step", duration=2.5)
    return [ExperimentCase(arm, PID(), ref, name="pid"),
            ExperimentCase(arm, JointPSMC(lam=0.4), ref, sensors=SensorConfig(noise=True,
                                                                              seed=3)),
            ExperimentCase(hyst, JointPSMC(lam=1.5, ki=12 * BAR), ref),
            ExperimentCase(arm, TaskPSMC(), ref, sensors=SensorConfig.ideal()),
            ExperimentCase(arm, PID(), ref, estimator=ForceEstimator(), name="estimator")]


def _same(one, many):
    for a, b in zip(one, many, strict=True):
        assert a.name == b.name and a.diverged == b.diverged
        np.testing.assert_array_equal(a.log, b.log)          # NaN where diverged, both
        if a.interaction is not None:
            np.testing.assert_array_equal(a.interaction, b.interaction)


def test_results_do_not_depend_on_the_number_of_threads():
    cases = _cases()
    one = run_batch(cases, threads=1)
    for threads in (2, 5):
        _same(one, run_batch(cases, threads=threads))
    assert not any(r.diverged for r in one)
    # one case alone gives the same bits as inside the batch
    np.testing.assert_array_equal(run_batch([cases[2]], threads=3)[0].log, one[2].log)


def test_a_diverging_case_stops_alone_on_any_number_of_threads():
    """Huge PID gains with a 50 ms control period blow up (tests/test_validation_control.py);
    the other cases of the batch run on, whichever thread runs them."""
    arm = thesis_arm()
    slow = arm.replace(effects=arm.effects.replace(valve_time_constant=(0.05,) * 4))
    ref = thesis_reference(arm, "step", duration=3.0, dt=0.05)
    cases = [ExperimentCase(slow, PID(), ref, name="calm", sensors=SensorConfig.ideal()),
             ExperimentCase(slow, PID(kp=1e9, ki=1e9, kd=1e7), ref, name="wild",
                            sensors=SensorConfig.ideal()),
             ExperimentCase(slow, JointPSMC(), ref, name="psmc")]
    with pytest.warns(UserWarning, match="'wild' diverged"):
        one = run_batch(cases, dt=0.05, threads=1)
    with pytest.warns(UserWarning, match="'wild' diverged"):
        _same(one, run_batch(cases, dt=0.05, threads=3))
    assert [r.diverged for r in one] == [False, True, False]


def test_run_threaded_covers_every_row_once_in_parts():
    seen, lock, names = [], threading.Lock(), set()

    def part(first, last):
        with lock:
            seen.extend(range(first, last))
            names.add(threading.current_thread().name)

    _jit.run_threaded(part, 103, threads=3)
    assert sorted(seen) == list(range(103))
    assert len(seen) == 103
    seen.clear()
    _jit.run_threaded(part, 1, threads=4)           # one row: in the calling thread
    assert seen == [0]
    seen.clear()
    _jit.run_threaded(part, 0, threads=2)
    assert seen == []


def test_run_threaded_raises_the_error_of_a_part():
    def part(first, last):
        if first <= 7 < last:
            raise ValueError("row 7 is bad")

    with pytest.raises(ValueError, match="row 7"):
        _jit.run_threaded(part, 20, threads=2)


def test_thread_counts_are_checked():
    with pytest.raises(ValueError, match="threads"):
        _jit.run_threaded(lambda a, b: None, 5, threads=0)
    with pytest.raises(ValueError, match="threads"):
        _jit.set_default_threads(0)
    with pytest.raises(ValueError, match="threads"):
        run_batch(_cases()[:1], threads=0)
    with pytest.raises(ValueError, match="threads"):
        run_batch(_cases()[:1], threads=1.5)
    with pytest.raises(TypeError, match="threads"):
        run_batch(_cases()[:1], threads="2")
    old = _jit.default_threads()
    try:
        _jit.set_default_threads(1)
        assert _jit.default_threads() == 1
    finally:
        _jit.set_default_threads(None)
    assert _jit.default_threads() == _jit.available_cores() == old
