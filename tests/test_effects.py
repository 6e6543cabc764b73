"""Optional plant effects (issue 9): payload, truth-vs-model parameters, per-row batches.

Every effect is off by default and then changes nothing (bitwise); each one
is checked against a closed form or an invariant.
"""

import math

import numpy as np
import pytest

from ppamsafety.params import ArmParameters
from ppamsafety.params.effects import EffectKind, Effects
from ppamsafety.plant import dynamics as dyn
from ppamsafety.plant import packing
from ppamsafety.plant import geometry as geo
from ppamsafety.plant import layout as lay
from ppamsafety.plant import model, torque
from ppamsafety.units import BAR

RNG = np.random.default_rng(20260109)
M_P = 1.3                                  #: payload mass of the tests [kg] (< 2 kg, §2.3.3.5)

#: Truth overrides used below (values inside the ranges of params/effects.py).
TRUTH = Effects(friction_coulomb=(0.1, 0.2), friction_viscous=(0.3, 0.05),
                valve_offset=(0.05 * BAR, -0.03 * BAR, 0.0, 0.02 * BAR),
                valve_gain=(0.95, 1.04, 1.0, 0.9), valve_time_constant=(0.02, 0.03, 0.08, 0.01),
                polytropic_n=1.2)


def _with(arm, **effects):
    return arm.replace(effects=Effects(**effects))


# --- defaults, validation, views ------------------------------------------------------------
def test_default_is_off_and_the_row_is_bitwise_nominal(arm):
    assert arm.effects == Effects() and not arm.effects.any and arm.effects.enabled() == ()
    P = packing.pack(arm)
    for a in (arm.replace(effects=Effects()), _with(arm, payload_mass=0.0)):
        np.testing.assert_array_equal(packing.pack(a), P)
    assert lay.PLANT.read(P, "effect_state_length") == 0.0
    assert not any(np.any(v) for v in packing.plant_effects(P).values())
    np.testing.assert_array_equal(P[lay.EFFECTS_START:], lay.EFFECTS.empty())


def test_effects_change_only_the_plant_truth_view(arm):
    """Controller / model views (and the Python-level valve data) keep the nominal values."""
    fx = TRUTH.replace(payload_mass=M_P)
    a = arm.replace(effects=fx)
    # every parameter-only effect (the effects with state: tests/test_effects_hysteresis.py)
    assert set(fx.enabled()) == set(Effects.names(EffectKind.PARAMETER))
    np.testing.assert_array_equal(packing.controller_view(a), packing.controller_view(arm))
    np.testing.assert_array_equal(packing.model_view(a), packing.model_view(arm))
    P, P0 = packing.pack(a), packing.pack(arm)
    read = lay.PLANT.read
    np.testing.assert_array_equal(read(P, "coulomb"), fx.friction_coulomb)
    np.testing.assert_array_equal(read(P, "viscous"), fx.friction_viscous)
    np.testing.assert_array_equal(read(P, "v1"), fx.valve_offset)
    np.testing.assert_array_equal(read(P, "v2"), fx.valve_gain)
    np.testing.assert_array_equal(read(P, "tv"), fx.valve_time_constant)
    assert read(P, "n_poly") == fx.polytropic_n and read(P, "payload_mass") == M_P
    # the flags on are those the parameter effects set, each alone (nothing else is on)
    on = {k for k, v in packing.plant_effects(P).items() if v}
    alone = set()
    for name in Effects.names(EffectKind.PARAMETER):
        Pn = packing.pack(_with(arm, **{name: getattr(fx, name)}))
        alone |= {k for k, v in packing.plant_effects(Pn).items() if v}
    assert on == alone and len(on) >= 6
    assert int(P[lay.PAYLOAD_MODE]) == lay.Switch.ON
    # nothing else moved: geometry, muscles, pressures, theta2 (the link-1 offset)
    others = [f.name for f in lay.PLANT.fields if f.name not in
              ("coulomb", "viscous", "v1", "v2", "tv", "n_poly", "theta")
              and f.name not in lay.PACK_TIME_EFFECTS]
    for name in others:
        np.testing.assert_array_equal(read(P, name), read(P0, name), err_msg=name)
    assert P[lay.THETA2] == P0[lay.THETA2]
    # one override alone sets only its own flag
    P1 = packing.pack(_with(arm, valve_gain=fx.valve_gain))
    flags = packing.plant_effects(P1)
    assert flags["valve_gain_mode"] and sum(bool(v) for v in flags.values()) == 1
    np.testing.assert_array_equal(read(P1, "v1"), read(P0, "v1"))


@pytest.mark.parametrize("kwargs, match", [
    (dict(payload_mass=-0.1), "payload_mass"),
    (dict(payload_mass=5.5), "payload_mass"),
    (dict(payload_mass=math.nan), "payload_mass"),
    (dict(friction_coulomb=(0.1, -0.1)), r"friction_coulomb\[1\]"),
    (dict(friction_viscous=(0.1, 0.2, 0.3)), "friction_viscous must have 2"),
    (dict(valve_offset=(0.0, 0.0, 0.6 * BAR, 0.0)), r"valve_offset\[2\]"),
    (dict(valve_gain=(1.0, 1.0, 1.0, 1.6)), r"valve_gain\[3\]"),
    (dict(valve_time_constant=(0.06, 5e-4, 0.06, 0.06)), r"valve_time_constant\[1\]"),
    (dict(valve_time_constant=(0.06, 0.06, 0.06, 11.0)), r"valve_time_constant\[3\]"),
    (dict(polytropic_n=1.5), "polytropic_n"),
    (dict(polytropic_n=0.9), "polytropic_n"),
])
def test_effects_are_validated(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Effects(**kwargs)


def test_effects_type_errors(arm):
    with pytest.raises(TypeError, match="payload_mass"):
        Effects(payload_mass=True)
    with pytest.raises(TypeError, match="valve_gain"):
        Effects(valve_gain=1.0)
    with pytest.raises(TypeError, match="ArmParameters.effects"):
        arm.replace(effects={"payload_mass": 1.0})
    # closed valves are allowed, and sequences become hashable tuples (pack is cached)
    fx = Effects(valve_time_constant=[math.inf] * 4, friction_coulomb=np.zeros(2))
    assert fx.valve_time_constant == (math.inf,) * 4 and hash(fx) == hash(fx.replace())
    assert isinstance(arm.replace(effects=fx), ArmParameters)


def test_with_effects_rejects_pack_time_effects(arm):
    for name in lay.PACK_TIME_EFFECTS:
        with pytest.raises(ValueError, match="ArmParameters.effects"):
            packing.with_effects(packing.pack(arm), **{name: 1.0})


# --- payload ----------------------------------------------------------------------------------
def test_payload_is_the_parallel_axis_change_of_theta(arm):
    g = arm.geometry
    d = lay.PLANT.read(packing.pack(_with(arm, payload_mass=M_P)), "theta") - \
        lay.PLANT.read(packing.pack(arm), "theta")
    expect = M_P * np.array([g.L1, 0.0, g.L1 ** 2, g.LL, g.dL, g.LL ** 2 + g.dL ** 2])
    np.testing.assert_allclose(d, expect, rtol=1e-13, atol=1e-16)


def _A(q, P):
    return np.array(geo.load_point(float(q[0]), float(q[1]), P))


def _jacobian(q, P, h=1e-3):
    """dA_L/dq by central differences with one Richardson step (error O(h^4) ~ 1e-12)."""
    def D(s):
        return np.stack([(_A(q + s * e, P) - _A(q - s * e, P)) / (2 * s) for e in np.eye(2)],
                        axis=1)
    return (4 * D(h / 2) - D(h)) / 3


def _velocity_product_acceleration(q, qd, P, h=4e-2):
    """d^2/ds^2 A_L(q + s qd) at s = 0 (= Jdot qd) by second differences.

    Along the unit direction d = qd/|qd| (then times |qd|^2), with two Richardson steps
    over the spacings h/2, h, 2h: truncation O(h^6), round-off ~ 4 eps |A| / (h/2)^2;
    measured against the closed form: < 1e-11 for |qd| <= 5 rad/s.
    """
    n = float(np.linalg.norm(qd))
    d = qd / n

    def D2(s):
        return (_A(q + s * d, P) - 2 * _A(q, P) + _A(q - s * d, P)) / s ** 2

    r1 = (4 * D2(h / 2) - D2(h)) / 3
    r2 = (4 * D2(h) - D2(2 * h)) / 3
    return (16 * r1 - r2) / 15 * n * n


def test_payload_dynamics_equal_the_point_mass_lagrangian(arm):
    """H, C qd, G with payload - nominal = those of a point mass M at A_L (A.21).

    Point mass: T = 1/2 M |J qd|^2, U = M g y_A, so H_p = M J^T J, G_p = M g dy_A/dq and
    C_p qd = M J^T (Jdot qd), J = dA_L/dq taken numerically from the geometry kernel
    ``load_point`` (independent of the base-parameter formulas of plant/dynamics.py).
    Tolerance 1e-10 (H [kg m^2], G [N m], C qd [N m]).
    """
    a = _with(arm, payload_mass=M_P)
    P = packing.pack(arm)
    q = RNG.uniform([0.3, -2.2], [1.8, -0.5], size=(12, 2))
    qd = RNG.normal(scale=1.5, size=(12, 2))
    dH = dyn.inertia_matrix(q, a) - dyn.inertia_matrix(q, arm)
    dG = dyn.gravity(q, a) - dyn.gravity(q, arm)
    dCqd = (np.einsum("nij,nj->ni", dyn.coriolis(q, qd, a), qd)
            - np.einsum("nij,nj->ni", dyn.coriolis(q, qd, arm), qd))
    dU = dyn.potential_energy(q, a) - dyn.potential_energy(q, arm)
    for n in range(len(q)):
        J = _jacobian(q[n], P)
        np.testing.assert_allclose(dH[n], M_P * J.T @ J, rtol=0, atol=1e-10)
        np.testing.assert_allclose(dG[n], M_P * arm.gravity * J[1], rtol=0, atol=1e-10)
        acc = _velocity_product_acceleration(q[n], qd[n], P)
        np.testing.assert_allclose(dCqd[n], M_P * J.T @ acc, rtol=0, atol=1e-10)
        # the potential is M g y_A (up to the same constant as the links': zero here)
        np.testing.assert_allclose(dU[n], M_P * arm.gravity * _A(q[n], P)[1], rtol=0,
                                   atol=1e-12)
    assert np.abs(dH).max() > 0.05 and np.abs(dG).max() > 3.0      # the payload is felt


@pytest.mark.parametrize("gravity", [0.0, 9.81])
def test_free_motion_with_payload_conserves_energy(arm, gravity):
    """Closed valves, no friction (both set through the truth overrides), payload on.

    E = T + U + sum_i [(P_atm + p_i) V_i/(n - 1) + P_atm V_i] is conserved (as in
    tests/test_dynamics.py, here with the payload in T and U and the overridden n);
    RK4 at h = 0.25 ms resolves it to 1e-6 of E and 1e-5 of the initial kinetic energy.
    """
    fx = Effects(payload_mass=M_P, friction_coulomb=(0.0, 0.0), friction_viscous=(0.0, 0.0),
                 valve_time_constant=(math.inf,) * 4, polytropic_n=1.25)
    a = arm.replace(gravity=gravity, effects=fx)
    x0, u = model.rest_state(np.radians([50, -80]), a)
    x0[2:4] = [2.0, -3.0]
    X = model.simulate(a, x0, np.tile(u, (2000, 1)), dt=1e-3, substeps=4)
    q, qd, p = X[:, :2], X[:, 2:4], X[:, 4:]
    V = torque.group_volumes(q, a)
    patm = a.pneumatics.p_atm
    gas = ((patm + p) * V / (fx.polytropic_n - 1) + patm * V).sum(axis=1)
    KE = dyn.kinetic_energy(q, qd, a)
    E = KE + gas + dyn.potential_energy(q, a)
    assert KE.max() - KE.min() > 0.2 * KE[0]
    assert np.abs(E - E[0]).max() / abs(E[0]) < 1e-6
    assert np.abs(E - E[0]).max() / KE[0] < 1e-5
    # the payload is really in the kinetic energy: the nominal arm's H gives less
    assert np.all(dyn.kinetic_energy(q, qd, arm) < KE)


def test_rest_state_holds_the_plant_truth(arm):
    """rest_state with payload and valve-truth overrides is an equilibrium of that plant."""
    a = arm.replace(effects=TRUTH.replace(payload_mass=M_P))
    q = np.radians([50, -80])
    x0, u = model.rest_state(q, a)
    dx = model.state_derivative(x0, u, a)
    np.testing.assert_allclose(dx[2:4], 0.0, atol=1e-10)        # rad/s^2
    np.testing.assert_allclose(dx[4:], 0.0, atol=1e-6)          # Pa/s (p ~ 1e5 Pa)
    # ...and the nominal rest state is not: the payload pulls the arm down
    x0n, un = model.rest_state(q, arm)
    assert np.abs(model.state_derivative(x0n, un, a)[2:4]).max() > 1.0


# --- truth overrides: closed forms -----------------------------------------------------------
def test_valve_and_friction_overrides_closed_forms(arm):
    a = arm.replace(effects=TRUTH)
    fx = TRUTH
    # valves (3.2), (3.12): at qd = 0 the volume term vanishes, pd = (v1 + v2 u - p)/T
    x = np.concatenate([np.radians([50, -80]), [0.0, 0.0], [1.2, 0.8, 1.5, 0.6]]) * \
        np.r_[1, 1, 1, 1, BAR, BAR, BAR, BAR]
    u = np.array([2.0, 0.5, 1.0, 2.5]) * BAR
    pd = model.state_derivative(x, u, a)[4:]
    expect = (np.array(fx.valve_offset) + np.array(fx.valve_gain) * u - x[4:]) / \
        np.array(fx.valve_time_constant)
    np.testing.assert_allclose(pd, expect, rtol=1e-13)
    # friction (3.30), smooth Coulomb as in the plant
    qd = RNG.normal(scale=0.5, size=(20, 2))
    vs = a.friction_velocity
    np.testing.assert_allclose(dyn.friction(qd, a),
                               np.array(fx.friction_coulomb) * np.tanh(qd / vs)
                               + np.array(fx.friction_viscous) * qd, rtol=1e-14, atol=1e-15)
    # the controllers' friction is still the identified one (Table 3.5)
    np.testing.assert_array_equal(dyn.friction(qd, a, params=a.model),
                                  dyn.friction(qd, arm, params=arm.model))


def test_polytropic_override_scales_the_closed_valve_pressure_rate(arm):
    """Closed valves: pd_i = -n (P_atm + p_i) m_tau,i qd_j / V_i (3.6) is linear in n."""
    closed = dict(valve_time_constant=(math.inf,) * 4)
    x = np.concatenate([np.radians([50, -80]), [0.7, -1.1], np.array([1.2, 0.8, 1.5, 0.6]) * BAR])
    u = np.zeros(4)
    pd_nom = model.state_derivative(x, u, _with(arm, **closed))[4:]
    pd_iso = model.state_derivative(x, u, _with(arm, polytropic_n=1.0, **closed))[4:]
    assert arm.pneumatics.polytropic_n == 1.4
    np.testing.assert_allclose(pd_iso, pd_nom / 1.4, rtol=1e-13)
    assert np.all(np.abs(pd_nom) > 1e3)


def test_valve_time_constant_must_exceed_the_integration_step(arm):
    a = _with(arm, valve_time_constant=(1e-3, 0.06, 0.06, 0.06))
    x0, u = model.rest_state(np.radians([50, -80]), arm)
    X = model.simulate(a, x0, np.tile(u, (5, 1)), dt=1e-3, substeps=2)   # h = 0.5 ms: fine
    assert np.all(np.isfinite(X))
    with pytest.raises(ValueError, match=r"row 0 valve 1 time constant 0.001 s"):
        model.simulate(a, x0, np.tile(u, (5, 1)), dt=4e-3, substeps=2)   # h = 2 ms > T


# --- per batch row ---------------------------------------------------------------------------
def test_mixed_effects_batch_equals_separate_runs_bitwise(arm):
    arms = [arm, _with(arm, payload_mass=M_P), arm.replace(effects=TRUTH),
            _with(arm, polytropic_n=1.0, valve_gain=(1.05, 1.0, 0.95, 1.0))]
    x0, u = model.rest_state(np.radians([50, -80]), arm)
    U = np.tile(u, (300, 1))
    U[100:] += np.array([0.3, -0.3, 0.2, -0.2]) * BAR          # a step excites everything
    batch = model.simulate(arms, x0, U)
    assert batch.shape == (4, 301, 8)
    for b, a in enumerate(arms):
        np.testing.assert_array_equal(batch[b], model.simulate(a, x0, U))
    # the rows really differ (each effect changes the response)
    for b in range(1, 4):
        assert np.abs(batch[b] - batch[0]).max() > 1e-3


# --- joint torque bias (a stateless effect the kernels read) ---------------------------------
BIAS = (0.8, -0.5)                         #: constant joint torques of the tests [N m]


def test_torque_bias_is_the_kernel_kind_and_only_the_plant_sees_it(arm):
    assert Effects.kind("joint_torque_bias") is EffectKind.KERNEL
    a = _with(arm, joint_torque_bias=BIAS)
    np.testing.assert_array_equal(packing.controller_view(a), packing.controller_view(arm))
    P = packing.pack(a)
    assert int(P[lay.TORQUE_BIAS_MODE]) == lay.Switch.ON
    np.testing.assert_array_equal(lay.PLANT.read(P, "torque_bias"), BIAS)
    assert lay.PLANT.read(P, "effect_state_length") == 0.0          # stateless: no z


def test_torque_bias_accelerates_the_arm_by_the_inverse_inertia(arm):
    """From the nominal rest state the bias is the only unbalanced torque: H qdd = b (3.1)."""
    q = np.radians([50, -80])
    x0, u = model.rest_state(q, arm)
    a = _with(arm, joint_torque_bias=BIAS)
    qdd = model.state_derivative(x0, u, a)[2:4]
    expect = np.linalg.solve(dyn.inertia_matrix(q, arm), np.array(BIAS))
    np.testing.assert_allclose(qdd, expect, rtol=1e-10, atol=1e-12)
    assert np.abs(qdd).min() > 0.1                                   # rad/s^2: really moves


def test_torque_bias_equilibrium_is_held_by_the_muscles(arm):
    """rest_state of the biased plant balances gravity minus the bias (the shared kernel)."""
    q = np.radians([50, -80])
    a = _with(arm, joint_torque_bias=BIAS)
    x0, u = model.rest_state(q, a)
    np.testing.assert_allclose(model.state_derivative(x0, u, a)[2:4], 0.0, atol=1e-10)
    X = model.simulate(a, x0, np.tile(u, (200, 1)))                  # 0.2 s at rest
    np.testing.assert_allclose(X[-1, :2], q, atol=1e-9)
    # the muscles of the biased plant hold a different pressure difference
    assert np.abs(x0[4:] - model.rest_state(q, arm)[0][4:]).max() > 100.0    # Pa


@pytest.mark.parametrize("value, match", [((25.0, 0.0), r"joint_torque_bias\[0\]"),
                                          ((1.0,), "2 entries"),
                                          ((math.nan, 0.0), r"joint_torque_bias\[0\]")])
def test_torque_bias_is_validated(value, match):
    with pytest.raises(ValueError, match=match):
        Effects(joint_torque_bias=value)
