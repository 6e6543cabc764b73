"""Property-based tests (issue 8): public entry points of control, experiments and plant.

For arbitrary (mostly invalid) input -- wrong types, NaN/inf, zero/negative/huge values, wrong
shapes, degrees for radians -- each call must either raise ``TypeError``/``ValueError`` whose
message names the argument, or return a finite, sane result.  Anything else (AttributeError,
OverflowError, a numba typing error, a silent NaN) fails the test.

Counts per entry point are printed at the end of the module and written to
``$PPAMSAFETY_PROPERTY_COUNTS/property_counts_control.txt`` when that variable names a folder.
"""

import math

import numpy as np
import pytest
hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from property_support import SPECIAL_VALUES, Recorder, bad_types, numbers  # noqa: E402

from ppamsafety.control import (PID, GravityCompensation, JointPSMC, SensorConfig,  # noqa: E402
                                SlidingModeControl, TaskPSMC)
from ppamsafety.experiments import catalog, metrics  # noqa: E402
from ppamsafety.experiments import trajectories as tr  # noqa: E402
from ppamsafety.experiments.case import ExperimentCase  # noqa: E402
from ppamsafety.experiments.closed_loop import run_batch  # noqa: E402
from ppamsafety.params import thesis_arm  # noqa: E402
from ppamsafety.plant import dynamics, geometry, model, pneumatics, torque  # noqa: E402

FAST = settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
SLOW = settings(max_examples=12, deadline=None, suppress_health_check=list(HealthCheck))
ARM = thesis_arm()

special = st.sampled_from(SPECIAL_VALUES + [30.0, 70.0, -80.0])   # + degrees as radians
anything = st.one_of(bad_types, special, numbers)
pairs = st.one_of(anything, st.lists(numbers, min_size=1, max_size=3),
                  st.tuples(st.floats(0, 1e6), st.floats(0, 1e6)))
arrays2 = st.one_of(anything, st.lists(numbers, min_size=2, max_size=2),
                    st.lists(st.lists(numbers, min_size=2, max_size=2), min_size=1, max_size=3),
                    st.lists(numbers, max_size=5), st.tuples(st.floats(-3, 3), st.floats(-3, 3)))


_REC = Recorder("control")
outcome = _REC.outcome


def finite(x):
    return np.all(np.isfinite(np.asarray(x, dtype=float)))


@pytest.fixture(scope="module", autouse=True)
def _report_counts():
    yield
    _REC.report()


# --- controllers ------------------------------------------------------------------------

CONTROLLERS = {
    PID: ["kp", "ki", "kd", "derivative", "gravity_compensation"],
    JointPSMC: ["lam", "kp", "ki", "kd", "dp_limit", "gravity_compensation"],
    TaskPSMC: ["lam", "kp", "ki", "kd", "force_limit", "gravity_compensation"],
    SlidingModeControl: ["poles", "gain", "boundary_layer", "coupling", "model_time_constants",
                         "model_links"],
    GravityCompensation: ["at"],
}
CTRL_FIELDS = [(cls, f) for cls, fs in CONTROLLERS.items() for f in fs]


@FAST
@given(which=st.sampled_from(CTRL_FIELDS), value=st.one_of(pairs, st.lists(numbers, min_size=4,
                                                                           max_size=4)))
def test_controller_constructors(which, value):
    cls, field = which
    c = outcome(cls.__name__, lambda: cls(**{field: value}), f"{cls.__name__}.{field}",
                *[f"{cls.__name__}.{f}" for f in ("kp", "ki", "kd", "lam")])
    if c is not None:
        assert finite(c.pack())


@FAST
@given(field=st.sampled_from(["encoder", "velocity", "noise", "seed", "resolution", "clock_hz",
                              "counter_bits", "dead_band", "noise_variances"]),
       value=st.one_of(anything, st.lists(numbers, min_size=4, max_size=4)))
def test_sensor_config(field, value):
    c = outcome("SensorConfig", lambda: SensorConfig(**{field: value}), f"SensorConfig.{field}")
    if c is not None:
        assert finite(c.pack())


REF_ROW = np.zeros(12)
REF_ROW[:2] = (0.9, -1.4)


@FAST
@given(arg=st.sampled_from(["q_meas", "qd_meas", "p_meas", "ref", "dt", "arm"]), value=arrays2,
       cls=st.sampled_from([PID, JointPSMC, TaskPSMC, GravityCompensation]))
def test_controller_step(arg, value, cls):
    kw = {"arm": ARM, "q_meas": [0.9, -1.4], "qd_meas": [0.0, 0.0], "p_meas": [1.5e5] * 4,
          "ref": REF_ROW, "dt": 1e-3}
    kw[arg] = value
    c = cls()
    out = outcome("Controller.step", lambda: c.step(kw["arm"], kw["q_meas"], kw["qd_meas"],
                                                     kw["p_meas"], kw["ref"], dt=kw["dt"]), arg)
    if out is not None:
        assert out.shape == (2,) and finite(out)


# --- trajectories -------------------------------------------------------------------------

STEP_ARGS = ["low", "high", "q2", "t_up", "t_down", "duration", "dt"]


@FAST
@given(field=st.sampled_from(STEP_ARGS), value=anything)
def test_step(field, value):
    kw = {"t_up": 0.1, "t_down": 0.2, "duration": 0.3}
    kw[field] = value
    ref = outcome("trajectories.step", lambda: tr.step(ARM, **kw), field, "t_up", "t_down",
                  "low", "high", "number of samples round(duration/dt)")
    if ref is not None:
        assert finite(ref.data) and ref.n_steps >= 1


@FAST
@given(levels=st.one_of(anything, st.lists(st.lists(st.floats(-200, 200), min_size=2,
                                                    max_size=2), min_size=1, max_size=3)),
       changes=st.one_of(anything, st.lists(st.floats(-1, 2), max_size=2)),
       duration=st.one_of(st.floats(0.01, 1.5), anything))
def test_joint_steps(levels, changes, duration):
    ref = outcome("trajectories.joint_steps",
                  lambda: tr.joint_steps(ARM, q_levels=levels, t_changes=changes,
                                         duration=duration),
                  "q_levels", "t_changes", "duration", "joint_steps", "dt",
                  *[f"t_changes[{i}]" for i in range(3)],
                  *[f"q_levels[{i}, {j}]" for i in range(3) for j in range(2)],
                  "number of samples round(duration/dt)")
    if ref is not None:
        q = ref.field("q_d")
        assert finite(ref.data) and geometry.in_working_area(q, ARM).all()


@SLOW
@given(field=st.sampled_from(["period", "center", "radius", "phase", "duration", "dt"]),
       value=st.one_of(anything, st.tuples(st.floats(-1, 1), st.floats(-1, 1)),
                       st.floats(0.01, 0.3)))
def test_circle(field, value):
    kw = {"period": 5.0, "duration": 0.2}
    kw[field] = value
    ref = outcome("trajectories.circle", lambda: tr.circle(ARM, **kw), field, "circle")
    if ref is not None:
        assert finite(ref.data) and geometry.in_working_area(ref.field("q_d"), ARM).all()


@SLOW
@given(field=st.sampled_from(["period_before", "period_after", "t_switch", "duration"]),
       value=st.one_of(anything, st.floats(0.01, 2.0)))
def test_trajectory_switch(field, value):
    kw = {"duration": 1.0, "t_switch": 0.5}
    kw[field] = value
    ref = outcome("trajectories.trajectory_switch", lambda: tr.trajectory_switch(ARM, **kw),
                  field, "t_switch", "trajectory_switch (before)", "trajectory_switch (after)")
    if ref is not None:
        assert finite(ref.data)


@FAST
@given(name=st.one_of(anything, st.sampled_from(catalog.EXPERIMENTS)),
       duration=st.one_of(st.none(), anything, st.floats(0.5, 20)))
def test_thesis_reference(name, duration):
    if isinstance(duration, float) and math.isfinite(duration) and duration > 20:
        duration = 20.0            # keep the example cheap
    ref = outcome("catalog.thesis_reference",
                  lambda: catalog.thesis_reference(ARM, name, duration=duration),
                  "name", "duration", "step experiment", "switch experiment", "t_switch", "t_up")
    if ref is not None:
        assert finite(ref.data)


@FAST
@given(value=st.one_of(anything, st.lists(numbers, max_size=3)))
def test_thesis_variants(value):
    v = outcome("catalog.thesis_variants", lambda: catalog.thesis_variants(lambdas=value),
                "lambdas", "JointPSMC.lam", "TaskPSMC.lam")
    if v is not None:
        assert len(v) >= 4


# --- experiment case and closed loop ------------------------------------------------------

SHORT = tr.step(ARM, t_up=0.01, t_down=0.02, duration=0.03)


@FAST
@given(field=st.sampled_from(["arm", "controller", "reference", "sensors", "x0", "name",
                              "meta"]),
       value=st.one_of(anything, st.lists(numbers, min_size=8, max_size=8)))
def test_experiment_case(field, value):
    kw = {"arm": ARM, "controller": PID(), "reference": SHORT}
    kw[field] = value
    outcome("ExperimentCase", lambda: ExperimentCase(**kw), f"ExperimentCase.{field}",
            "ExperimentCase.x0[0:2] (q1, q2)", "ExperimentCase.x0[2:4] (qd1, qd2)",
            "ExperimentCase.x0[4:8] (p1..p4)")


@SLOW
@given(field=st.sampled_from(["dt", "substeps", "cases"]), value=anything)
def test_run_batch(field, value):
    kw = {"cases": [ExperimentCase(ARM, PID(), SHORT)], "dt": 1e-3, "substeps": 1}
    kw[field] = value
    res = outcome("closed_loop.run_batch", lambda: run_batch(**kw), field, "cases[0]",
                  "run_batch")
    if res:
        assert all(not r.diverged and finite(r.log) for r in res)


# --- metrics --------------------------------------------------------------------------------

@FAST
@given(which=st.sampled_from(["time_to_within", "settling_time"]),
       field=st.sampled_from(["t", "err", "t_event", "tol", "t_end"]),
       value=st.one_of(anything, st.lists(numbers, min_size=5, max_size=5)))
def test_time_metrics(which, field, value):
    kw = {"t": np.arange(5) * 0.1, "err": np.linspace(1, 0, 5), "t_event": 0.0, "tol": 0.3,
          "t_end": None}
    kw[field] = value
    f = getattr(metrics, which)
    r = outcome(f"metrics.{which}", lambda: f(kw["t"], kw["err"], kw["t_event"], kw["tol"],
                                              t_end=kw["t_end"]),
                field, "t_from", "t_to", "t_end", "t_event")
    if r is not None:
        assert isinstance(r, float)


@FAST
@given(dp=st.one_of(anything, st.lists(st.lists(numbers, min_size=2, max_size=2), min_size=1,
                                       max_size=8)),
       dt=st.one_of(anything, st.just(1e-3)))
def test_chattering(dp, dt):
    r = outcome("metrics.chattering_index", lambda: metrics.chattering_index(dp, dt), "dp", "dt")
    if r is not None:
        # NaN only for a non-finite command (a diverged run, flagged there)
        assert isinstance(r, float) and (math.isfinite(r) or not finite(dp))


# --- plant ----------------------------------------------------------------------------------

PLANT_Q = [
    ("geometry.forward_kinematics", geometry.forward_kinematics),
    ("geometry.jacobian", geometry.jacobian),
    ("geometry.contractions", geometry.contractions),
    ("geometry.muscle_lengths", geometry.muscle_lengths),
    ("geometry.lever_arms", geometry.lever_arms),
    ("geometry.attachment_points", geometry.attachment_points),
    ("geometry.in_working_area", geometry.in_working_area),
    ("torque.torque_functions", torque.torque_functions),
    ("pneumatics.gravity_compensation", pneumatics.gravity_compensation),
    ("pneumatics.static_pressures", pneumatics.static_pressures),
    ("dynamics.inertia_matrix", dynamics.inertia_matrix),
    ("dynamics.gravity", dynamics.gravity),
    ("dynamics.potential_energy", dynamics.potential_energy),
    ("model.rest_state", model.rest_state),
]


@FAST
@given(which=st.sampled_from(PLANT_Q), q=arrays2, bad_arm=st.booleans())
def test_plant_functions_of_q(which, q, bad_arm):
    name, f = which
    arm = "thesis" if bad_arm else ARM
    r = outcome(name, lambda: f(q, arm), "q", "arm")
    if r is not None:
        assert all(finite(x) for x in (r if isinstance(r, tuple) else (r,)))


PLANT_QD = [("dynamics.coriolis", lambda a, arm: dynamics.coriolis([0.9, -1.4], a, arm)),
            ("dynamics.kinetic_energy",
             lambda a, arm: dynamics.kinetic_energy([0.9, -1.4], a, arm)),
            ("dynamics.friction", lambda a, arm: dynamics.friction(a, arm)),
            ("geometry.inverse_kinematics", lambda a, arm: geometry.inverse_kinematics(a, arm)),
            ("pneumatics.delta_p_pressures",
             lambda a, arm: pneumatics.delta_p_pressures(a, arm))]


@FAST
@given(which=st.sampled_from(PLANT_QD), a=arrays2)
def test_plant_functions_of_speed(which, a):
    name, f = which
    r = outcome(name, lambda: f(a, ARM), "qd", "r", "dp", "inverse_kinematics")
    if r is not None:
        assert finite(r)


X_REST = model.rest_state([0.9, -1.4], ARM)[0]


@FAST
@given(field=st.sampled_from(["x", "set_values", "tau_ext"]),
       value=st.one_of(anything, st.lists(numbers, min_size=8, max_size=8),
                       st.lists(numbers, min_size=4, max_size=4),
                       st.lists(numbers, min_size=2, max_size=2)))
def test_state_derivative(field, value):
    kw = {"x": X_REST, "set_values": np.full(4, 1.5e5), "tau_ext": None}
    kw[field] = value
    r = outcome("model.state_derivative",
                lambda: model.state_derivative(kw["x"], kw["set_values"], ARM,
                                               tau_ext=kw["tau_ext"]),
                field, "x[..., 0:2] (q)", "x[..., 2:4] (qd)", "x[..., 4:8] (p)",
                "state_derivative")
    if r is not None:
        assert finite(r)


@SLOW
@given(field=st.sampled_from(["x0", "set_values", "dt", "substeps", "arm"]),
       value=st.one_of(anything, st.lists(numbers, min_size=8, max_size=8),
                       st.lists(st.lists(numbers, min_size=4, max_size=4), min_size=1,
                                max_size=3)))
def test_simulate(field, value):
    kw = {"arm": ARM, "x0": X_REST, "set_values": np.full((3, 4), 1.5e5), "dt": 1e-3,
          "substeps": 2}
    kw[field] = value
    r = outcome("model.simulate",
                lambda: model.simulate(kw["arm"], kw["x0"], kw["set_values"], dt=kw["dt"],
                                       substeps=kw["substeps"]),
                field, "x0[..., 0:2] (q)", "x0[..., 2:4] (qd)", "x0[..., 4:8] (p)", "simulate",
                "params")
    if r is not None:
        assert finite(r)
