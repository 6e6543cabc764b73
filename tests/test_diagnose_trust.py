"""Trust in the diagnosis (issue 19): sensor faults, Gram fits, gates, stability, detection limits.

The randomized battery itself (``ppamsafety.diagnose.scenarios``) runs a seeded subset here
and in full behind ``slow`` (``tests/test_diagnose_scenarios.py``).
"""

import math

import numpy as np
import pytest

from ppamsafety.diagnose import diagnose, synthesize
from ppamsafety.diagnose.arm import gates as gates_mod
from ppamsafety.diagnose.arm.candidates import (REGISTRY, SENSOR_FAULTS, SensorFault,
                                                default_candidates, separating_experiment)
from ppamsafety.diagnose.arm.residuals import (ENCODER_OFFSET_COLUMNS, PRESSURE_GAIN_COLUMNS,
                                               PRESSURE_OFFSET_COLUMNS, arm_record, block_system,
                                               channel_noise, model_vector, noise_draws)
from ppamsafety.diagnose.core.result import Estimate
from ppamsafety.diagnose.arm.selection import (fit_model, gram_fit, make_problem,
                                               stability_selection)
from ppamsafety.params import thesis_arm
from ppamsafety.plant import packing

ARM = thesis_arm()
MU0 = model_vector(packing.pack(ARM))


def _residual(data):
    rec, _ = arm_record(data)
    bs = block_system(rec, ARM)
    return bs, bs.y - bs.X @ MU0


@pytest.mark.parametrize("name, value, key, tol", [
    # exact: the offset enters the equations linearly
    ("pressure_sensor_offset", (3000.0, 0.0, -2000.0, 0.0), PRESSURE_OFFSET_COLUMNS, 1e-6),
    # first order in g (the torque columns are exact in g / (1 + g)): 3 % of a 3 % gain
    ("pressure_sensor_gain", (0.03, 0.0, 0.0, -0.02), PRESSURE_GAIN_COLUMNS, 0.04),
    # first order in the offset (central difference): 1 % at 0.01 rad
    ("encoder_offset", (0.01, -0.005), ENCODER_OFFSET_COLUMNS, 0.02),
])
def test_sensor_fault_columns_reproduce_the_fault(name, value, key, tol):
    """On noise-free records, a sensor fault changes the block residual by E(mu0) phi: the
    columns are the fault's signature (relative RMS error per channel within ``tol``)."""
    for exp in ("open-loop", "closed-loop"):
        clean = synthesize(experiment=exp, seed=1, duration=6.0, noise="none")
        fault = synthesize(experiment=exp, effects={name: value}, seed=1, duration=6.0,
                           noise="none")
        _, r0 = _residual(clean)
        bs1, r1 = _residual(fault)
        d = r1 - r0
        pred = bs1.extra[key].at(MU0) @ np.asarray(value, float)
        for c in range(6):
            if np.sqrt(np.mean(d[:, c] ** 2)) > 1e-9 * (1 + np.abs(r0[:, c]).max()):
                err = np.sqrt(np.mean((d[:, c] - pred[:, c]) ** 2)) / np.sqrt(np.mean(d[:, c] ** 2))
                assert err < max(tol, 0.05 if name == "encoder_offset" and c < 4 else tol) \
                    or np.sqrt(np.mean(d[:, c] ** 2)) < 1e-3 * np.sqrt(np.mean(r0[:, c] ** 2)), \
                    (exp, name, c, err)


def _problem(data):
    rec, _ = arm_record(data)
    noise = channel_noise(rec)
    bs = block_system(rec, ARM, velocity_noise=noise["qd"])
    return make_problem(bs, MU0, noise_draws(rec, ARM, noise, velocity_noise=True), ARM)


def test_gram_fits_equal_the_full_design_fits():
    """The per-chunk Gram matrices give the same coefficients and chi2 as least squares on the
    whole design (relative 1e-8), on every subset tried and on half of the chunks."""
    prob = _problem(synthesize(effects={"payload_mass": 0.3}, seed=3, duration=8.0))
    universe = default_candidates()
    rng = np.random.default_rng(0)
    half = rng.random(prob.nchunk) < 0.5
    for names in (["payload"], ["joint_friction", "valve_lag"],
                  ["pressure_sensor_offset", "encoder_offset", "hysteresis"]):
        for chunks in (None, half):
            g = gram_fit(prob, names, universe=universe, chunks=chunks)
            mask = None if chunks is None else half[prob.chunk]
            f = fit_model(prob, names, mask=mask)
            assert math.isclose(g.chi2, f.chi2, rel_tol=1e-8), (names, g.chi2, f.chi2)
            np.testing.assert_allclose(g.phi, f.phi, rtol=1e-6, atol=1e-9 * np.abs(f.phi).max())


@pytest.mark.parametrize("effects, name", [
    ({"pressure_sensor_offset": (8000.0, -5000.0, 0.0, 3000.0)}, "pressure_sensor_offset"),
    ({"pressure_sensor_gain": (0.02, 0.0, -0.03, 0.0)}, "pressure_sensor_gain"),
    ({"encoder_offset": (0.02, -0.01)}, "encoder_offset"),
])
def test_sensor_faults_are_named_with_their_values(effects, name):
    """A sensor fault alone is named, at high confidence, its 95 % intervals covering the
    truth (open loop, 15 s, Table 3.2 noise)."""
    dg = diagnose(synthesize(effects=effects, seed=5, duration=15.0), seed=5)
    assert dg.names == (name,), (dg.names, dg.confounded)
    e = dg.effects[0]
    assert e.confidence_level == "high", e.gates
    truth = list(effects.values())[0]
    for (p, d), t in zip(e.parameters.items(), truth):
        assert d.ci_low <= t <= d.ci_high, (p, d, t)


def test_negative_payload_is_never_named():
    """An out-of-library error that a negative mass would fit (a lighter forearm) never gets a
    payload name: a fit outside the physical range is a symptom, not an effect."""
    data = synthesize(effects={"link.m2": 0.8 * ARM.links.m2}, seed=2, duration=15.0)
    dg = diagnose(data, seed=2)
    for e in dg.effects:
        if e.name == "payload":
            assert e.parameters["M"].ci_low >= 0.0
            assert e.parameters["M"].value > 0.0
    assert all(e.confidence_level != "high" or e.name != "payload" for e in dg.effects)


def _est(value, ci_low, ci_high, nominal, ci_low_raw=None, ci_high_raw=None):
    return Estimate(value=value, unit="-", ci_low=ci_low, ci_high=ci_high, std_error=0.01,
                    nominal=nominal, ci_low_raw=ci_low_raw, ci_high_raw=ci_high_raw)


def test_gate_of_physical_admissibility():
    """The admissibility gate on parameter tables: a moved parameter needs its raw interval in
    the physical range; an unmoved one only must not be significantly outside it."""
    ok = {"M": _est(0.4, ci_low=0.39, ci_high=0.41, nominal=0.0)}
    neg = {"M": _est(-0.3, ci_low=-0.35, ci_high=-0.25, nominal=0.0)}
    straddle = {"M": _est(0.3, ci_low=0.0, ci_high=0.4, ci_low_raw=-0.1, ci_high_raw=0.4,
                          nominal=0.0)}
    assert gates_mod.physically_admissible("payload", ok)
    assert not gates_mod.physically_admissible("payload", neg)
    assert gates_mod.physically_admissible("payload", straddle)        # not moved: consistent
    n_low = {"n": _est(1.05, ci_low=1.0, ci_high=1.12, ci_low_raw=0.98, ci_high_raw=1.12,
                       nominal=1.4)}
    assert not gates_mod.physically_admissible("polytropic_exponent", n_low)   # moved, < 1
    n_ok = {"n": _est(1.2, ci_low=1.15, ci_high=1.25, nominal=1.4)}
    assert gates_mod.physically_admissible("polytropic_exponent", n_ok)
    fr = {"c1": _est(0.5, ci_low=0.45, ci_high=0.55, nominal=0.03),
          "c2": _est(0.07, ci_low=0.06, ci_high=0.08, nominal=0.07),
          "b1": _est(0.83, ci_low=0.8, ci_high=0.86, nominal=0.83),
          "b2": _est(-0.002, ci_low=-0.01, ci_high=0.006, nominal=0.0037)}
    assert gates_mod.physically_admissible("joint_friction", fr)       # b2 = 0 within its CI
    fr["b2"] = _est(-0.2, ci_low=-0.25, ci_high=-0.15, nominal=0.0037)
    assert not gates_mod.physically_admissible("joint_friction", fr)


def test_gates_all_needed_for_high():
    table = {"M": _est(0.4, ci_low=0.39, ci_high=0.41, nominal=0.0)}
    base = dict(weight=0.999, stability=0.95, stability_threshold=0.8, rho=np.ones(6),
                unexplained=False, confounded=False, consistency=0.5, blocks=1000)
    assert gates_mod.level(gates_mod.gates("payload", table, **base)) == "high"
    for change in (dict(weight=0.9), dict(stability=0.5), dict(stability=None),
                   dict(rho=np.r_[np.ones(5), 1.3]), dict(unexplained=True),
                   dict(confounded=True), dict(consistency=1e-5)):
        g = gates_mod.gates("payload", table, **{**base, **change})
        assert gates_mod.level(g) == "low", change
    unmoved = {"M": _est(0.01, ci_low=-0.02, ci_high=0.04, nominal=0.0)}
    assert gates_mod.level(gates_mod.gates("payload", unmoved, **base)) == "low"


def test_stability_selection_and_its_bound():
    """Complementary pairs: frequencies in [0, 1], 2B halves, the Meinshausen-Buehlmann bound
    q^2 / ((2 pi - 1) p); a hidden payload is selected in (nearly) every half."""
    prob = _problem(synthesize(effects={"payload_mass": 0.5}, seed=4, duration=10.0))
    st = stability_selection(prob, default_candidates(), pairs=6, seed=1)
    assert st.pairs == 6 and all(0.0 <= f <= 1.0 for f in st.frequency.values())
    assert st.frequency["payload"] >= 0.9
    assert math.isclose(st.expected_false_bound,
                        st.q ** 2 / ((2 * st.threshold - 1) * st.p))
    d = st.to_dict()
    assert d["halves"] == 12 and "expected_false_selections_bound" in d


def test_detection_limits_are_reported_and_mean_what_they_say():
    """With nothing hidden, nothing is named and every library parameter has a finite limit;
    a payload at 3x its naming limit is named, one at a third of its detection limit is not."""
    data = synthesize(seed=6, duration=10.0)
    dg = diagnose(data, seed=6)
    assert dg.names == () and not dg.confounded
    lim = dg.detection_limits
    assert set(lim) == set(default_candidates())
    for n, ps in lim.items():
        for p, d in ps.items():
            assert d["limit"] > 0 and math.isfinite(d["limit"]), (n, p)
            assert d["limit_named"] >= d["limit"]
    big = diagnose(synthesize(effects={"payload_mass": 3 * lim["payload"]["M"]["limit_named"]},
                              seed=6, duration=10.0), seed=6)
    small = diagnose(synthesize(effects={"payload_mass": lim["payload"]["M"]["limit"] / 3},
                                seed=6, duration=10.0), seed=6)
    assert "payload" in big.names
    assert "payload" not in small.names
    assert "detection_limits" in dg.to_dict()


def test_confounded_pairs_are_reported_not_named():
    """A record that cannot tell two candidates apart reports the pair with the experiment
    that separates them, and names neither (a dead time on a slow closed-loop circle looks
    like a valve lag)."""
    data = synthesize(experiment="closed-loop", reference="circle20",
                      effects={"valve_dead_time": 0.008}, seed=11, duration=12.0)
    dg = diagnose(data, seed=11)
    for g in dg.confounded:
        assert len(g.members) >= 2 and g.separating_experiment
        assert not set(g.members) & set(dg.names)
    assert separating_experiment("valve_offset_gain", "pressure_sensor_offset") \
        == separating_experiment("pressure_sensor_offset", "valve_offset_gain")


def test_sensor_fault_measurement_model_round_trip():
    f = SensorFault(p_offset=(1e3, 0, 0, -2e3), p_gain=(0.02, 0, -0.01, 0), q_offset=(0.01, 0))
    x = np.random.default_rng(0).normal(size=(5, 8)) * 1e5
    np.testing.assert_allclose(f.true_state(f.measure(x)), x, rtol=1e-12, atol=1e-6)
    assert set(SENSOR_FAULTS) <= set(REGISTRY)
