"""Independent cross-check of the impact engine with pymunk (issue 4, item 5).

The same arm-head impact is built from pymunk bodies, pivots and rotary
springs (:mod:`ppamsafety.impact.pymunk_engine`) and compared with the RK4
main engine (:func:`ppamsafety.impact.model.simulate_impacts`, dt = 10 us).

Acceptance criterion of the issue: F_max and HIC36 agree within 1 %.  At the
pymunk step used here (1 us) the measured differences are 1e-6 .. 5e-4, and
they halve with the step (pymunk's semi-implicit Euler is first order for the
velocity-dependent Hunt-Crossley damping), so the 1 % margin is not what makes
the tests pass; the convergence test checks that the remaining difference is
pymunk's own discretisation error.
"""

import functools

import numpy as np
import pytest

pytest.importorskip("pymunk")

from ppamsafety.impact.model import simulate_impacts  # noqa: E402
from ppamsafety.impact.pymunk_engine import HISTORY_COLUMNS, simulate_impact_pymunk  # noqa: E402
from ppamsafety.params import thesis_arm  # noqa: E402
from ppamsafety.impact.head import head_model  # noqa: E402
from ppamsafety.plant.geometry import jacobian  # noqa: E402
from ppamsafety.units import DEG  # noqa: E402

DT_PYMUNK = 1e-6      # pymunk step [s]
DT_MAIN = 1e-5        # main engine step [s]
RTOL = 0.01           # issue 4, item 5

ARM = thesis_arm()
THESIS = head_model("thesis-frontal")
UNDAMPED = THESIS.replace(name="thesis-frontal-b0", damping=0.0)

# name: (q [deg], joint-velocity direction, tool speed [m/s] (None: qd as given), K, head)
CASES = {
    "step-1.2ms-K43": ((50.0, -80.0), (2.0, 1.0), None, (43.0, 27.0), THESIS),
    "stiff-3ms-K3000": ((90.0, -40.0), (1.0, 0.5), 3.0, (3000.0, 3000.0), THESIS),
    "soft-0.6ms-K1-b0": ((30.0, -120.0), (-1.0, 3.0), 0.6, (1.0, 1.0), UNDAMPED),
    # linear ISO head, undamped stiff arm, 3 kg head
    "iso-0.3ms-K43": ((70.0, -100.0), (-0.5, 1.0), 0.3, (43.0, 27.0),
                      head_model("iso15066-forehead")),
    "stiff-2ms-K3000-b0": ((100.0, -60.0), (1.0, -0.5), 2.0, (3000.0, 3000.0), UNDAMPED),
    "child-1.5ms-K1": ((25.0, -35.0), (1.0, 1.0), 1.5, (1.0, 1.0), head_model("child-frontal")),
}


def _inputs(name):
    qdeg, direction, speed, K, head = CASES[name]
    q = np.array(qdeg) * DEG
    qd = np.array(direction, dtype=float)
    if speed is not None:
        qd = qd * speed / np.linalg.norm(jacobian(q, ARM) @ qd)
    return q, qd, np.array(K), head


@functools.cache
def _main(name):
    q, qd, K, head = _inputs(name)
    return simulate_impacts(ARM, q, qd, K, head=head, dt=DT_MAIN).summary.iloc[0]


@functools.cache
def _pymunk(name, dt=DT_PYMUNK):
    q, qd, K, head = _inputs(name)
    return simulate_impact_pymunk(ARM, q, qd, K, head=head, dt=dt)


def _rel(a, b):
    return abs(a / b - 1.0)


@pytest.mark.parametrize("name", list(CASES))
def test_peak_force_and_hic_agree_with_main_engine(name):
    ref, pm = _main(name), _pymunk(name)
    assert ref.F_max > 50.0 and ref.HIC36 > 0.0          # a real impact
    assert _rel(pm.F_max, ref.F_max) < RTOL
    assert _rel(pm.HIC36, ref.HIC36) < RTOL
    assert _rel(pm.HIC15, ref.HIC15) < RTOL
    assert _rel(pm.delta_max, ref.delta_max) < RTOL
    assert abs(pm.t_Fmax - ref.t_Fmax) < 0.02 * ref.t_Fmax + 2 * DT_MAIN
    assert pm.E_initial == pytest.approx(ref.E_initial, rel=1e-9)
    assert pm.joint_error_max < 1e-6                      # pivots stay closed (< 1 um)
    assert pm.history.F.min() >= 0.0


def test_difference_is_pymunk_discretisation_error():
    """Halving pymunk's step halves the difference (first order) and the Richardson
    extrapolation 2 p(dt/2) - p(dt) meets the main engine to 1e-4."""
    name = "step-1.2ms-K43"
    ref, fine, coarse = _main(name), _pymunk(name), _pymunk(name, 2 * DT_PYMUNK)
    for key in ("F_max", "HIC36"):
        e_fine, e_coarse = getattr(fine, key), getattr(coarse, key)
        err_f, err_c = e_fine / ref[key] - 1.0, e_coarse / ref[key] - 1.0
        assert 1.6 < err_c / err_f < 2.4
        assert _rel(2.0 * e_fine - e_coarse, ref[key]) < 1e-4


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CASES))
def test_difference_halves_again_at_half_step(name):
    """dt = 0.5 us: the difference to the main engine halves again (first-order damped
    cases) or stays at the 1e-6 level of the main engine's own error (undamped cases)."""
    ref, p1, p2 = _main(name), _pymunk(name), _pymunk(name, DT_PYMUNK / 2)
    for key in ("F_max", "HIC36"):
        e1, e2 = _rel(getattr(p1, key), ref[key]), _rel(getattr(p2, key), ref[key])
        assert e2 <= 0.6 * e1 + 5e-6


def _power_bound(hist, dt, K):
    """Energy-error bound of semi-implicit Euler: (dt/2) max |P|, P the conservative power.

    For x_{k+1} = x_k + dt v_k, v_{k+1} = v_k + dt M^-1 f(x_{k+1}) the quantity
    H - (dt/2) v.f is conserved to O(dt^2), so |E_k - E_0| <= (dt/2) max |v.f| + O(dt^2),
    where v.f is the power of the contact (k delta^n d(delta)/dt) and of the joint springs
    (the pivot impulses do no work).  The measured deviation equals this bound within 2 %.
    """
    def rate(col):
        return np.gradient(hist[col].to_numpy(), dt)

    p = (hist.F.to_numpy() * rate("delta") + K[0] * hist.dq1.to_numpy() * rate("dq1")
         + K[1] * hist.dq2.to_numpy() * rate("dq2"))
    return 0.5 * dt * np.max(np.abs(p))


def test_energy_is_conserved_without_damping():
    """b = 0: kinetic + spring + contact energy stays within the symplectic-Euler bound
    (about 1e-4 relative at 1 us during contact) and returns to E0 after the contact."""
    name = "soft-0.6ms-K1-b0"
    pm = _pymunk(name)
    e = pm.history.E_total.to_numpy()
    e0 = e[0]
    dev = np.abs(e - e0).max()
    assert dev <= 1.5 * _power_bound(pm.history, pm.dt, _inputs(name)[2])   # O(dt^2) margin
    assert dev / e0 < 5e-4
    assert pm.history.F.iloc[-1] == 0.0                   # the contact has ended ...
    assert abs(e[-1] / e0 - 1.0) < 1e-5                   # ... and no energy drifted away
    assert pm.E_dissipated == 0.0
    # head momentum gained = arm energy handed over; the head really moved
    assert pm.history.v_head_n.iloc[-1] > 0.1


def test_energy_balance_with_damping():
    """Damped head: energy + contact dissipation stays equal to E0 within the same bound,
    and the dissipation agrees with the main engine's."""
    name = "step-1.2ms-K43"
    pm, ref = _pymunk(name), _main(name)
    bal = pm.history.E_total.to_numpy() + pm.history.E_dissipated.to_numpy()
    assert np.abs(bal - bal[0]).max() <= 1.5 * _power_bound(pm.history, pm.dt, _inputs(name)[2])
    assert _rel(pm.E_dissipated, ref.E_dissipated) < 1e-4


@pytest.mark.parametrize("qdeg, qd, K, duration", [
    ((50.0, -80.0), (2.0, 1.0), (43.0, 27.0), 0.05),
    ((90.0, -40.0), (4.16, 2.08), (3000.0, 3000.0), 0.012),   # ~1/3 of a vibration period
])
def test_free_motion_matches_main_engine(qdeg, qd, K, duration):
    """Head out of reach: the pymunk bodies, pivots and springs reproduce the main
    engine's free arm motion (checks CoG offsets, inertias, spring signs and the
    initial velocities independently of the contact)."""
    q, qd = np.array(qdeg) * DEG, np.array(qd)
    v = jacobian(q, ARM) @ qd
    away = -v / np.linalg.norm(v)            # head behind the tool: the tool moves away
    main = simulate_impacts(ARM, q, qd, K, direction=away, dt=DT_MAIN, duration=duration,
                            history=True).histories[0]
    assert main.F.max() == 0.0               # no contact in the main engine either
    dt = DT_PYMUNK
    pm = simulate_impact_pymunk(ARM, q, qd, K, direction=away, gap=1.0, dt=dt,
                                duration=duration)
    hist = pm.history
    assert list(hist.columns) == HISTORY_COLUMNS and hist.F.max() == 0.0
    idx = np.rint(main.t.to_numpy() / dt).astype(int)
    np.testing.assert_allclose(hist.t.to_numpy()[idx], main.t.to_numpy(), atol=1e-12)
    for col in ("dq1", "dq2"):
        scale = np.abs(main[col]).max()
        assert scale > 0.01                                   # the springs are loaded
        assert np.abs(hist[col].to_numpy()[idx] - main[col].to_numpy()).max() < 1e-4 * scale
    v0 = abs(main.v_tcp_n.iloc[0])
    assert np.abs(hist.v_tcp_n.to_numpy()[idx] - main.v_tcp_n.to_numpy()).max() < 1e-4 * v0
    assert np.abs(hist.E_total / hist.E_total.iloc[0] - 1.0).max() < 1e-4


def test_spring_sign_convention():
    """A deflection-free start with zero speed stays at rest (springs unloaded at t0),
    and a joint-2 velocity loads spring 2 with the right sign: dq2 follows qd2."""
    q = np.array([60.0, -90.0]) * DEG
    rest = simulate_impact_pymunk(ARM, q, (0.0, 0.0), (3000.0, 3000.0), direction=(1.0, 0.0),
                                  gap=1.0, dt=1e-5, duration=0.01)
    assert np.abs(rest.history[["dq1", "dq2"]].to_numpy()).max() < 1e-12
    moving = simulate_impact_pymunk(ARM, q, (0.0, 1.0), (3000.0, 3000.0),
                                    direction=(1.0, 0.0), gap=1.0, dt=1e-6, duration=0.012)
    dq2 = moving.history.dq2.to_numpy()
    # spring 2 must decelerate the joint (omega ~ 190 rad/s): dq2 rises, peaks well below
    # qd2 * t and turns back; a spring of the wrong sign would make it grow without bound
    assert 0.0 < dq2.max() < 0.5 * 1.0 * 0.012
    assert dq2[-1] < 0.8 * dq2.max()


def test_validation():
    q, qd = np.array([50.0, -80.0]) * DEG, np.array([1.0, 0.0])
    with pytest.raises(ValueError, match="dt"):
        simulate_impact_pymunk(ARM, q, qd, (1.0, 1.0), dt=1e-2)
    with pytest.raises(ValueError, match="stiffness"):
        simulate_impact_pymunk(ARM, q, qd, (-1.0, 1.0))
    with pytest.raises(ValueError, match="at rest"):
        simulate_impact_pymunk(ARM, q, (0.0, 0.0), (1.0, 1.0))
    with pytest.raises(ValueError, match="iterations"):
        simulate_impact_pymunk(ARM, q, qd, (1.0, 1.0), iterations=0)
    with pytest.raises(ValueError, match="shape"):
        simulate_impact_pymunk(ARM, np.zeros((2, 2)), qd, (1.0, 1.0))
    with pytest.raises(ValueError, match="unknown head"):
        simulate_impact_pymunk(ARM, q, qd, (1.0, 1.0), head="nobody")
