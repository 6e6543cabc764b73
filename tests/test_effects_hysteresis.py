"""Muscle force hysteresis (3.31)-(3.35) in the plant, and the valve dead time (issue 9).

Hysteresis: with delta = 0 the hysteretic plant is bitwise the nominal one;
the branch structure, rate independence and dissipation that (3.35) predicts
are checked on the plant itself (``plant.model.simulate`` and the plant's
own factor kernel ``plant.model.hysteresis_factors``).
"""

import math

import numpy as np
import pytest

from ppamsafety.hysteresis import DELTA_25_FIBRES, EPS_MAX, initial_memory, preisach_response, w_fit
from ppamsafety.hysteresis.memory import STATE_LENGTH
from ppamsafety.hysteresis.memory import history_of_memory
from ppamsafety.params.effects import Effects
from ppamsafety.plant import layout as lay
from ppamsafety.plant import packing
from ppamsafety.plant import model
from ppamsafety.units import BAR, DEG

DELTA = (DELTA_25_FIBRES,) * 4            #: thesis §3.6.5, 25-fibre muscles
Q0 = np.array([50.0 * DEG, -60.0 * DEG])  #: a configuration inside the working area


def _hyst(arm, delta=DELTA, **more):
    return arm.replace(effects=Effects(hysteresis_delta=delta, **more))


def _sine_inputs(arm, period, n_periods=1.0, amp=0.6 * BAR, dt=1e-3):
    """Set values moving joint 2 (and 1, at a third of the amplitude) slowly up and down."""
    x0, u0 = model.rest_state(Q0, arm)
    t = np.arange(int(round(n_periods * period / dt))) * dt
    s = np.sin(2 * np.pi * t / period)
    U = np.tile(u0, (t.size, 1))
    U[:, 0] += amp / 3 * s
    U[:, 1] -= amp / 3 * s
    U[:, 2] += amp * s
    U[:, 3] -= amp * s
    return x0, U


# --- validation, packing ----------------------------------------------------------------------
def test_effects_validation_names_the_field():
    with pytest.raises(ValueError, match=r"hysteresis_delta\[1\].*outside \[0, 1\]"):
        Effects(hysteresis_delta=(0.1, 1.5, 0.1, 0.1))
    with pytest.raises(ValueError, match="hysteresis_delta must have 4 entries"):
        Effects(hysteresis_delta=(0.1, 0.1))
    with pytest.raises(ValueError, match="hysteresis_initial"):
        Effects(hysteresis_delta=DELTA, hysteresis_initial="up")
    with pytest.raises(ValueError, match="saturation value"):
        Effects(hysteresis_delta=DELTA, hysteresis_initial=(0.2, 0.5))
    with pytest.raises(ValueError, match=r"\[-1, 1\]"):
        Effects(hysteresis_delta=DELTA, hysteresis_initial=(-1.0, 1.5))
    with pytest.raises(ValueError, match="valve_dead_time\\[2\\] = 101"):
        Effects(valve_dead_time=(0, 0, 101, 0))
    with pytest.raises(ValueError, match="integer"):
        Effects(valve_dead_time=(0, 0.5, 1, 0))
    with pytest.raises(TypeError, match="valve_dead_time"):
        Effects(valve_dead_time=3)
    # the initial memory is an option of the hysteresis, not an effect
    assert not Effects(hysteresis_initial="positive").any


def test_pack_hysteresis_and_dead_time(arm):
    P = packing.pack(_hyst(arm, valve_dead_time=(0, 2, 5, 1)))
    read = lay.PLANT.read
    assert read(P, "hysteresis_mode") == lay.Switch.ON and read(P, "dead_time_mode") == lay.Switch.ON
    np.testing.assert_array_equal(read(P, "hysteresis_delta"), DELTA)
    assert read(P, "hysteresis_eps_max") == EPS_MAX == 0.35
    np.testing.assert_array_equal(read(P, "hysteresis_wfit"), w_fit())
    np.testing.assert_array_equal(read(P, "hysteresis_initial"), np.tile(initial_memory(), 4))
    assert read(P, "dead_time_length") == 6
    assert read(P, "effect_state_length") == lay.EFFECT_STATE.size + 4 * 6
    with pytest.raises(ValueError, match="pack-time effect"):
        packing.with_effects(P, hysteresis_delta=0.2)
    # controller views ignore the plant effects
    np.testing.assert_array_equal(packing.controller_view(_hyst(arm)), packing.controller_view(arm))


def test_initial_memory_options(arm):
    hist = (-1.0, 0.6, -0.3, 0.2)
    for init, rows in (("positive", [initial_memory("positive")] * 4),
                       (hist, [initial_memory(hist)] * 4),
                       ((hist, (1.0, -0.5), (-1.0,), (1.0,)),
                        [initial_memory(h) for h in (hist, (1.0, -0.5), (-1.0,), (1.0,))])):
        P = packing.pack(_hyst(arm, hysteresis_initial=init))
        z = model.initial_effect_state(P)[0]
        np.testing.assert_array_equal(z[lay.Z_HYST:lay.Z_HYST + 4 * STATE_LENGTH],
                                      np.concatenate(rows))
        # cached outputs = the operator's output at the stored input
        for k, r in enumerate(rows):
            w = preisach_response(np.array([r[1]]), state=r)[0]
            assert z[lay.Z_HYST_W + k] == w
    # a memory row round-trips through its history exactly (a saved state can be restarted)
    u = np.concatenate([np.linspace(-1, 0.7, 50), np.linspace(0.7, -0.4, 40),
                        np.linspace(-0.4, 0.1, 20)])
    _, row = preisach_response(u, return_state=True)
    np.testing.assert_array_equal(initial_memory(history_of_memory(row)), row)


# --- hysteresis: nominal equivalence ----------------------------------------------------------
def test_delta_zero_is_bitwise_the_nominal_plant(arm):
    x0, U = _sine_inputs(arm, period=2.0, n_periods=1.0)
    X0 = model.simulate(arm, x0, U)
    X1 = model.simulate(_hyst(arm, delta=(0.0,) * 4), x0, U)
    np.testing.assert_array_equal(X1, X0)
    # and with hysteresis on, the trajectory does change (the test above can fail)
    X2 = model.simulate(_hyst(arm), x0, U)
    assert np.max(np.abs(X2[:, :2] - X0[:, :2])) > 0.1 * DEG


def test_hysteresis_off_row_is_bitwise_nominal(arm):
    """Every new effect field at its default: the packed row is the nominal one."""
    P = packing.pack(arm.replace(effects=Effects(hysteresis_initial="positive")))
    np.testing.assert_array_equal(P, packing.pack(arm))
    assert lay.PLANT.read(P, "effect_state_length") == 0


# --- hysteresis: branch structure, rate independence, dissipation --------------------------------
@pytest.fixture(scope="module")
def quasi_static_loop(arm):
    """A slow (20 s) open-loop cycle of joint 2 after a first rise, hysteresis on."""
    a = _hyst(arm)
    x0, U = _sine_inputs(a, period=20.0, n_periods=1.25)
    X = model.simulate(a, x0, U)
    eps, fac = model.hysteresis_factors(X, a)
    return a, X, eps, fac


def test_force_branches_follow_3_35(quasi_static_loop):
    """(3.35) with the Preisach output: contracting -> force below the model, extending -> above.

    From the thesis' initial state (negative saturation) the memory follows the
    ascending major branch while eps rises, where W < W_fit for eps_s below
    ~0.9 (fig. 3.12); after a reversal the descending branch lies above the
    ascending one.  So (i) on the first rise of a group's contraction the
    factor is < 1 (force lower than the model, thesis §3.5.1.6: "if
    contraction increases, the output force is lower than predicted"), and
    (ii) at equal contraction the falling branch is above the rising one.
    """
    _, X, eps, fac = quasi_static_loop
    # the first sample is a rise from the saturated memory (eps_s = -1) to eps(x0)
    assert np.all(fac[0] < 1.0)
    first_risers = 0
    for k in (2, 3):                               # the groups of joint 2
        de = np.diff(eps[:, k], prepend=eps[0, k])
        rising, falling = de > 1e-7, de < -1e-7
        if eps[5000, k] > eps[0, k]:               # (i) this group contracts first
            first_risers += 1
            quarter = slice(0, 5000)               # up to the first extremum of the input
            assert np.all(2 * eps[quarter, k] / EPS_MAX - 1 < 0.9)
            assert np.all(fac[quarter, k] < 1.0), k
        # (ii) on the closed loop from the first extremum (t = 5 s) on, at equal
        # contraction the falling-branch factor is above the rising-branch one
        loop = np.arange(eps.shape[0]) >= 5000
        lo, hi = np.percentile(eps[loop, k], [20, 80])
        grid = np.linspace(lo, hi, 7)
        r, f = rising & loop, falling & loop
        f_rise = np.interp(grid, *_sorted(eps[r, k], fac[r, k]))
        f_fall = np.interp(grid, *_sorted(eps[f, k], fac[f, k]))
        assert np.all(f_fall > f_rise), (k, f_rise, f_fall)
    assert first_risers == 1                       # antagonists: one contracts, one extends


def _sorted(x, y):
    o = np.argsort(x)
    return x[o], y[o]


def test_plant_loop_is_rate_independent(arm):
    """The plant's factor-vs-eps loop is (nearly) the same at period 20 s and 40 s.

    The closed loop of a period (from the first maximum down to the minimum
    and back) is compared at equal contraction.  The Preisach factor is a
    function of the contraction path only; what can differ between the two
    time scales is the path itself (the dynamic lag of the valves, T ~ 0.1 s,
    and of the arm behind the quasi-static equilibrium: relative size
    ~ T/period <= 0.5 %, halved at 40 s) and the registration of the turning
    points at the end of a 0.5 ms RK4 step (~ 1e-4 of the stroke).  So the
    two loops must agree to a small fraction of their width: 5 % of the
    largest falling-minus-rising gap (a 20x margin on the 0.25 % lag bound
    relative to the gap of ~1.4 % of the force; measured: 0.9 %).
    """
    a = _hyst(arm)
    loops = []
    for period in (20.0, 40.0):
        x0, U = _sine_inputs(a, period=period, n_periods=1.25, dt=1e-3)
        X = model.simulate(a, x0, U)
        eps, fac = model.hysteresis_factors(X, a)
        n4 = int(round(period / 4 / 1e-3))           # the first maximum of the set values
        e, f = eps[n4:, 2], fac[n4:, 2]
        de = np.diff(e, prepend=e[0])
        lo, hi = np.percentile(e, [20, 80])
        grid = np.linspace(lo, hi, 9)
        r, fl = de > 0, de < 0
        loops.append((np.interp(grid, *_sorted(e[r], f[r])),
                      np.interp(grid, *_sorted(e[fl], f[fl]))))
    (r20, f20), (r40, f40) = loops
    gap = f20 - r20
    assert np.all(gap > 0)                            # an open loop: falling above rising
    tol = 0.05 * gap.max()
    assert np.max(np.abs(r40 - r20)) < tol
    assert np.max(np.abs(f40 - f20)) < tol


def test_factor_is_exactly_rate_independent_on_a_resampled_path(arm):
    """Same contraction path sampled twice as densely: identical factors at the common samples.

    The turning points lie on both grids, so the Preisach memories see the
    same extrema: the factors agree to rounding (prefix sums are the same
    operations), whatever the sampling rate.
    """
    a = _hyst(arm)
    n = 400
    s = np.linspace(0.0, 2.0, 2 * n + 1)            # two periods, extrema on both grids
    q2 = Q0[1] + 15 * DEG * np.sin(np.pi * s) * np.exp(-0.3 * s)
    X = np.zeros((s.size, 8))
    X[:, 0], X[:, 1] = Q0[0], q2
    _, f_fine = model.hysteresis_factors(X, a)
    _, f_coarse = model.hysteresis_factors(X[::2], a)
    np.testing.assert_allclose(f_coarse, f_fine[::2], rtol=0, atol=1e-15)


def test_passive_cycle_dissipates_energy(arm):
    """Closed valves, no friction: a slow external torque cycle costs work only with hysteresis.

    With the valves closed the gas is polytropic (conservative), friction
    is set to zero, gravity is conservative: without hysteresis the work of
    the external torque over a slow out-and-back cycle is ~0 (only the
    kinetic-energy / oscillation residue); with hysteresis the muscles take
    in more work while extended than they return while contracting (forces
    higher on the extending branch, (3.35)), so the cycle work is > 0.
    """
    fx = dict(valve_time_constant=(math.inf,) * 4, friction_coulomb=(0.0, 0.0),
              friction_viscous=(0.0, 0.0))
    dt, period = 1e-3, 10.0
    t = np.arange(int(period / dt)) * dt
    tau = np.zeros((t.size, 2))
    tau[:, 1] = 2.0 * np.sin(np.pi * t / period) ** 2      # N m, out and back on joint 2
    works = {}
    for name, a in (("nominal", arm.replace(effects=Effects(**fx))),
                    ("hysteresis", arm.replace(effects=Effects(hysteresis_delta=DELTA, **fx)))):
        x0, u0 = model.rest_state(Q0, arm)
        X = model.simulate(a, x0, np.tile(u0, (t.size, 1)), dt=dt, tau_ext=tau)
        qd = 0.5 * (X[:-1, 2:4] + X[1:, 2:4])                # midpoint velocity per interval
        works[name] = float(np.sum(tau * qd) * dt)
        amplitude = np.ptp(X[:, 1])
        assert amplitude > 2 * DEG                           # the cycle really moves the joint
    assert works["hysteresis"] > 0.0
    assert abs(works["nominal"]) < 0.1 * works["hysteresis"], works


# --- valve dead time --------------------------------------------------------------------------
def test_dead_time_delays_a_step_by_exactly_d_periods(arm):
    d = (0, 1, 3, 7)
    a = arm.replace(effects=Effects(valve_dead_time=d))
    x0, u0 = model.rest_state(Q0, arm)
    for i, di in enumerate(d):
        U = np.tile(u0, (40, 1))
        U[10:, i] += 0.2 * BAR                            # a step of valve i at k = 10
        X = model.simulate(a, x0, U)
        shifted = U.copy()
        shifted[10 + di:, i] = U[10, i]
        shifted[:10 + di, i] = U[0, i]
        np.testing.assert_array_equal(X, model.simulate(arm, x0, shifted))
        # the valve's pressure starts to move exactly d periods after the step
        moved = np.nonzero(np.abs(X[:, 4 + i] - X[0, 4 + i]) > 1.0)[0]
        assert moved[0] == 10 + di + 1
    # zero delays everywhere: bitwise nominal
    X0 = model.simulate(arm.replace(effects=Effects(valve_dead_time=(0,) * 4)), x0, U)
    np.testing.assert_array_equal(X0, model.simulate(arm, x0, U))


def test_dead_time_state_continues_a_run(arm):
    a = arm.replace(effects=Effects(valve_dead_time=(2, 2, 2, 2)))
    x0, u0 = model.rest_state(Q0, arm)
    U = np.tile(u0, (30, 1))
    U[5:] += 0.1 * BAR
    X, z = model.simulate(a, x0, U, return_effect_state=True)
    X1, z1 = model.simulate(a, x0, U[:12], return_effect_state=True)
    X2 = model.simulate(a, X1[-1], U[12:], effect_state=z1)
    np.testing.assert_array_equal(np.vstack([X1, X2[1:]]), X)


def test_hysteresis_state_continues_a_run(arm):
    a = _hyst(arm)
    x0, U = _sine_inputs(a, period=1.0, n_periods=1.0)
    X, z = model.simulate(a, x0, U, return_effect_state=True)
    X1, z1 = model.simulate(a, x0, U[:400], return_effect_state=True)
    X2 = model.simulate(a, X1[-1], U[400:], effect_state=z1)
    np.testing.assert_array_equal(np.vstack([X1, X2[1:]]), X)
    with pytest.raises(ValueError, match="Preisach memories"):
        model.simulate(a, x0, U[:5], effect_state=np.zeros_like(z))


def test_secant_stages_agree_with_exact_peeks(arm):
    """The fast stage scheme (secant of the last step) vs preisach_peek at every stage.

    The secant error in a stage's W is O(dv^2) (dv the stage's change of
    eps_s from the step start, <= 1e-3 here), i.e. ~1e-6 in W, 1e-7 in
    the force factor; over a 2 s loop it must stay far below the
    hysteresis effect itself (the difference to delta = 0): < 1e-3 of it.
    """
    x0, U = _sine_inputs(arm, period=2.0, n_periods=1.0)
    X_nom = model.simulate(arm, x0, U)
    X_sec = model.simulate(_hyst(arm), x0, U)
    X_ex = model.simulate(_hyst(arm, hysteresis_exact_stages=True), x0, U)
    effect = np.max(np.abs(X_ex[:, :2] - X_nom[:, :2]))
    assert effect > 0.1 * DEG
    assert np.max(np.abs(X_sec[:, :2] - X_ex[:, :2])) < 1e-3 * effect
    with pytest.raises(TypeError, match="hysteresis_exact_stages"):
        Effects(hysteresis_delta=DELTA, hysteresis_exact_stages=1)
