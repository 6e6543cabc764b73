"""The discrepancy workflow on closed-loop records (issue 10, closed loop).

A closed-loop record carries the set values the controller sent; the
diagnosis replays the plant with them.  Feedback makes the set values depend
on the measurement noise (the controller sees the noisy q, qd that are
recorded); these tests check that the residual statistics survive that, and
run a small blind battery (each library effect alone, nothing hidden, two
together).  Magnitudes as in ``tests/test_diagnose_battery.py`` (its module
docstring says why); the records are 10 s of the 10 s circle under joint
PSMC (Ki = 2, lambda = 0.4 s) unless stated.
"""

import numpy as np
import pytest

from ppamsafety.data import load_measured
from ppamsafety.diagnose import diagnose, synthesize
from ppamsafety.diagnose.arm.residuals import arm_record, block_system, model_vector, replay
from ppamsafety.params import thesis_arm
from ppamsafety.plant import packing

ARM = thesis_arm()
NOM_T = np.array([v.time_constant for v in ARM.valves.valves])

CASES = {
    "nothing": ({}, set()),
    "payload": ({"payload_mass": 0.4}, {"payload"}),
    "valve_offset": ({"valve_offset_delta": 5000.0}, {"valve_offset_gain"}),
    "valve_lag": ({"valve_time_constant_factor": 1.5}, {"valve_lag"}),
    "friction": ({"friction_coulomb_factor": 3.0}, {"joint_friction"}),
    "polytropic": ({"polytropic_n": 1.0}, {"polytropic_exponent"}),
    "dead_time": ({"valve_dead_time": 0.02}, {"valve_dead_time"}),
    "friction+dead_time": ({"friction_coulomb_factor": 3.0, "valve_dead_time": 0.02},
                           {"joint_friction", "valve_dead_time"}),
    "payload+lag": ({"payload_mass": 0.4, "valve_time_constant_factor": 1.5},
                    {"payload", "valve_lag"}),
}


def test_closed_loop_record_metadata_and_no_hint(tmp_path):
    a = synthesize("closed-loop", {"payload_mass": 0.4}, seed=2, duration=3.0,
                   reference="step", controller="PID")
    b = synthesize("closed-loop", {"valve_dead_time": 0.02}, seed=2, duration=3.0,
                   reference="step", controller="PID")
    assert a.meta == b.meta
    assert a.meta["reference"] == "step" and a.meta["controller"] == {"variant": "PID"}
    # feedback: the controller sent different set values to different plants
    assert not np.array_equal(a.column("u1"), b.column("u1"))
    back = load_measured(a.save(tmp_path / "cl.csv"))
    assert back.experiment == "closed-loop" and back.meta["reference"] == "step"
    np.testing.assert_allclose(back.column("u3"), a.column("u3"), rtol=1e-12)


def test_closed_loop_replay_with_the_sent_set_values_reproduces_the_record():
    """Noise-free, nominal plant: replaying the logged set values open loop gives back the
    closed-loop trajectory (same plant, same RK4 step): the logged u is what the valves got."""
    rec, _ = arm_record(synthesize("closed-loop", noise="none", seed=0, duration=3.0))
    X = replay(rec, packing.pack(ARM)[None])[0]
    assert np.max(np.abs(X[:, :2] - rec.q)) < 1e-9          # rad
    assert np.max(np.abs(X[:, 4:] - rec.p)) < 1e-4          # Pa
    bs = block_system(rec, ARM)
    r = bs.y - bs.X @ model_vector(packing.pack(ARM))
    assert np.max(np.abs(r[:, :4])) < 5.0                   # Pa (trapezoid at 1 kHz)
    assert np.max(np.abs(r[:, 4:])) < 2e-5                  # N m s


@pytest.mark.parametrize("reference,controller", [("circle10", "PSMC joint Ki=2 λ=0.4"),
                                                  ("step", "PID")])
def test_feedback_keeps_the_residual_statistics(reference, controller):
    """Nothing hidden, measurement noise fed back through the controller: every whitened
    block channel has RMS 1 within 15 % (about 200 blocks: standard error ~5 %) and mean 0
    within 4 standard errors, and nothing is named."""
    dg = diagnose(synthesize("closed-loop", seed=5, duration=10.0, reference=reference,
                             controller=controller))
    e = dg.blocks["before"]
    rms = np.sqrt(np.mean(e ** 2, axis=0))
    np.testing.assert_allclose(rms, 1.0, atol=0.15)
    z = e.mean(axis=0) * np.sqrt(e.shape[0])
    assert np.all(np.abs(z) < 4.0), z
    assert dg.names == () and not dg.unexplained


def outcome(case, dg):
    named = set(dg.names)
    return "correct" if named == CASES[case][1] else "named: " + ("+".join(sorted(named))
                                                                  or "none")


def check_parameters(case, dg):
    """Fitted parameters within the tolerances of tests/test_diagnose_battery.py."""
    p = {e.name: e.parameters for e in dg.effects}
    if "payload" in p:
        assert abs(p["payload"]["M"].value - 0.4) < 0.02
    if "valve_lag" in p:
        T = np.array([p["valve_lag"][f"T_{i}"].value for i in range(1, 5)])
        np.testing.assert_allclose(T, 1.5 * NOM_T, rtol=0.10)
    if "joint_friction" in p:
        c = np.array([p["joint_friction"]["c1"].value, p["joint_friction"]["c2"].value])
        np.testing.assert_allclose(c, 3 * np.array(ARM.plant_base.coulomb), rtol=0.35)
    if "polytropic_exponent" in p:
        assert abs(p["polytropic_exponent"]["n"].value - 1.0) < 0.15
    if "valve_dead_time" in p:
        # +-2 samples of 1 ms, compared in whole samples
        assert abs(round(p["valve_dead_time"]["d"].value / 1e-3) - 20) <= 2


@pytest.mark.parametrize("case", ["payload", "dead_time", "friction+dead_time"])
def test_closed_loop_battery_fast_subset(case):
    dg = diagnose(synthesize("closed-loop", CASES[case][0], seed=11, duration=10.0))
    assert outcome(case, dg) == "correct", (case, dg.names, dg.ranking().head())
    check_parameters(case, dg)
    assert not dg.unexplained
    # the gap shrinks in the full simulation on every angle
    for ch in ("q1", "q2"):
        assert dg.residual_rms[ch]["after"] <= dg.residual_rms[ch]["before"]


@pytest.mark.slow
def test_closed_loop_battery_full():
    """Every case, three seeds, two closed-loop experiments: >= 5 of 6 correct per case, and
    the fitted parameters within the tolerances of :func:`check_parameters` in >= 5 of 6 runs
    per case.

    Known limitation, measured and kept visible rather than hidden: the Coulomb coefficients
    fitted from noisy velocities are biased (errors in variables, see
    tests/test_diagnose_battery.py); under PID on the 5 s circle, seed 2, c1 comes out +44 %
    (friction alone) and +47 % (with the dead time) against the 35 % tolerance, i.e. one run
    in six of each friction case.  The test prints every miss.
    """
    rows, misses = {}, {}
    for case, (eff, _) in CASES.items():
        good = 0
        for seed in (1, 2, 3):
            for ref, ctrl in (("circle10", "PSMC joint Ki=2 λ=0.4"), ("circle5", "PID")):
                dg = diagnose(synthesize("closed-loop", eff, seed=seed, duration=10.0,
                                         reference=ref, controller=ctrl))
                o = outcome(case, dg)
                rows.setdefault(case, []).append(o)
                if o == "correct":
                    good += 1
                    try:
                        check_parameters(case, dg)
                    except AssertionError as exc:
                        misses.setdefault(case, []).append(f"{ref} seed {seed}: {exc}")
        assert good >= 5, (case, rows[case])
    for case, lst in misses.items():
        print(f"parameter miss, {case}: {lst}")
    assert all(len(lst) <= 1 for lst in misses.values()), misses
    # only the Coulomb friction bias is known; any other parameter miss is a regression
    assert all(case.startswith("friction") for case in misses), misses


@pytest.mark.slow
def test_sixty_second_closed_loop_record_is_diagnosed_within_a_minute():
    """Issue 10 item 9: a 60 s closed-loop record at 1 kHz against the whole library in
    <= 60 s on 2 cores (benchmarks/bench_diagnose.py measured 9.1 s on the loaded machine)."""
    import time

    rec = synthesize("closed-loop", {"payload_mass": 0.4, "valve_dead_time": 0.02}, seed=1,
                     duration=60.0)
    diagnose(synthesize("closed-loop", seed=1, duration=2.0))      # warm-up (kernels loaded)
    t0 = time.perf_counter()
    dg = diagnose(rec)
    elapsed = time.perf_counter() - t0
    assert set(dg.names) == {"payload", "valve_dead_time"}
    assert elapsed <= 60.0, elapsed
