"""The report's warm-up compiles the large kernels with the argument types of the real calls."""

import numpy as np
import pytest

from ppamsafety.control import PID, JointPSMC
from ppamsafety.control.dispatch import controller_step
from ppamsafety.control.estimation import ForceEstimator, estimator_step
from ppamsafety.experiments import ExperimentCase, run_batch
from ppamsafety.experiments.catalog import thesis_reference
from ppamsafety.experiments.closed_loop import _run_batch
from ppamsafety.impact import clamping, collision, engine, twobody
from ppamsafety.impact.clamping import simulate_clamping
from ppamsafety.impact.collision import Reaction, simulate_collision
from ppamsafety.impact.model import simulate_impacts
from ppamsafety.impact.twobody import two_body_impact
from ppamsafety.params import thesis_arm
from ppamsafety.plant.model import rk4_step
from ppamsafety.report import warmup
from ppamsafety.units import BAR

KERNELS = {"controller_kernels": [controller_step],
           "plant_kernels": [rk4_step, estimator_step],
           "closed_loop_kernels": [_run_batch],
           "collision_kernels": [collision._run_collision],
           "impact_kernels": [engine.impact_batch, engine.impact_batch_dense],
           "contact_kernels": [clamping.clamp_batch, twobody._twobody_batch]}


def test_each_task_compiles_its_kernels():
    assert sorted(t.name for t in warmup.TASKS) == sorted(KERNELS)
    names = [t.name for t in warmup.TASKS]
    for i, task in enumerate(warmup.TASKS):
        assert all(names.index(a) < i for a in task.after), task   # runnable in table order
        warmup.run_task(i)
        for k in KERNELS[task.name]:
            assert len(k.signatures) >= 1, (task.name, k.py_func.__name__)


def test_real_calls_use_the_warm_up_types():
    """Study-sized calls after the warm-up (other controllers, references, batch sizes) find
    their kernels compiled for exactly their types: one signature per kernel, so the warm-up
    compiled what the report runs and nothing is compiled twice.  (A kernel loaded from the
    cache does not type the kernels it calls; the fresh-cache test below covers those.)  The
    Python API calls the controller step with the same row types
    (``Controller.step``, checked here too)."""
    for i in range(len(warmup.TASKS)):
        warmup.run_task(i)
    compiled = {k: list(k.signatures) for ks in KERNELS.values() for k in ks}
    arm = thesis_arm()
    ref = thesis_reference(arm, "step", duration=2.5)
    case = ExperimentCase(arm, JointPSMC(lam=0.4, ki=2.0 * BAR), ref, name="psmc")
    run_batch([case, ExperimentCase(arm, PID(), ref, estimator=ForceEstimator(), name="pid")])
    JointPSMC().step(arm, np.array([0.8, -1.2]), np.zeros(2), np.zeros(4), ref.data[0])
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
            # nothing new; and a single signature for the kernels only the report's paths call
            # (other tests call the controller and plant steps with other row types)
            assert k.signatures == compiled[k], (task, k.py_func.__name__, k.signatures)
            if task not in ("controller_kernels", "plant_kernels"):
                assert len(k.signatures) == 1, (task, k.py_func.__name__, k.signatures)


@pytest.mark.parametrize("index, exc", [(-1, ValueError), (len(warmup.TASKS), ValueError),
                                        ("0", TypeError), (True, TypeError), (0.0, TypeError)])
def test_bad_task_index_is_named(index, exc):
    with pytest.raises(exc, match="index"):
        warmup.run_task(index)


_FRESH_CACHE_SCRIPT = """
import sys
from numba.core import event
from ppamsafety.report import warmup

compiled = []


class Listener(event.Listener):
    def on_start(self, ev):
        compiled.append(ev.data["dispatcher"].py_func.__name__)

    def on_end(self, ev):
        pass


event.register("numba:compile", Listener())
for i, task in enumerate(warmup.TASKS):
    del compiled[:]
    warmup.run_task(i)
    print(task.name, " ".join(sorted(set(compiled))))
"""


@pytest.mark.slow
def test_dependent_tasks_reuse_the_compiled_steps(tmp_path):
    """On a fresh kernel cache, the closed loop and the collision kernel load the controller
    step, the RK4 step and the estimator step that the first tasks compiled (the hand-written
    signatures of ``warmup._compile`` match the calls) instead of compiling them again."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "PPAMSAFETY_CACHE_DIR": str(tmp_path)}
    env.pop("NUMBA_CACHE_DIR", None)
    out = subprocess.run([sys.executable, "-c", _FRESH_CACHE_SCRIPT], env=env, check=True,
                         capture_output=True, text=True, timeout=900).stdout
    compiled = {line.split()[0]: set(line.split()[1:]) for line in out.splitlines() if line}
    assert {"controller_step"} <= compiled["controller_kernels"]
    assert {"rk4_step", "estimator_step", "plant_rhs_at"} <= compiled["plant_kernels"]
    steps = {"controller_step", "rk4_step", "estimator_step", "plant_rhs_at"}
    for task in ("closed_loop_kernels", "collision_kernels"):
        assert "_run_batch" in compiled["closed_loop_kernels"]
        assert not steps & compiled[task], (task, steps & compiled[task])


def _scheduled(monkeypatch, tasks, studies=("s1", "s2"), processes=2):
    """Run ``build._run_in_pool`` on a thread pool with ``tasks`` and fake studies; the log of
    (event, name) in time order and the studies reported."""
    import threading
    import time
    from concurrent.futures import ThreadPoolExecutor

    from ppamsafety.report import build

    log, lock = [], threading.Lock()

    def task(name, seconds, fail=False):
        def run():
            with lock:
                log.append(("start", name))
            time.sleep(seconds)
            with lock:
                log.append(("end", name))
            if fail:
                raise RuntimeError(f"task {name} failed")
        run.__name__ = name
        return run

    def fake_study(name, stage, quick, arm=None, head=None, processes=None):
        with lock:
            log.append(("start", name))
        return name, 0.0, 0.0

    monkeypatch.setattr(warmup, "TASKS", tuple(warmup.Task(task(*spec[:3]), after=spec[3])
                                               for spec in tasks))
    monkeypatch.setattr(build, "_timed_section", fake_study)
    reported = []
    with ThreadPoolExecutor(processes) as pool:
        build._run_in_pool(pool, processes, list(studies), None, False, True,
                           lambda name, res, dt, cpu: reported.append(name))
    return {e: i for i, e in enumerate(log)}, reported


def test_schedule_follows_after_and_starts_studies_once_every_task_started(monkeypatch):
    pos, reported = _scheduled(monkeypatch, [("a", 0.3, False, ()), ("b", 0.02, False, ()),
                                             ("c", 0.01, False, ("a",)),
                                             ("d", 0.01, False, ("b",))])
    assert pos[("start", "c")] > pos[("end", "a")]
    assert pos[("start", "d")] > pos[("end", "b")]
    assert pos[("start", "d")] < pos[("end", "a")]      # a free worker does not wait for "a"
    first_study = min(pos[("start", s)] for s in ("s1", "s2"))
    assert all(pos[("start", t)] < first_study for t in "abcd")
    assert sorted(reported) == ["s1", "s2"]


def test_a_failing_task_warns_and_the_studies_still_run(monkeypatch):
    with pytest.warns(RuntimeWarning, match="warm-up task a failed"):
        pos, reported = _scheduled(monkeypatch, [("a", 0.01, True, ()),
                                                 ("b", 0.01, False, ("a",))])
    assert pos[("start", "b")] > pos[("end", "a")]
    assert sorted(reported) == ["s1", "s2"]


def test_a_task_waiting_for_an_unknown_task_is_an_error(monkeypatch):
    with pytest.raises(RuntimeError, match="not in warmup.TASKS"):
        _scheduled(monkeypatch, [("a", 0.01, False, ("nowhere",))])


def test_report_workers_use_one_blas_thread():
    """The report's worker initializer limits BLAS to one thread (the workers fill the cores)."""
    import subprocess
    import sys

    script = ("import numpy; from threadpoolctl import threadpool_info; "
              "from ppamsafety.report.build import _one_blas_thread; _one_blas_thread(); "
              "print(sorted({p['num_threads'] for p in threadpool_info() "
              "if p['user_api'] == 'blas'}))")
    out = subprocess.run([sys.executable, "-c", script], check=True, capture_output=True,
                         text=True, timeout=300).stdout.strip()
    assert out == "[1]", out


@pytest.mark.parametrize("kwargs, match", [({"run": "closed_loop_kernels"}, "run"),
                                           ({"run": warmup.plant_kernels, "after": "x"}, "after"),
                                           ({"run": warmup.plant_kernels, "after": (1,)},
                                            "after")])
def test_bad_task_is_named(kwargs, match):
    with pytest.raises(TypeError, match=match):
        warmup.Task(**kwargs)


def test_metrics_record_wall_and_cpu_time_of_each_section(tmp_path):
    """metrics.json holds each section's wall and CPU time [s] (the CPU time counts the
    threads of the process that ran it); here one quick section in this process."""
    import json

    from ppamsafety.report.build import build_report

    build_report(tmp_path / "r", quick=True, only=["stiffness"], processes=1, progress=False)
    m = json.loads((tmp_path / "r" / "metrics.json").read_text())["stiffness"]
    assert m["wall_time_s"] > 0 and m["cpu_time_s"] > 0
    # one thread mostly: the CPU time is not far above the wall time
    assert m["cpu_time_s"] < 4.0 * m["wall_time_s"] + 1.0
