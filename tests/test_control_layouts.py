"""Declared controller/sensor/log layouts (issue 7): sizes, identical rows in both paths, and
log columns that mean what their names say.

Tests marked ``boundscheck`` are also run by ``.ci/run`` with ``NUMBA_BOUNDSCHECK=1``: they cover
every controller kind, the closed loop (sensors, log writer) and the plant integrator.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest

from ppamsafety.control import (PID, ControllerKind, GCMode, GravityCompensation, JointPSMC,
                                PIDDerivative, SensorConfig, SlidingModeControl, SMCCoupling,
                                TaskPSMC)
from ppamsafety.control import CONTROLLER_CLASSES, dispatch, reference
from ppamsafety.control.admittance import AdmittancePSMC
from ppamsafety.control.estimation import ESTIMATOR_INTERNALS
from ppamsafety.control.sensors import (SENSOR_CONFIG, SENSOR_STATE, VelocitySource,
                                        initial_sensor_state)
from ppamsafety.experiments import closed_loop as cl
from ppamsafety.experiments.case import ExperimentCase
from ppamsafety.experiments import trajectories as tr
from ppamsafety.experiments.trajectories import Reference
from ppamsafety.plant import geometry as geo
from ppamsafety.plant.model import rest_state, simulate
from ppamsafety.plant.pneumatics import delta_p_to_set_values
from ppamsafety.units import BAR, DEG

T = 1e-3
KINDS = list(ControllerKind)
#: Force-estimator row handed to controller_step (read only by the admittance kind).
FEST0 = np.zeros(ESTIMATOR_INTERNALS.size)


def _random_controller(kind, rng):
    """A controller of ``kind`` with random valid gains around the thesis defaults."""
    f = lambda: rng.uniform(0.5, 2.0, size=2)          # noqa: E731  per-joint factor
    gc = ("off", "measured", "desired")
    if kind == ControllerKind.GC:
        return GravityCompensation(at=str(rng.choice(["desired", "measured"])))
    if kind == ControllerKind.PID:
        return PID(kp=2 * BAR * f(), ki=2 * BAR * f(), kd=0.1 * BAR * f(),
                   derivative=str(rng.choice(["velocity", "difference"])),
                   gravity_compensation=str(rng.choice(gc)))
    if kind == ControllerKind.PSMC_JOINT:
        return JointPSMC(lam=0.4 * f(), kp=2 * BAR * f(), ki=2 * BAR * f(), kd=0.1 * BAR * f(),
                         dp_limit=0.2 * BAR * f(),
                         gravity_compensation=str(rng.choice(gc + ("proxy",))))
    if kind == ControllerKind.PSMC_TASK:
        return TaskPSMC(lam=0.4 * f()[0], kp=200 * f()[0], ki=100 * f()[0], kd=10 * f()[0],
                        force_limit=15 * f()[0],
                        gravity_compensation=str(rng.choice(gc + ("proxy",))))
    if kind == ControllerKind.ADMITTANCE:
        return AdmittancePSMC(b=40 * f()[0], f_min=3 * f()[0],
                              source=str(rng.choice(["rls", "observer"])),
                              psmc=JointPSMC(lam=0.4 * f(), kp=2 * BAR * f(), ki=2 * BAR * f(),
                                             kd=0.1 * BAR * f(), dp_limit=0.2 * BAR * f(),
                                             gravity_compensation=str(rng.choice(gc))))
    return SlidingModeControl(poles=40 * f(), gain=3000 * f(), boundary_layer=10 * f(),
                              coupling=str(rng.choice(["siso", "mimo"])))


def _random_reference(arm, n, rng):
    """A 'random' reference: a joint-space step plus random jitter in every column."""
    base_ref = tr.joint_steps(arm, q_levels=[[50 * DEG, -80 * DEG]], t_changes=[],
                              duration=n * T)
    data = base_ref.data.copy()
    data[:, reference.R_Q:reference.R_Q + 2] += rng.normal(scale=0.02, size=(n, 2))
    data[:, reference.R_QD:reference.R_QD + 2] += rng.normal(scale=0.1, size=(n, 2))
    data[:, reference.R_QDD:reference.R_QDD + 2] += rng.normal(scale=0.5, size=(n, 2))
    data[:, reference.R_QDDD:reference.R_QDDD + 2] += rng.normal(scale=2.0, size=(n, 2))
    r = geo.forward_kinematics(data[:, reference.R_Q:reference.R_Q + 2], arm)
    data[:, reference.R_X], data[:, reference.R_Y] = r[:, 0], r[:, 1]
    data[:, reference.R_XD:reference.R_XD + 2] += rng.normal(scale=0.01, size=(n, 2))
    return Reference("random", base_ref.t, data, T)


# -- declarations ---------------------------------------------------------------------------
def test_reference_constants_match_the_reference_columns():
    """The controllers' reference offsets are those of the declared reference row."""
    assert reference.NREF == len(tr.REF_COLUMNS)
    for const, col in [("R_Q", "q1_d"), ("R_QD", "qd1_d"), ("R_QDD", "qdd1_d"),
                       ("R_QDDD", "qddd1_d"), ("R_X", "x_d"), ("R_Y", "y_d"), ("R_XD", "xd_d"),
                       ("R_YD", "yd_d")]:
        assert getattr(reference, const) == tr.REF_COLUMNS.index(col)


def test_buffers_are_sized_from_the_declarations():
    """Every kind's declared need fits the allocated buffers, which are computed maxima."""
    classes = CONTROLLER_CLASSES
    assert set(classes) == set(ControllerKind)
    for name, attr in [("CONTROLLER_ROW_WIDTH", lambda c: c.PARAMS.size),
                       ("NSTATE", lambda c: c.STATE.size),
                       ("NINT", lambda c: c.INTERNALS.size),
                       ("NSCRATCH", lambda c: c.SCRATCH)]:
        needs = [attr(c) for c in classes.values()]
        allocated = getattr(dispatch, name)
        assert all(isinstance(x, int) and x >= 0 for x in needs), name
        assert max(needs) <= allocated, name
        assert allocated == max(needs), f"{name} is not the maximum declared need"
    # the runner uses exactly these
    assert cl.NSTATE == dispatch.NSTATE and cl.NSCRATCH == dispatch.NSCRATCH
    assert cl.NINT == dispatch.NINT and cl.LOG.length("internals") == dispatch.NINT
    # scratch needs come from scratch layouts (SMC uses all of its 32 slots: the torque
    # functions of its model, its pressure terms and the b, A, v of (4.33)-(4.41); the task
    # PSMC its m_tau and the gravity compensation's)
    assert SlidingModeControl.SCRATCH == 32 and TaskPSMC.SCRATCH == 8


@pytest.mark.parametrize("kind", KINDS)
def test_rows_have_the_declared_sizes(arm, kind):
    c = _random_controller(kind, np.random.default_rng(int(kind)))
    assert c.kind == kind and isinstance(c.kind, ControllerKind)
    assert c.pack().shape == (c.PARAMS.size,)
    assert c.state.shape == (c.STATE.size,) and c.internals.shape == (c.INTERNALS.size,)
    k, C, sizes, _ = cl._controller_rows(arm, c)
    np.testing.assert_array_equal(C, c.pack())
    assert tuple(sizes) == dispatch.declared_sizes(kind)
    # flag fields hold enum codes
    for f in c.PARAMS.fields:
        if f.unit == "code":
            assert float(c.PARAMS.read(C, f.name)).is_integer()


def test_internal_names_come_from_the_layouts():
    assert cl.INTERNAL_NAMES[ControllerKind.PSMC_JOINT] == [
        "dp_psmc1", "dp_psmc2", "s1", "s2", "on_surface1", "on_surface2", "a1", "a2"]
    assert cl.INTERNAL_NAMES[ControllerKind.PSMC_TASK] == [
        "fx", "fy", "sx", "sy", "on_surface", "f_star_norm", "ax", "ay"]
    assert cl.INTERNAL_NAMES[ControllerKind.SMC] == [
        "s1", "s2", "a11", "a22", "b1", "b2", "u_smc1", "u_smc2"]
    assert cl.INTERNAL_NAMES[ControllerKind.PID] == ["pid1", "pid2", "integral1", "integral2"]
    assert ControllerKind.GC not in cl.INTERNAL_NAMES
    for kind, cls in CONTROLLER_CLASSES.items():
        assert cl.INTERNAL_NAMES.get(kind, []) == cls.INTERNALS.columns()
    assert cl.LOG_COLUMNS == cl.LOG.columns() and cl.NLOG == len(cl.LOG_COLUMNS)
    assert cl.LOG_COLUMNS[:23] == ["t", "q1", "q2", "qd1", "qd2", "p1", "p2", "p3", "p4",
                                   "q1_meas", "q2_meas", "qd1_meas", "qd2_meas", "u1", "u2",
                                   "u3", "u4", "dp1", "dp2", "x", "y", "xd", "yd"]


def test_flags_are_enum_codes_validated_by_name():
    assert PID(derivative=PIDDerivative.DIFFERENCE).derivative == "difference"
    assert PID().pack()[PID.PARAMS.offset("derivative")] == PIDDerivative.VELOCITY
    assert JointPSMC().gc == GCMode.PROXY and JointPSMC(gravity_compensation="off").gc == 0
    assert SlidingModeControl(coupling="MIMO").pack()[-1] == SMCCoupling.MIMO
    with pytest.raises(ValueError, match="PID.gravity_compensation"):
        PID(gravity_compensation="proxy")               # PID has no proxy
    with pytest.raises(ValueError, match="JointPSMC.gravity_compensation"):
        JointPSMC(gravity_compensation="everywhere")
    with pytest.raises(ValueError, match="PID.derivative"):
        PID(derivative=2)
    cfg = SensorConfig(velocity=VelocitySource.IDEAL, encoder=False).pack()
    assert SENSOR_CONFIG.read(cfg, "velocity") == VelocitySource.IDEAL
    assert SENSOR_CONFIG.read(cfg, "encoder") == 0
    st = initial_sensor_state([0.0, 0.0])
    assert st.shape == (SENSOR_STATE.size,)
    assert np.all(SENSOR_STATE.read(st, "t_last") == -1e9)


# -- identical rows in Controller.step and the batched runner ---------------------------------
@pytest.mark.boundscheck
def test_controller_step_and_batched_runner_are_bitwise_equal(arm):
    """Random valid gains for every kind (two variants each, mixed in one batch so rows are
    padded), 200 samples of a random reference, noisy realistic sensors: replaying the
    runner's measured inputs through Controller.step gives bitwise the logged Delta p and
    internals."""
    n = 200
    rng = np.random.default_rng(7)
    ref = _random_reference(arm, n, rng)
    controllers = [_random_controller(k, rng) for k in KINDS for _ in range(2)]
    x0 = rest_state(np.radians([50, -80]), arm)[0]
    sensors = SensorConfig(noise=True, seed=3)
    runs = cl.run_batch([ExperimentCase(arm=arm, controller=c, reference=ref, sensors=sensors,
                                        x0=x0) for c in controllers])
    kinds_seen = set()
    for c, res in zip(controllers, runs):
        assert not res.diverged
        qm = res.signals("q1_meas", "q2_meas")
        qdm = res.signals("qd1_meas", "qd2_meas")
        p = res.signals("p1", "p2", "p3", "p4")
        dp = res.signals("dp1", "dp2")
        ints = res.log[:, cl.LOG.slice("internals")]
        c.reset()
        est = res.estimator_log          # the loop's force estimates (admittance reads them)
        for k in range(n):
            out = c.step(arm, qm[k], qdm[k], p[k], ref.data[k],
                         f_est=None if est is None else est[k])
            assert out.tobytes() == dp[k].tobytes(), (c.name, k)
            assert c.internals.tobytes() == ints[k, :c.INTERNALS.size].tobytes(), (c.name, k)
            assert np.all(ints[k, c.INTERNALS.size:] == 0.0)
        assert np.any(dp != 0.0)
        kinds_seen.add(c.kind)
    assert kinds_seen == set(ControllerKind)


@pytest.mark.boundscheck
def test_batched_dispatch_with_padded_table_rows_equals_controller_step(arm):
    """Open loop, random measurements: the dispatch driven with rows cut from the runner's
    padded parameter table (as _run_batch cuts them) equals Controller.step bitwise."""
    n = 200
    rng = np.random.default_rng(11)
    ref = _random_reference(arm, n, rng).data
    q = np.radians([50, -80]) + rng.normal(scale=0.05, size=(n, 2))
    qd = rng.normal(scale=0.5, size=(n, 2))
    p = rng.uniform(1.0e5, 3.0e5, size=(n, 4))
    controllers = [_random_controller(k, rng) for k in KINDS]
    rows = [cl._controller_rows(arm, c) for c in controllers]
    CP = np.zeros((len(rows), dispatch.CONTROLLER_ROW_WIDTH))
    for i, (_, C, _, _) in enumerate(rows):
        CP[i, :C.size] = C
    for i, (c, (kind, _, sizes, Pm)) in enumerate(zip(controllers, rows)):
        S_buf, int_buf = np.zeros(dispatch.NSTATE), np.zeros(dispatch.NINT)
        scr_buf = np.empty(dispatch.NSCRATCH)
        C = CP[i, :sizes[cl.Z_PARAMS]]
        S, ints = S_buf[:sizes[cl.Z_STATE]], int_buf[:sizes[cl.Z_INTERNALS]]
        scr = scr_buf[:sizes[cl.Z_SCRATCH]]
        dp = np.empty(2)
        c.reset()
        for k in range(n):
            dispatch.controller_step(kind, C, S, Pm, k, T, q[k], qd[k], p[k], ref[k], FEST0, dp,
                                     ints, scr)
            out = c.step(arm, q[k], qd[k], p[k], ref[k])
            assert out.tobytes() == dp.tobytes(), (c.name, k)
            assert c.internals.tobytes() == ints.tobytes(), (c.name, k)
            assert c.state.tobytes() == S.tobytes(), (c.name, k)


@pytest.mark.boundscheck
def test_too_short_rows_raise_under_boundscheck(arm):
    """With NUMBA_BOUNDSCHECK=1 (the .ci/run subset) a row shorter than declared raises."""
    if not numba.config.BOUNDSCHECK:
        pytest.skip("only meaningful with NUMBA_BOUNDSCHECK=1")
    c = SlidingModeControl()
    C = c.pack()
    z = np.zeros(2)
    with pytest.raises(IndexError):
        dispatch.controller_step(int(c.kind), C, np.zeros(0), c.model_row(arm), 0, T,
                                 np.radians([50, -80]), z, np.full(4, 2e5), np.zeros(12),
                                 FEST0, np.empty(2), np.zeros(c.INTERNALS.size),
                                 np.zeros(c.SCRATCH - 1))


@pytest.mark.boundscheck
def test_plant_integrator_runs(arm):
    """The plant kernels (covered by the boundscheck subset): a short valve step moves q."""
    x0, u = rest_state(np.radians([50, -80]), arm)
    U = np.tile(u, (300, 1))
    U[50:, 0] += 0.4 * BAR
    X = simulate(arm, x0, U)
    assert X.shape == (301, 8) and np.all(np.isfinite(X))
    assert abs(X[-1, 0] - x0[0]) > 1e-3


# -- log columns mean what their names say ------------------------------------------------------
def _drift_run(arm, controller, sensors=None):
    ref = tr.step(arm, duration=3.0)
    sensors = SensorConfig(encoder=True, velocity="ideal", noise=False) if sensors is None \
        else sensors
    return cl.run(arm, controller, ref, sensors=sensors), ref


@pytest.mark.boundscheck
def test_log_columns_mean_what_their_names_say(arm):
    c = JointPSMC(gravity_compensation="off", lam=(0.4, 0.3))
    res, ref = _drift_run(arm, c)
    s = res.signal
    n = ref.n_steps
    # t = k dt
    np.testing.assert_array_equal(s("t"), np.arange(n) * T)
    q = res.signals("q1", "q2")
    qd = res.signals("qd1", "qd2")
    # x, y = FK(q1, q2); xd, yd = J(q) qd
    np.testing.assert_allclose(res.signals("x", "y"), geo.forward_kinematics(q, arm),
                               rtol=0, atol=1e-14)
    J = geo.jacobian(q, arm)
    np.testing.assert_allclose(res.signals("xd", "yd"), np.einsum("nij,nj->ni", J, qd),
                               rtol=0, atol=1e-13)
    # encoder quantisation of q (count * resolution, count = floor(q/res)); ideal velocity
    res_ = SensorConfig().resolution
    np.testing.assert_array_equal(res.signals("q1_meas", "q2_meas"),
                                  np.floor(q / res_) * res_)
    np.testing.assert_array_equal(res.signals("qd1_meas", "qd2_meas"), qd)
    # u1..u4: Delta-p set-value conversion of dp1, dp2 with the controller's model
    Pm = c.model_row(arm)
    dp = res.signals("dp1", "dp2")
    u = np.empty(4)
    U = res.signals("u1", "u2", "u3", "u4")
    for k in range(0, n, 7):
        delta_p_to_set_values(dp[k, 0], dp[k, 1], Pm, u)
        np.testing.assert_array_equal(U[k], u)
    # pressures are the plant's: rest state at the start
    np.testing.assert_array_equal(res.log[0, cl.LOG.slice("p")],
                                  rest_state(ref.data[0, 0:2], arm)[0][4:8])
    # PSMC internals (gc off, so dp = Delta p_psmc): (5.27), (5.32)
    for j in range(2):
        f = s(f"dp_psmc{j + 1}")
        np.testing.assert_array_equal(f, dp[:, j])
        a = s(f"a{j + 1}")
        kp, ki, kd, lam, lim = c.kp[j], c.ki[j], c.kd[j], c.lam[j], c.dp_limit[j]
        ap = np.concatenate([[0.0, 0.0], a])
        a_prev, da_prev = ap[1:-1], ap[1:-1] - ap[:-2]
        sigma = (s(f"q{j + 1}_d") - s(f"q{j + 1}_meas")) + lam * (s(f"qd{j + 1}_d")
                                                                  - s(f"qd{j + 1}_meas"))
        A = ki * T * T + kp * T + kd
        fs = A / (T + lam) * sigma + ki * a_prev + (lam * (ki * T + kp) - kd) / (
            T * (T + lam)) * da_prev
        np.testing.assert_allclose(f, np.clip(fs, -lim, lim), rtol=1e-9, atol=1e-6)
        np.testing.assert_allclose(s(f"s{j + 1}"), (T + lam) / A * (fs - f),
                                   rtol=1e-9, atol=1e-12)
        on = s(f"on_surface{j + 1}")
        clear = np.abs(np.abs(fs) - lim) > 1e-6 * lim
        np.testing.assert_array_equal(on[clear], (np.abs(fs) <= lim)[clear].astype(float))
        assert 0 < on.mean() < 1                    # the step saturates, tracking does not


@pytest.mark.parametrize("kind", [ControllerKind.PID, ControllerKind.SMC,
                                  ControllerKind.PSMC_TASK])
def test_internals_of_other_kinds_mean_what_their_names_say(arm, kind):
    if kind == ControllerKind.PID:
        c = PID(gravity_compensation="off")
    elif kind == ControllerKind.SMC:
        c = SlidingModeControl()
    else:
        c = TaskPSMC(lam=0.05)
    res, ref = _drift_run(arm, c)
    s = res.signal
    dp = res.signals("dp1", "dp2")
    if kind == ControllerKind.PID:
        e = res.signals("q1_d", "q2_d") - res.signals("q1_meas", "q2_meas")
        np.testing.assert_allclose(res.signals("integral1", "integral2"),
                                   np.cumsum(T * e, axis=0), rtol=1e-9, atol=1e-12)
        np.testing.assert_array_equal(res.signals("pid1", "pid2"), dp)
    elif kind == ControllerKind.SMC:
        np.testing.assert_array_equal(res.signals("u_smc1", "u_smc2"), dp)
        assert np.all(res.signals("a11", "a22") > 0)      # valve opening raises qddd
    else:
        fn = np.hypot(s("fx"), s("fy"))
        assert np.all(fn <= c.force_limit * (1 + 1e-12))
        assert np.all(s("f_star_norm") >= fn * (1 - 1e-12))
        on = s("on_surface") > 0.5
        np.testing.assert_allclose(fn[on], s("f_star_norm")[on], rtol=1e-12)
        assert np.all(np.abs(res.signals("sx", "sy"))[on] < 1e-12)


# -- compiled kernels with IntEnum constants are cached ---------------------------------------
_CACHE_PROBE = r"""
import json, numpy as np
from ppamsafety.params import thesis_arm
from ppamsafety.control import CONTROLLER_CLASSES, ControllerKind, dispatch
from ppamsafety.experiments.trajectories import REFERENCE_ROW as REF
from ppamsafety.plant.geometry import forward_kinematics
arm = thesis_arm()
q = np.radians([50, -80])
ref = REF.pack(q_d=q, qd_d=0.0, qdd_d=0.0, qddd_d=0.0, r_d=forward_kinematics(q, arm),
               rd_d=0.0)                          # a consistent hold reference
for cls in CONTROLLER_CLASSES.values():
    cls().step(arm, q, np.zeros(2), np.full(4, 2e5), ref)
st = dispatch.controller_step.stats
print(json.dumps({"hits": sum(st.cache_hits.values()), "misses": sum(st.cache_misses.values())}))
"""


def test_kernels_comparing_intenum_flags_load_from_the_disk_cache():
    """numba freezes IntEnum members as constants; the cached machine code must be reused
    by a fresh process (njit(cache=True))."""
    env = dict(os.environ)
    root = str(Path(__file__).resolve().parents[1])
    env["PYTHONPATH"] = root + os.pathsep + env.get("PYTHONPATH", "")
    outs = []
    for _ in range(2):
        r = subprocess.run([sys.executable, "-c", _CACHE_PROBE], capture_output=True,
                           text=True, env=env, cwd=root, timeout=600)
        assert r.returncode == 0, r.stderr
        outs.append(json.loads(r.stdout.strip().splitlines()[-1]))
    assert outs[1]["misses"] == 0 and outs[1]["hits"] >= 1, outs
