"""Static identification (thesis §3.5.1): muscle (3.8)-(3.11), valves (3.12), gravity (3.13)-(3.16).

Synthetic data come from the plant (:func:`ppamsafety.identify.static.static_experiment`):
31 equilibria (§3.5.1.4) held by the plant's exact static pressures, one reading each.

Noise used (seeded, independent, zero-mean Gaussian), and why:
* muscle forces F1..F4: Table 3.2 variances (0.51, 1.02, 0.59, 0.45 N^2), the
  thesis' own measurement noise of the force sensors;
* joint angles: Table 3.2 variances (3.46e-6, 2.59e-6 rad^2); contractions and
  the torques (3.17) are computed from the noisy angles, as on the rig;
* pressures: 500 Pa (5 mbar) standard deviation; the thesis tabulates no
  pressure noise, this is a typical transducer figure (0.17 % of 3 bar).

Coverage of the 95 % intervals: every interval is an independent Bernoulli(0.95)
trial only approximately (errors in variables; the 4 gravity intervals of one seed
are correlated), so the acceptance bands are binomial bands with margin:
* slow battery, 60 seeds: 240 gravity / 1200 muscle / 480 valve intervals,
  band [90 %, 99 %] (the brief's band; binomial sd <= 1.4 %, i.e. > 3.5 sd);
* fast battery, 20 seeds: 80 gravity / 400 muscle / 160 valve intervals;
  binomial sd 2.4 % / 1.1 % / 1.7 %, band [85 %, 100 %] for gravity (4 sd),
  [90 %, 99 %] for muscle and valves (>= 3.5 sd below, 3.6 sd above).
"""

import numpy as np
import pandas as pd
import pytest

from ppamsafety.identify import static as st
from ppamsafety.identify.lsq import LSQResult


@pytest.fixture(scope="module")
def configs(arm):
    return st.equilibrium_configurations(arm, 31, seed=0)


@pytest.fixture(scope="module")
def exact(arm, configs):
    return st.static_experiment(arm, configs, noise=False)


def _true_muscle(arm, k):
    return np.array(arm.muscles.groups[k].coefficients)


def _true_valve(arm, k):
    v = arm.valves.valves[k]
    return np.array([v.v1, v.v2])


# -- noise-free recovery (tolerance 1e-6 relative, the brief; LS on exact data is exact to
#    ~1e-12 times the condition number) -------------------------------------------------------

def test_configurations_are_31_holdable_points_in_working_area(arm, configs):
    from ppamsafety.plant.geometry import in_working_area
    assert configs.shape == (31, 2)
    assert in_working_area(configs, arm).all()
    assert st._holdable(configs, arm).all()
    # spread over the area: both joints span more than half their range
    g = arm.geometry
    assert np.ptp(configs[:, 0]) > 0.5 * (g.q1_max - g.q1_min)
    assert np.ptp(configs[:, 1]) > 0.5 * (g.q2_max - g.q2_min)


def test_gravity_noise_free_recovers_plant(arm, exact):
    res = st.identify_gravity(exact.q, exact.tau, gravity_acc=arm.gravity)
    true = st.true_gravity_parameters(arm.plant_base)
    np.testing.assert_allclose(res.estimates, true, rtol=1e-6, atol=0)
    assert res.residual_rms < 1e-10


def test_gravity_from_pressures_equals_from_forces(arm, exact):
    """tau by (2.17) from pressures equals tau by (3.17) from forces for exact data."""
    from ppamsafety.plant.torque import joint_torques
    tau_p = joint_torques(exact.q, exact.pressures, arm)
    np.testing.assert_allclose(tau_p, exact.tau, rtol=1e-10, atol=1e-12)


def test_muscle_noise_free_recovers_table_b1(arm, exact):
    for k in range(4):
        res = st.identify_muscle(exact.forces[:, k], exact.pressures[:, k], exact.contractions[:, k])
        np.testing.assert_allclose(res.estimates, _true_muscle(arm, k), rtol=1e-6, atol=0)


def test_valves_noise_free_recover_table_b2(arm, exact):
    res = st.identify_valves(exact.set_values, exact.pressures)
    for k in range(4):
        np.testing.assert_allclose(res[k].estimates, _true_valve(arm, k), rtol=1e-6, atol=0)


def test_gravity_base_parameters_roundtrip(arm, exact):
    res = st.identify_gravity(exact.q, exact.tau)
    base = st.gravity_base_parameters(res, arm.model)
    assert base.IS2 == arm.model.IS2
    assert base.m2LG2 == pytest.approx(arm.plant_base.m2LG2, rel=1e-6)
    with pytest.raises(TypeError, match="template"):
        st.gravity_base_parameters(res, "model")


# -- noisy data: reported intervals and their coverage ----------------------------------------

def _coverage(arm, configs, seeds):
    true_g = st.true_gravity_parameters(arm.plant_base)
    cg, cm, cv = [], [], []
    for s in seeds:
        ex = st.static_experiment(arm, configs, seed=int(s))
        cg.append(st.identify_gravity(ex.q, ex.tau).covers(true_g))
        for k in range(4):
            cm.append(st.identify_muscle(ex.forces[:, k], ex.pressures[:, k],
                                         ex.contractions[:, k]).covers(_true_muscle(arm, k)))
        for k, r in enumerate(st.identify_valves(ex.set_values, ex.pressures)):
            cv.append(r.covers(_true_valve(arm, k)))
    return np.mean(cg), np.mean(cm), np.mean(cv)


def test_noisy_reports_intervals(arm, configs):
    ex = st.static_experiment(arm, configs, seed=123)
    res = st.identify_gravity(ex.q, ex.tau)
    df = res.to_pandas()
    assert list(df.columns) == ["estimate", "std_error", "ci_low", "ci_high", "unit"]
    assert list(df.index) == list(st.GRAVITY_NAMES)
    assert np.all(df["ci_low"] < df["estimate"]) and np.all(df["estimate"] < df["ci_high"])
    assert np.all(res.std_errors > 0)
    # sigma of the torque equations near the noise put in: Table 3.2 gives tau variances
    # 1.82e-3 / 1.01e-3 N^2 m^2 (sd 0.043 / 0.032 N m); forces and angles here give the same order
    assert 0.01 < res.sigma < 0.1
    # the t quantile: half-width / SE = t_{0.975, 58} = 2.0017 (tables)
    np.testing.assert_allclose((res.ci_high - res.estimates) / res.std_errors, 2.0017, rtol=1e-4)


def test_coverage_fast_20_seeds(arm, configs):
    g, m, v = _coverage(arm, configs, range(1000, 1020))
    assert 0.85 <= g <= 1.0, g
    assert 0.90 <= m <= 0.99, m
    assert 0.90 <= v <= 0.99, v


@pytest.mark.slow
def test_coverage_60_seeds(arm, configs):
    g, m, v = _coverage(arm, configs, range(2000, 2060))
    for c in (g, m, v):
        assert 0.90 <= c <= 0.99, (g, m, v)


def test_joint_weighting_runs_and_agrees(arm, configs):
    ex = st.static_experiment(arm, configs, seed=5)
    ls = st.identify_gravity(ex.q, ex.tau)
    wls = st.identify_gravity(ex.q, ex.tau, weighting="joint")
    assert wls.method.startswith("WLS")
    # both unbiased estimates of the same thing: agree within 3 combined SEs
    assert np.all(np.abs(ls.estimates - wls.estimates) < 3 * (ls.std_errors + wls.std_errors))


# -- result object ---------------------------------------------------------------------------

def test_result_object(arm, exact):
    res = st.identify_muscle(exact.forces[:, 0], exact.pressures[:, 0], exact.contractions[:, 0])
    assert isinstance(res, LSQResult)
    assert res["a0"] == pytest.approx(_true_muscle(arm, 0)[0], rel=1e-6)
    with pytest.raises(KeyError, match="a9"):
        res["a9"]
    assert res.ci.shape == (5, 2)
    assert res.condition_number > 1
    df = res.to_pandas()
    assert isinstance(df, pd.DataFrame) and set(df["unit"]) == {"N/Pa"}
    assert isinstance(st.static_experiment(arm, np.array([[1.0, -1.4]]), noise=False).to_pandas(),
                      pd.DataFrame)


def test_plot_returns_figure(arm, configs):
    from matplotlib.figure import Figure
    ex = st.static_experiment(arm, configs, seed=1)
    fig = st.identify_gravity(ex.q, ex.tau).plot()
    assert isinstance(fig, Figure) and len(fig.axes) == 2


# -- input validation ------------------------------------------------------------------------

def test_bad_inputs(arm, exact):
    F, p, e = exact.forces[:, 0], exact.pressures[:, 0], exact.contractions[:, 0]
    with pytest.raises(ValueError, match="force"):
        st.identify_muscle(F[:-1], p, e)
    with pytest.raises(ValueError, match="contraction"):
        st.identify_muscle(F, p, np.where(np.arange(e.size) == 3, 0.0, e))
    bad = p.copy()
    bad[2] = np.nan
    with pytest.raises(ValueError, match="pressure contains NaN"):
        st.identify_muscle(F, bad, e)
    with pytest.raises(TypeError, match="force"):
        st.identify_muscle("abc", p, e)
    with pytest.raises(ValueError, match="too few"):
        st.identify_muscle(F[:5], p[:5], e[:5])
    with pytest.raises(ValueError, match="tau"):
        st.identify_gravity(exact.q, exact.tau[:, :1])
    with pytest.raises(ValueError, match="q"):
        st.identify_gravity(exact.q[:, 0], exact.tau)
    with pytest.raises(ValueError, match="weighting"):
        st.identify_gravity(exact.q, exact.tau, weighting="huber")
    with pytest.raises(ValueError, match="rank deficient|excite"):
        # all points at one configuration cannot separate the 4 parameters
        st.identify_gravity(np.repeat(exact.q[:1], 10, axis=0), np.repeat(exact.tau[:1], 10, axis=0))
    with pytest.raises(ValueError, match="confidence"):
        st.identify_valve(exact.set_values[:, 0], exact.pressures[:, 0], confidence=1.5)
    with pytest.raises(ValueError, match="cannot be held"):
        st.static_experiment(arm, np.array([[0.0, 0.0]]))
