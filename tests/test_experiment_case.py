"""Typed experiment cases, the declared reference row and controller variants (issue 7)."""

import warnings

import numpy as np
import pytest

from ppamsafety.control import PID, JointPSMC, SensorConfig, SlidingModeControl, TaskPSMC
from ppamsafety.experiments import catalog
from ppamsafety.experiments import closed_loop as cl
from ppamsafety.experiments import trajectories as tr
from ppamsafety.experiments.case import ExperimentCase
from ppamsafety.layouts import REGISTRY
from ppamsafety.units import BAR


# -- reference row ----------------------------------------------------------------------------
def test_reference_row_is_declared_and_generates_the_columns():
    lay = tr.REFERENCE_ROW
    assert REGISTRY["reference row"] is lay and lay.size == tr.NREF == 12
    # the column names and order of the pre-layout REF_COLUMNS (thesis §5.3.4 layout)
    assert tr.REF_COLUMNS == ["q1_d", "q2_d", "qd1_d", "qd2_d", "qdd1_d", "qdd2_d", "qddd1_d",
                              "qddd2_d", "x_d", "y_d", "xd_d", "yd_d"]
    assert (tr.R_Q_D, tr.R_QD_D, tr.R_QDD_D, tr.R_QDDD_D, tr.R_R_D, tr.R_RD_D) == (
        0, 2, 4, 6, 8, 10)
    assert lay.field("r_d").unit == "m" and lay.field("qd_d").unit == "rad/s"


def test_reference_signal_reads_columns_by_name(arm):
    ref = tr.circle(arm, period=10.0, duration=1.0)
    for j, name in enumerate(tr.REF_COLUMNS):
        np.testing.assert_array_equal(ref.signal(name), ref.data[:, j])
    np.testing.assert_array_equal(ref.field("r_d"),
                                  np.stack([ref.signal("x_d"), ref.signal("y_d")], 1))
    # the circle's task-space reference is the 10 cm circle around CIRCLE_CENTER
    c = np.asarray(tr.CIRCLE_CENTER)
    np.testing.assert_allclose(np.linalg.norm(ref.field("r_d") - c, axis=1), 0.10, atol=1e-12)
    with pytest.raises(KeyError, match="q3_d"):
        ref.signal("q3_d")
    with pytest.raises(ValueError, match="shape"):
        tr.Reference("bad", ref.t, ref.data[:, :11], ref.dt)


# -- experiment cases -------------------------------------------------------------------------
@pytest.fixture(scope="module")
def short_ref(arm):
    return tr.step(arm, t_up=0.1, t_down=0.3, duration=0.5)


@pytest.mark.parametrize("field, value, exc, match", [
    ("arm", "thesis", TypeError, "ExperimentCase.arm must be an ArmParameters"),
    ("controller", JointPSMC, TypeError, "ExperimentCase.controller must be a Controller"),
    ("reference", np.zeros((10, 12)), TypeError, "ExperimentCase.reference must be a Reference"),
    ("sensors", "ideal", TypeError, "ExperimentCase.sensors must be a SensorConfig"),
    ("x0", np.zeros(4), ValueError, r"ExperimentCase.x0 must have shape \(8,\)"),
    ("x0", [0.0] * 7 + [np.inf], ValueError, "ExperimentCase.x0 must be finite"),
    ("x0", ["a"] * 8, ValueError, "ExperimentCase.x0"),
    ("name", 3, TypeError, "ExperimentCase.name"),
    ("meta", [1, 2], TypeError, "ExperimentCase.meta"),
])
def test_experiment_case_names_the_bad_field(arm, short_ref, field, value, exc, match):
    kw = {"arm": arm, "controller": PID(), "reference": short_ref, field: value}
    with pytest.raises(exc, match=match):
        ExperimentCase(**kw)


def test_experiment_case_defaults_and_immutability(arm, short_ref):
    c = ExperimentCase(arm, PID(), short_ref, x0=np.zeros(8), meta={"a": 1})
    assert c.name == "step" and isinstance(c.sensors, SensorConfig) and c.meta == {"a": 1}
    assert c.x0.shape == (8,) and not c.x0.flags.writeable
    with pytest.raises(AttributeError):
        c.name = "other"


def test_run_batch_takes_typed_cases_and_deprecated_dicts(arm, short_ref):
    sens = SensorConfig.ideal()
    typed = cl.run_batch([ExperimentCase(arm, PID(), short_ref, sensors=sens, name="a",
                                         meta={"k": 1})])
    with pytest.warns(DeprecationWarning, match="ExperimentCase"):
        old = cl.run_batch([{"arm": arm, "controller": PID(), "reference": short_ref,
                             "sensors": sens, "name": "a", "meta": {"k": 1}}])
    assert typed[0].name == old[0].name == "a" and old[0].meta == {"k": 1}
    np.testing.assert_array_equal(typed[0].log, old[0].log)
    one = cl.run(arm, PID(), short_ref, sensors=sens, name="a")
    np.testing.assert_array_equal(one.log, typed[0].log)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        with pytest.raises(ValueError, match="'sensor'"):
            cl.run_batch([{"arm": arm, "controller": PID(), "reference": short_ref,
                           "sensor": sens}])
        with pytest.raises(ValueError, match="'reference'"):
            cl.run_batch([{"arm": arm, "controller": PID()}])
        with pytest.raises(TypeError, match="ExperimentCase.controller"):
            cl.run_batch([{"arm": arm, "controller": "PID", "reference": short_ref}])
    with pytest.raises(TypeError, match=r"cases\[0\]"):
        cl.run_batch([(arm, PID(), short_ref)])


def test_result_accessors_use_signal_names(arm, short_ref):
    r = cl.run(arm, PID(), short_ref, sensors=SensorConfig.ideal())
    err = np.hypot(r.signal("x_d") - r.signal("x"), r.signal("y_d") - r.signal("y"))
    np.testing.assert_array_equal(r.tracking_error(), err)
    np.testing.assert_array_equal(r.tcp_speed(), np.hypot(r.signal("xd"), r.signal("yd")))
    # the reference is at rest at the start: the error starts at (almost) zero
    assert r.tracking_error()[0] < 1e-6


# -- controller variants ----------------------------------------------------------------------
def test_controller_variant_infers_and_checks_its_fields():
    v = catalog.ControllerVariant.of(JointPSMC(lam=0.8, ki=12 * BAR))
    assert (v.family, v.ki_bar, v.lambda_s, v.label, v.group) == (
        catalog.Family.PSMC_JOINT, 12.0, 0.8, "PSMC joint Ki=12 λ=0.8", "PSMC joint Ki=12")
    same = catalog.ControllerVariant("PSMC joint", 12.0, 0.8, v.controller)
    assert same.family is catalog.Family.PSMC_JOINT and same.label == v.label
    smc = catalog.ControllerVariant.of(SlidingModeControl())
    assert smc.family is catalog.Family.SMC and np.isnan(smc.ki_bar) and np.isnan(smc.lambda_s)
    with pytest.raises(ValueError, match="ControllerVariant.family = 'PSMC'"):
        catalog.ControllerVariant("PSMC", 12.0, 0.8, v.controller)
    with pytest.raises(ValueError, match="ControllerVariant.family = 'PSMC task'"):
        catalog.ControllerVariant("PSMC task", 12.0, 0.8, v.controller)
    with pytest.raises(ValueError, match="ControllerVariant.ki_bar = 2.0"):
        catalog.ControllerVariant("PSMC joint", 2.0, 0.8, v.controller)
    with pytest.raises(ValueError, match="ControllerVariant.lambda_s"):
        catalog.ControllerVariant("PSMC task", None, -1.0, TaskPSMC())
    with pytest.raises(TypeError, match="ControllerVariant.controller"):
        catalog.ControllerVariant("PID", 2.0, None, "PID")
    with pytest.raises(TypeError, match="ControllerVariant.ki_bar"):
        catalog.ControllerVariant("PID", "two", None, PID())


def test_labelled_pairs_become_variants_with_inferred_fields():
    v = catalog.as_variant(("PID Ki=12", PID(ki=12 * BAR)))
    assert (v.family, v.ki_bar, v.label, v.name) == (catalog.Family.PID, 12.0, "PID Ki=12",
                                                     "PID Ki=12")
    w = catalog.as_variant(("PSMC task λ=0.4", TaskPSMC()))
    assert w.name is None and w.label == "PSMC task λ=0.4"
    with pytest.raises(ValueError, match="pairs"):
        catalog.as_variant(PID())
