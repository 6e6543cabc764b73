"""Dynamic identification (thesis §3.5.2, B.3-B.7) and excitation design (§3.5.2.4).

Data: the plant simulated open loop (:func:`ppamsafety.plant.model.simulate`) under a
5-harmonic 10 s Fourier Delta-p excitation, starting at the equilibrium of Delta p(0);
torques from the simulated pressures through the torque functions (2.17).

Friction: the plant has smooth Coulomb friction c tanh(qd/v_s) (v_s = 0.01 rad/s) plus
viscous friction; the noise-free tests identify with the same smooth sign in the regressor
(``sign_velocity=arm.friction_velocity``), so the 10-parameter model is exact.

Discretisation error: the bilinear filter makes omega (W1 - <W1>_F) the filtered
*trapezoidal* derivative of H qd; against the filtered exact K(q, qd, qdd) theta it differs
by the trapezoid-rule error, O((w T)^2/12).  Measured: max 6e-6 N m at T = 1 ms (torques
~3 N m RMS), scaling as T^2.  So the 1e-6-relative recovery is checked on a record sampled
at T = 0.1 ms (error / 100), and the thesis' 1 kHz record with the T^2-scaled tolerance.
"""

import math
import time

import numpy as np
import pandas as pd
import pytest

from ppamsafety.identify import dynamic as dy
from ppamsafety.identify import excitation as ex
from ppamsafety.plant import dynamics as pdyn


def _theta(arm):
    b = arm.plant_base
    return np.concatenate([b.as_vector(), b.coulomb, b.viscous])


@pytest.fixture(scope="module")
def excitation(arm):
    rng = np.random.default_rng(0)
    k = np.arange(1, 6)[:, None]
    return ex.FourierExcitation(a=rng.normal(size=(5, 2)) * 3e4 / k, b=rng.normal(size=(5, 2)) * 3e4 / k,
                                offset=ex.default_offset(arm))


@pytest.fixture(scope="module")
def excitation2(arm):
    rng = np.random.default_rng(1)
    k = np.arange(1, 6)[:, None]
    return ex.FourierExcitation(a=rng.normal(size=(5, 2)) * 3e4 / k, b=rng.normal(size=(5, 2)) * 3e4 / k,
                                offset=ex.default_offset(arm))


@pytest.fixture(scope="module")
def data_1khz(arm, excitation):
    return ex.simulate_excitation(arm, excitation, periods=1, dt=1e-3, substeps=2, name="ES 1")


@pytest.fixture(scope="module")
def data_10khz(arm, excitation):
    return ex.simulate_excitation(arm, excitation, periods=1, dt=1e-4, substeps=1, name="ES 1 fine")


# -- regressors against the plant's own H, C, G, friction (independent code paths) -----------

def test_regressors_match_plant_dynamics(arm, data_1khz):
    d = data_1khz
    base, th = arm.plant_base, _theta(arm)
    sv = arm.friction_velocity
    W1, W2, W3 = dy.w_matrices(d.q, d.qd, arm, sign_velocity=sv)
    H = pdyn.inertia_matrix(d.q, arm, params=base)
    np.testing.assert_allclose(W1 @ th, np.einsum("nij,nj->ni", H, d.qd), rtol=1e-12, atol=1e-13)
    h = 1e-6                                          # dH/dt = dH/dq2 qd2 (H depends on q2 only)
    dq = np.array([0.0, h])
    dH = (pdyn.inertia_matrix(d.q + dq, arm, params=base) - pdyn.inertia_matrix(d.q - dq, arm, params=base)) / (2 * h)
    Hdot_qd = np.einsum("nij,nj->ni", dH * d.qd[:, 1, None, None], d.qd)
    np.testing.assert_allclose(W2 @ th, Hdot_qd, rtol=0, atol=1e-8)
    C = pdyn.coriolis(d.q, d.qd, arm, params=base)
    w3 = np.einsum("nij,nj->ni", C, d.qd) + pdyn.gravity(d.q, arm, params=base) + pdyn.friction(d.qd, arm, params=base)
    np.testing.assert_allclose(W3 @ th, w3, rtol=1e-12, atol=1e-12)
    # the full regressor reproduces the plant torques exactly (same ODE)
    K = dy.regressor(d.q, d.qd, d.qdd, arm, sign_velocity=sv)
    np.testing.assert_allclose(K @ th, d.tau, rtol=0, atol=1e-11)
    # without friction: the first six columns
    np.testing.assert_array_equal(dy.regressor(d.q, d.qd, d.qdd, arm, friction=False),
                                  dy.regressor(d.q, d.qd, d.qdd, arm)[..., :6])


# -- the filter --------------------------------------------------------------------------------

def test_filter_is_bilinear_first_order(arm):
    from scipy.signal import bilinear
    dt, w = 1e-3, dy.FILTER_OMEGA
    b, a = dy.filter_coefficients(dt)
    bb, aa = bilinear([w], [1.0, w], fs=1 / dt)
    np.testing.assert_allclose(b, bb, rtol=1e-14)
    np.testing.assert_allclose(a, aa, rtol=1e-14)
    assert dy.FILTER_OMEGA == pytest.approx(10 * math.pi)   # 5 Hz, §3.5.2.2
    # unit DC gain
    assert b.sum() / a.sum() == pytest.approx(1.0, rel=1e-14)


def test_discrete_identity_is_exact():
    """omega (y - <y>_F) equals <Tustin derivative of y>_F to machine precision."""
    from scipy.signal import lfilter
    dt, w = 1e-3, dy.FILTER_OMEGA
    y = np.random.default_rng(3).normal(size=5000).cumsum()
    b, a = dy.filter_coefficients(dt)
    lhs = w * (y - dy.filter_signal(y, dt))
    rhs = lfilter(b[0] * 2 / dt * np.array([1.0, -1.0]), a, y)   # F(z) * (2/T)(1 - z^-1)/(1 + z^-1)
    np.testing.assert_allclose(lhs, rhs, rtol=0, atol=1e-10 * np.abs(lhs).max())


@pytest.mark.parametrize("which, tol", [("data_1khz", 2e-5), ("data_10khz", 2e-7)])
def test_filtered_regressor_equals_filtered_model(arm, which, tol, request):
    """K_f theta == lfilter(F, K(q, qd, qdd) theta); tolerance = trapezoid error, scaling T^2."""
    d = request.getfixturevalue(which)
    th, sv = _theta(arm), arm.friction_velocity
    ref = dy.filter_signal(dy.regressor(d.q, d.qd, d.qdd, arm, sign_velocity=sv) @ th, d.dt)
    Kf = dy.filtered_regressor(d.q, d.qd, d.dt, arm, sign_velocity=sv)
    err = np.abs(Kf @ th - ref).max()
    assert err <= tol * np.sqrt(np.mean(ref ** 2)), err


# -- noise-free recovery -------------------------------------------------------------------------

def test_noise_free_recovery_10khz(arm, data_10khz):
    """All parameters to 1e-6 relative except b2 = 0.0037 N m s/rad, which contributes < 2e-3 N m
    of torque: its absolute error (measured 2.3e-7) is held to 1e-6 N m s/rad."""
    th = _theta(arm)
    r = dy.identify_dynamic(data_10khz, arm, sign_velocity=arm.friction_velocity, drop=3000)
    rel = np.abs(r.estimates - th) / np.abs(th)
    assert np.all(rel[:9] < 1e-6), rel
    assert abs(r.estimates[9] - th[9]) < 1e-6


def test_noise_free_recovery_1khz_thesis_rate(arm, data_1khz):
    """At the thesis' 1 kHz the T^2 discretisation error is 100x that at 10 kHz: 1e-4 relative."""
    th = _theta(arm)
    r = dy.identify_dynamic(data_1khz, arm, sign_velocity=arm.friction_velocity)
    rel = np.abs(r.estimates - th) / np.abs(th)
    assert np.all(rel[:9] < 1e-4), rel
    assert abs(r.estimates[9] - th[9]) < 1e-4


def test_frictionless_model_on_frictionless_plant(arm, excitation):
    plant = arm.replace(links=arm.links.replace(coulomb=(0.0, 0.0), viscous=(0.0, 0.0)))
    d = ex.simulate_excitation(plant, excitation, periods=1, dt=1e-4, substeps=1)
    r = dy.identify_dynamic(d, plant, friction=False, drop=3000)
    assert r.estimates.size == 6 and r.theta[6:].tolist() == [0.0] * 4
    np.testing.assert_allclose(r.estimates, plant.plant_base.as_vector(), rtol=1e-6)
    base = r.to_base_parameters()
    assert base.IS2 == pytest.approx(plant.plant_base.IS2, rel=1e-6)


# -- noisy data, LS vs WLS, validation (Table 3.4 layout) ---------------------------------------

def _noisy(d, seed, name):
    """Table 3.2 noise (first signal): q, qd, and the torque variances 1.82e-3, 1.01e-3 N^2 m^2."""
    rng = np.random.default_rng(seed)
    sq = np.sqrt([3.46e-6, 2.59e-6])
    sv = np.sqrt([1.63e-4, 2.32e-5])
    st = np.sqrt([1.82e-3, 1.01e-3])
    n = len(d)
    return dy.DynamicData(q=d.q + rng.normal(size=(n, 2)) * sq, qd=d.qd + rng.normal(size=(n, 2)) * sv,
                          tau=d.tau + rng.normal(size=(n, 2)) * st, dt=d.dt, name=name, qdd=d.qdd)


def test_ls_wls_and_validation_table(arm, excitation, excitation2, data_1khz):
    es1 = _noisy(ex.simulate_excitation(arm, excitation, periods=2, dt=1e-3), 1, "ES 1")
    vs1 = _noisy(ex.simulate_excitation(arm, excitation2, periods=1, dt=1e-3), 2, "VS 1")
    sv = arm.friction_velocity
    ls = dy.identify_dynamic(es1, arm, sign_velocity=sv)
    wls = dy.identify_dynamic(es1, arm, sign_velocity=sv, method="WLS")
    nof = dy.identify_dynamic(es1, arm, friction=False)
    th = _theta(arm)
    # Errors in variables (thesis §3.5.2.6: "biased due to noise in K_f, mainly from q-dot"):
    # the unfiltered term omega W1 carries the velocity noise times omega = 31 rad/s, comparable
    # to the filtered accelerations, so the inertial columns are attenuated.  Measured on this
    # record: theta3 -93 %, theta6 -25 %, gravity terms theta1 +3.1 %, theta4 -1.2 %.  The
    # same direction as the thesis' physically impossible theta3 = 0.0181 kg m^2 (Table 3.5).
    for r in (ls, wls):
        np.testing.assert_allclose(r.estimates[[0, 3]], th[[0, 3]], rtol=5e-2)
        assert r.estimates[2] < 0.5 * th[2]                     # attenuated inertia
    assert wls.method.startswith("WLS") and ls.method.startswith("LS")
    # filtered-torque residual per joint is of the filtered noise order (Table 3.3: ~1e-2 N m)
    assert np.all(ls.joint_sigma > 1e-3) and np.all(ls.joint_sigma < 0.1)
    table = dy.validation_table({"Friction (LS)": ls, "Friction (WLS)": wls, "Frictionless (LS)": nof},
                                [es1, vs1], arm)
    assert list(table.index) == ["ES 1", "VS 1", "Average"]
    assert table.attrs["self_validation"] == [("ES 1", c) for c in table.columns]
    # Average excludes the self-validation: equals the VS 1 row here
    np.testing.assert_allclose(table.loc["Average"].to_numpy(), table.loc["VS 1"].to_numpy())
    # errors are at least the torque noise ((1.82e-3 + 1.01e-3)/2 = 1.4e-3) and well below the thesis' 0.05
    assert np.all(table.to_numpy() > 1e-3) and np.all(table.to_numpy() < 0.05)
    # the plant has friction: the model with friction predicts better on the validation set
    assert table.loc["VS 1", "Friction (LS)"] < table.loc["VS 1", "Frictionless (LS)"]
    # with exact accelerations and noise-free data the error is tiny
    exact = dy.identify_dynamic(data_1khz, arm, sign_velocity=sv)
    t2 = dy.validation_table({"exact": exact}, [data_1khz], arm, use_true_qdd=True)
    assert t2.loc["ES 1", "exact"] < 1e-10 and np.isnan(t2.loc["Average", "exact"])


def test_result_object(arm, data_1khz):
    from matplotlib.figure import Figure
    r = dy.identify_dynamic(data_1khz, arm, sign_velocity=arm.friction_velocity)
    df = r.to_pandas()
    assert list(df.index) == list(dy.DYNAMIC_NAMES)
    assert df["unit"].tolist()[2] == "kg m^2" and df["unit"].tolist()[-1] == "N m s/rad"
    assert r.std_errors.shape == (10,) and np.all(r.std_errors >= 0)
    assert 1 < r.condition_number < 1e6
    assert isinstance(r.plot(), Figure)
    assert r.datasets == ("ES 1",)


def test_multiple_records_are_stacked(arm, data_1khz):
    th = _theta(arm)
    r = dy.identify_dynamic([data_1khz, data_1khz], arm, sign_velocity=arm.friction_velocity)
    Kf, tf = dy.filtered_system([data_1khz, data_1khz], arm)
    assert Kf.shape == (2 * (len(data_1khz) - dy.DROP_SAMPLES), 2, 10)
    assert np.all(np.abs(r.estimates - th) / np.abs(th) < [1e-4] * 9 + [1e-1])


# -- excitation ------------------------------------------------------------------------------------

def test_fourier_excitation(arm, excitation):
    t = np.linspace(0, 20, 2001)
    dp = excitation.delta_p(t)
    np.testing.assert_allclose(dp[:1001], dp[1000:], atol=1e-6)            # 10 s periodic
    np.testing.assert_allclose(dp.mean(axis=0), excitation.offset, atol=1.0 + 1e-3 * np.abs(dp).max())
    assert np.all(np.abs(dp - excitation.offset) <= excitation.amplitude_bound + 1e-9)
    u = excitation.set_values(t, arm)
    assert u.shape == (2001, 4) and np.all(u >= 0) and np.all(u <= arm.pneumatics.p_max)
    x = excitation.to_vector()
    e2 = ex.FourierExcitation.from_vector(x, excitation.offset)
    np.testing.assert_array_equal(e2.a, excitation.a)
    assert excitation.to_pandas().shape == (5, 4)


def test_equilibrium_start(arm, excitation):
    q0 = ex.equilibrium_for(excitation.delta_p([0.0])[0], arm)
    from ppamsafety.plant.pneumatics import gravity_compensation
    np.testing.assert_allclose(gravity_compensation(q0, arm, params=arm.plant_base),
                               excitation.delta_p([0.0])[0], atol=1e-6)


def test_design_excitation_small_budget(arm):
    t0 = time.perf_counter()
    d = ex.design_excitation(arm, n_random=4, maxfev=6, seed=1)
    elapsed = time.perf_counter() - t0
    assert d.evaluations == 4 + 6 + 1 or d.evaluations <= 4 + 6 + 2
    assert d.condition_number <= d.initial_condition_number + 1e-9
    assert np.isfinite(d.condition_number) and d.condition_number >= 1
    assert d.excitation.harmonics == 5 and d.excitation.period == 10.0
    assert d.feasible
    assert np.all(d.max_velocity <= ex.VELOCITY_LIMIT) and np.all(d.max_acceleration <= ex.ACCELERATION_LIMIT)
    g = arm.geometry
    assert g.q1_min <= d.q_range[0, 0] and d.q_range[0, 1] <= g.q1_max
    assert g.q2_min <= d.q_range[1, 0] and d.q_range[1, 1] <= g.q2_max
    assert isinstance(d.to_pandas(), pd.DataFrame)
    # seeded: same result again
    d2 = ex.design_excitation(arm, n_random=4, maxfev=6, seed=1)
    np.testing.assert_array_equal(d2.excitation.a, d.excitation.a)
    print(f"design_excitation (10 simulations x 20 s): {elapsed:.2f} s")


# -- speed -----------------------------------------------------------------------------------------

def test_speed_200k_samples(arm, data_1khz):
    """20 periods of 10 s at 1 kHz = 200 000 samples x 2 joints (thesis §3.5.2.4)."""
    d = data_1khz
    big = dy.DynamicData(q=np.tile(d.q, (20, 1)), qd=np.tile(d.qd, (20, 1)), tau=np.tile(d.tau, (20, 1)),
                         dt=d.dt, name="20 periods")
    assert len(big) == 200_000
    t0 = time.perf_counter()
    r = dy.identify_dynamic(big, arm, sign_velocity=arm.friction_velocity, method="WLS")
    elapsed = time.perf_counter() - t0
    print(f"identify_dynamic WLS, 200 000 samples: {elapsed:.2f} s")
    assert r.lsq.measured.size == 2 * (200_000 - dy.DROP_SAMPLES)
    assert elapsed < 20.0          # a few seconds on an idle core; generous for a shared machine


# -- input validation ------------------------------------------------------------------------------

def test_bad_inputs(arm, data_1khz):
    d = data_1khz
    with pytest.raises(ValueError, match="DynamicData.tau"):
        dy.DynamicData(q=d.q, qd=d.qd, tau=d.tau[:-1], dt=d.dt)
    bad = d.q.copy()
    bad[5, 1] = np.nan
    with pytest.raises(ValueError, match="DynamicData.q contains NaN"):
        dy.DynamicData(q=bad, qd=d.qd, tau=d.tau, dt=d.dt)
    with pytest.raises(ValueError, match="DynamicData.dt"):
        dy.DynamicData(q=d.q, qd=d.qd, tau=d.tau, dt=-1.0)
    with pytest.raises(TypeError, match="data"):
        dy.identify_dynamic(d.q, arm)
    with pytest.raises(ValueError, match="method"):
        dy.identify_dynamic(d, arm, method="ML")
    with pytest.raises(ValueError, match="drop"):
        dy.identify_dynamic(d, arm, drop=len(d))
    short = dy.DynamicData(q=d.q[:305], qd=d.qd[:305], tau=d.tau[:305], dt=d.dt)
    with pytest.raises(ValueError, match="too few"):
        dy.identify_dynamic(short, arm)
    with pytest.raises(ValueError, match="excite"):     # at rest: no inertial information
        rest = dy.DynamicData(q=np.tile(d.q[:1], (2000, 1)), qd=np.zeros((2000, 2)),
                              tau=np.tile(d.tau[:1], (2000, 1)), dt=d.dt)
        dy.identify_dynamic(rest, arm, friction=False, method="WLS")
    with pytest.raises(ValueError, match="omega"):
        dy.filter_coefficients(1e-3, omega=1e5)
    with pytest.raises(ValueError, match="sign_velocity"):
        dy.regressor(d.q, d.qd, d.qd, arm, sign_velocity=-1.0)
    with pytest.raises(ValueError, match="a and b"):
        ex.FourierExcitation(a=np.zeros((5, 2)), b=np.zeros((4, 2)), offset=(0, 0))
    with pytest.raises(TypeError, match="excitation"):
        ex.simulate_excitation(arm, "fourier")
