"""Damping-only admittance control around joint PSMC (thesis §5.4.1, §5.4.3, issue 12 item 2).

Closed forms: (5.43) discretised by forward Euler, x_adm[k] - x_adm[k-1] = T f_dz[k]/b
(exact in floating point up to one rounding of the sum), the dead zone of §5.4.3, and
the joint reference q_d = IK(r_d).
"""

import numpy as np
import pytest

from ppamsafety.control import ControllerKind, JointPSMC
from ppamsafety.control.admittance import B_THESIS, AdmittancePSMC
from ppamsafety.control.estimation import ESTIMATOR_INTERNALS, ForceEstimator
from ppamsafety.experiments import ExperimentCase, run_batch
from ppamsafety.experiments import trajectories as tr
from ppamsafety.params import thesis_arm
from ppamsafety.plant import geometry as geo
from ppamsafety.plant.model import rest_state

DT = 1e-3
Q0 = np.radians([50.0, -80.0])


@pytest.fixture(scope="module")
def arm():
    return thesis_arm()


@pytest.fixture(scope="module")
def ref(arm):
    return tr.joint_steps(arm, q_levels=[Q0], t_changes=[], duration=3.0)


@pytest.fixture(scope="module")
def pushed(arm, ref):
    """A 10 N push in +x from 1 s to 1.4 s (moves the set point < 0.1 m, inside the
    reachable annulus), perfect estimator model."""
    f = np.zeros((ref.n_steps, 2))
    f[1000:1400, 0] = 10.0
    case = ExperimentCase(arm, AdmittancePSMC(), ref, external_force=f,
                          estimator=ForceEstimator(model=arm.plant_base))
    return run_batch([case], dt=DT)[0]


def test_admittance_gets_a_default_estimator(arm, ref):
    c = ExperimentCase(arm, AdmittancePSMC(), ref)
    assert isinstance(c.estimator, ForceEstimator)
    assert AdmittancePSMC().kind == ControllerKind.ADMITTANCE
    assert B_THESIS == 40.0


def test_desired_position_integrates_force_over_b(pushed):
    """(5.43): x_adm[k] - x_adm[k-1] = T Fx_dz[k] / b, to 1e-12 m per sample."""
    x = pushed.signals("x_adm", "y_adm")
    f = pushed.signals("Fx_dz", "Fy_dz")
    step = np.diff(x, axis=0)
    np.testing.assert_allclose(step, DT * f[1:] / B_THESIS, rtol=0, atol=1e-12)
    # the push moved the set point in +x: 10 N x 0.4 s / 40 N s/m = 0.1 m at most, less
    # the estimator lag and the dead zone; bound 0.05 m
    assert x[-1, 0] - x[0, 0] > 0.05
    # ... and the arm followed it (within 3 cm at the end, 1.6 s after the push)
    r = pushed.signals("x", "y")
    assert np.linalg.norm(r[-1] - x[-1]) < 0.03


def test_dead_zone_in_the_loop(pushed):
    """Estimated forces within F_min = 3 N never move the set point (§5.4.3)."""
    est = pushed.signals("Fx_mo", "Fy_mo")
    fdz = pushed.signals("Fx_dz", "Fy_dz")
    small = np.hypot(est[:, 0], est[:, 1]) <= 3.0
    assert small.any() and (~small).any()
    assert np.all(fdz[small] == 0.0)
    assert np.all(fdz[~small] == est[~small])


def test_huge_dead_zone_gives_joint_psmc(arm, ref):
    """With F_min beyond any estimate the admittance is its inner joint PSMC: the joint
    reference is IK(FK(q_d)) = q_d up to round-off, so the motion agrees to 1e-8 rad."""
    x0 = rest_state(np.radians([45.0, -75.0]), arm)[0]          # start off the set point
    runs = run_batch([ExperimentCase(arm, AdmittancePSMC(f_min=1e4), ref, x0=x0),
                      ExperimentCase(arm, JointPSMC(), ref, x0=x0)], dt=DT)
    np.testing.assert_allclose(runs[0].signals("q1", "q2"), runs[1].signals("q1", "q2"),
                               rtol=0, atol=1e-8)
    assert np.all(runs[0].signals("Fx_dz", "Fy_dz") == 0.0)


def test_python_step_reads_the_estimate(arm):
    """Controller.step with a given estimator row: 2 N (inside the dead zone) leaves the
    set point, 20 N moves it by T f / b (closed form) in one step."""
    r0 = geo.forward_kinematics(Q0, arm)
    row = np.zeros(12)
    row[0:2] = Q0
    row[8:10] = r0
    p = np.full(4, 2e5)
    fe = np.zeros(ESTIMATOR_INTERNALS.size)
    for f, moved in ((2.0, 0.0), (20.0, DT * 20.0 / B_THESIS)):
        c = AdmittancePSMC(source="rls")
        fe[:] = 0.0
        fe[ESTIMATOR_INTERNALS.offset("f_rls")] = f
        c.step(arm, Q0, np.zeros(2), p, row, f_est=fe)
        x_adm = c.internals[AdmittancePSMC.INTERNALS.offset("r_adm")]
        assert x_adm - r0[0] == pytest.approx(moved, abs=1e-15)


@pytest.mark.parametrize("kw, exc, match", [
    ({"b": 0.0}, ValueError, "AdmittancePSMC.b"),
    ({"b": -40.0}, ValueError, "AdmittancePSMC.b"),
    ({"f_min": -1.0}, ValueError, "AdmittancePSMC.f_min"),
    ({"source": "force sensor"}, ValueError, "AdmittancePSMC.source"),
    ({"psmc": "joint"}, TypeError, "AdmittancePSMC.psmc"),
])
def test_argument_validation(kw, exc, match):
    with pytest.raises(exc, match=match):
        AdmittancePSMC(**kw)
