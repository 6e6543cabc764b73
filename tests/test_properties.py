"""Property-based tests: every public entry point of params, hic, head_fit and design.

For arbitrary (mostly invalid) input -- wrong types (str, None, dict, complex,
bool, nested lists), NaN/inf, zero/negative/huge values, wrong shapes -- each
call must either raise ``TypeError``/``ValueError`` whose message names the
argument, or return a finite, sane result.  Anything else (AttributeError,
OverflowError, a numba typing error, a silent NaN) fails the test.

Counts per entry point (examples, clear errors, sane results) are printed at
the end of the module and written to
``$PPAMSAFETY_PROPERTY_COUNTS/property_counts_params.txt`` when that variable names a folder.
"""

import math

import numpy as np
import pytest
hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st
from property_support import Recorder, anything, bad_types, numbers, special  # noqa: E402

from ppamsafety import design
from ppamsafety.impact import head_fit as hf
from ppamsafety.impact.hic import hic, hic_bruteforce, hic_half_sine, hic_rectangular
from ppamsafety.params import (MuscleGroup, PneumaticParams, Valve,
                               identified_dynamic, thesis_arm, thesis_geometry, thesis_muscles,
                               thesis_valves)
from ppamsafety.params.geometry import group_length_range
from ppamsafety.impact.head import HeadContactModel, head_model
from ppamsafety.impact.contact import hunt_crossley_max_penetration

FAST = settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
SLOW = settings(max_examples=15, deadline=None, suppress_health_check=list(HealthCheck))

# --- strategies ----------------------------------------------------------------------



_REC = Recorder("params")
outcome = _REC.outcome


@pytest.fixture(scope="module", autouse=True)
def _report_counts():
    yield
    _REC.report()


def _is_float(x):
    return type(x) is float and math.isfinite(x)


# --- parameter sets -------------------------------------------------------------------

GEOM_FIELDS = [f for f in thesis_geometry().__dataclass_fields__]


@FAST
@given(field=st.sampled_from(GEOM_FIELDS), value=anything)
def test_arm_geometry(field, value):
    g = outcome("ArmGeometry", lambda: thesis_geometry().replace(**{field: value}), field)
    if g is not None:
        assert _is_float(getattr(g, field))
        assert all(dmin > 0 for dmin, _ in group_length_range(g))


@SLOW
@given(field=st.sampled_from(GEOM_FIELDS),
       scale=st.one_of(st.floats(0.0, 2.0), st.sampled_from([0.0, 0.5, 1.5])))
def test_arm_parameters_geometry_consistency(field, scale):
    """Scaled geometry fields: either refused naming the field's group, or buildable."""
    from ppamsafety.plant import geometry as geo
    arm = thesis_arm()
    value = getattr(arm.geometry, field) * scale

    def make():
        return arm.replace(geometry=arm.geometry.replace(**{field: value}))
    a = outcome("ArmParameters(geometry=...)", make, field, "ArmGeometry")
    if a is not None:
        g = a.geometry
        q1, q2 = np.meshgrid(np.linspace(g.q1_min, g.q1_max, 9), np.linspace(g.q2_min, g.q2_max, 9))
        e = geo.contractions(np.stack([q1.ravel(), q2.ravel()], -1), a)
        assert np.all(np.isfinite(e)) and e.min() >= -1e-6 and e.max() <= 0.4 + 1e-6
        assert np.all(geo.connection_lengths(a) > 0)


@FAST
@given(field=st.sampled_from(["gravity", "friction_velocity", "geometry", "links", "model"]),
       value=anything)
def test_arm_parameters(field, value):
    a = outcome("ArmParameters", lambda: thesis_arm().replace(**{field: value}),
                f"ArmParameters.{field}")
    if a is not None:
        assert _is_float(getattr(a, field))


@FAST
@given(field=st.sampled_from(["name", "n_muscles", "coefficients", "l0", "slenderness"]),
       value=st.one_of(anything, st.lists(numbers, max_size=6),
                       st.tuples(*[st.floats(-1e-3, 1e-3)] * 5)))
def test_muscle_group(field, value):
    kw = dict(name="g", n_muscles=3, coefficients=thesis_muscles().groups[0].coefficients)
    kw[field] = value
    grp = outcome("MuscleGroup", lambda: MuscleGroup(**kw), f"MuscleGroup.{field}",
                  "MuscleGroup.name")
    if grp is not None:
        assert type(grp.n_muscles) is int and len(grp.coefficients) == 5
        assert all(_is_float(c) for c in grp.coefficients) and grp.coefficients[0] >= 0
        assert _is_float(grp.l0) and grp.l0 > 0


@FAST
@given(field=st.sampled_from(["eps_min", "eps_max", "groups"]), value=anything)
def test_muscle_set(field, value):
    m = outcome("MuscleSet", lambda: thesis_muscles().replace(**{field: value}), "MuscleSet")
    if m is not None:
        assert 0 < m.eps_min < m.eps_max <= 0.4


@FAST
@given(field=st.sampled_from(["v1", "v2", "time_constant"]), value=anything)
def test_valve(field, value):
    kw = dict(v1=0.0, v2=1.0, time_constant=0.05)
    kw[field] = value
    vlv = outcome("Valve", lambda: Valve(**kw), f"Valve.{field}")
    if vlv is not None:
        t = vlv.time_constant
        assert type(t) is float and (t == math.inf or 1e-3 <= t <= 10.0)


@FAST
@given(value=st.one_of(anything, st.lists(anything, min_size=4, max_size=4),
                       st.lists(st.floats(-1.0, 1.0), max_size=5)))
def test_valve_set_time_constants(value):
    vs = outcome("ValveSet.with_time_constants",
                 lambda: thesis_valves().with_time_constants(value), "time_constants",
                 "valve 1 time_constant", "valve 2 time_constant", "valve 3 time_constant",
                 "valve 4 time_constant")
    if vs is not None:
        assert all(v.time_constant >= 1e-3 for v in vs.valves)


@FAST
@given(field=st.sampled_from(["p_mean", "p_max", "p_atm", "polytropic_n"]),
       value=st.one_of(anything, st.lists(numbers, max_size=3)))
def test_pneumatic_params(field, value):
    kw = dict(p_mean=(1.5e5, 1.5e5))
    kw[field] = value
    p = outcome("PneumaticParams", lambda: PneumaticParams(**kw), f"PneumaticParams.{field}",
                "PneumaticParams.p_mean")
    if p is not None:
        assert all(0 <= x <= p.p_max for x in p.p_mean) and _is_float(p.p_atm)


@FAST
@given(field=st.sampled_from(["m1LG1_m2L1", "m1dG1", "IO1_m2L1sq", "m2LG2", "m2dG2", "IS2",
                              "coulomb", "viscous"]),
       value=st.one_of(anything, st.lists(numbers, max_size=3)))
def test_base_parameters(field, value):
    b = outcome("BaseParameters", lambda: identified_dynamic().replace(**{field: value}),
                f"BaseParameters.{field}")
    if b is not None:
        assert np.all(np.isfinite(b.as_vector())) and len(b.coulomb) == len(b.viscous) == 2


LINK_FIELDS = ["m1", "m2", "LG1", "dG1", "LG2", "dG2", "IG1", "IG2", "coulomb", "viscous"]


@FAST
@given(field=st.sampled_from(LINK_FIELDS), value=st.one_of(anything, st.floats(1e-6, 5.0)),
       q2=st.floats(-math.pi, math.pi))
def test_link_inertia_is_positive_definite_when_accepted(field, value, q2):
    links = outcome("LinkInertia", lambda: thesis_arm().links.replace(**{field: value}),
                    f"LinkInertia.{field}")
    if links is not None:
        b = links.base_parameters(0.3)
        a = 0.3 * (b.m2LG2 * math.cos(q2) + b.m2dG2 * math.sin(q2))
        H = np.array([[b.IO1_m2L1sq + b.IS2 + 2 * a, b.IS2 + a], [b.IS2 + a, b.IS2]])
        assert np.all(np.linalg.eigvalsh(H) > -1e-12 * np.abs(H).max())


@FAST
@given(field=st.sampled_from(["name", "mass", "radius", "stiffness", "exponent", "damping"]),
       value=st.one_of(anything, st.floats(1e-12, 1e16)))
def test_head_contact_model(field, value):
    h = outcome("HeadContactModel", lambda: head_model().replace(**{field: value}),
                f"HeadContactModel.{field}", "HeadContactModel.stiffness",
                "HeadContactModel.damping", "HeadContactModel.radius", "HeadContactModel.name")
    if h is not None:
        d = hunt_crossley_max_penetration(h.mass, 5.0, h.stiffness, h.exponent, h.damping)
        assert 1e-4 * 5.0 <= d < h.radius


@FAST
@given(name=st.one_of(anything, st.sampled_from(["thesis-frontal", "iso15066-face", "x"])))
def test_head_model(name):
    h = outcome("head_model", lambda: head_model(name), "name", "head model")
    if h is not None:
        assert isinstance(h, HeadContactModel)


# --- HIC ------------------------------------------------------------------------------

arrays = st.one_of(
    st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=12),
    st.lists(st.floats(0.0, 300.0), min_size=2, max_size=60),
    st.lists(st.lists(st.floats(0.0, 100.0), min_size=1, max_size=5), min_size=1, max_size=3),
    st.lists(st.floats(0.0, 1e200), min_size=2, max_size=5),
    bad_types, special)


@FAST
@given(a=arrays, dt=st.one_of(st.sampled_from([1e-4, 1e-3]), anything),
       window=st.one_of(st.sampled_from([0.036, 0.015]), anything))
def test_hic(a, dt, window):
    r = outcome("hic", lambda: hic(a, dt, window=window), "a", "dt", "window")
    if r is not None:
        v = np.asarray(r.value)
        assert np.all(np.isfinite(v)) and np.all(v >= 0)
        assert np.all(np.asarray(r.t2) - np.asarray(r.t1) <= window * (1 + 1e-9))
        rb = hic_bruteforce(a, dt, window=window)
        np.testing.assert_allclose(rb.value, r.value, rtol=1e-9)


@FAST
@given(fn=st.sampled_from([hic_half_sine, hic_rectangular]),
       amplitude=st.one_of(st.floats(0.0, 500.0), anything),
       duration=st.one_of(st.floats(1e-4, 0.1), anything),
       window=st.one_of(st.sampled_from([0.036, 0.015]), anything))
def test_hic_closed_forms(fn, amplitude, duration, window):
    v = outcome(fn.__name__, lambda: fn(amplitude, duration, window=window),
                "amplitude", "duration", "window")
    if v is not None:
        assert _is_float(v) and v >= 0


# --- head_fit ---------------------------------------------------------------------------

@FAST
@given(k=st.one_of(st.floats(1e3, 1e8), anything), n=st.one_of(st.floats(1.0, 3.0), anything),
       force=st.one_of(st.floats(1.0, 1e3), anything))
def test_iso_effective_spring(k, n, force):
    v = outcome("head_fit.iso_effective_spring", lambda: hf.iso_effective_spring(k, n, force),
                "stiffness", "exponent", "force")
    if v is not None:
        assert _is_float(v) and v > 0


@SLOW
@given(k=st.one_of(st.just(1e6), anything), n=st.one_of(st.just(1.5), anything),
       b=st.one_of(st.just(0.0), anything), dt=st.one_of(st.just(1e-5), anything))
def test_hybrid3_drop(k, n, b, dt):
    v = outcome("head_fit.hybrid3_drop_peak_g", lambda: hf.hybrid3_drop_peak_g(k, n, b, dt=dt),
                "stiffness", "exponent", "damping", "dt")
    if v is not None:
        assert _is_float(v) and v > 0


@SLOW
@given(arm_mass=st.one_of(st.just(2.0), anything), head_mass=st.one_of(st.just(5.0), anything),
       speeds=st.one_of(st.none(), arrays))
def test_hic_curve(arm_mass, head_mass, speeds):
    df = outcome("head_fit.hic_curve",
                 lambda: hf.hic_curve(1e6, 1.5, 1e6, arm_mass=arm_mass, head_mass=head_mass,
                                      speeds=speeds), "arm_mass", "head_mass", "speeds")
    if df is not None:
        assert np.all(np.isfinite(df.to_numpy())) and np.all(df["F_max"] >= 0)


@FAST
@given(arm=anything)
def test_arm_argument_is_checked(arm):
    for name, fn in (("head_fit.default_arm_mass", hf.default_arm_mass),
                     ("head_fit.fit_thesis_head", hf.fit_thesis_head),
                     ("design.torque_function_curves", design.torque_function_curves),
                     ("design.stiffness_map", design.stiffness_map),
                     ("design.max_load_map", design.max_load_map)):
        assert outcome(name, lambda: fn(arm), "arm") is None


# --- design ------------------------------------------------------------------------------

grid_n = st.one_of(st.integers(2, 6), anything)


@SLOW
@given(n=grid_n)
def test_torque_function_curves(n):
    r = outcome("design.torque_function_curves",
                lambda: design.torque_function_curves(thesis_arm(), n=n), "n")
    if r is not None:
        assert np.all(np.isfinite(r.data.to_numpy(float)))


@SLOW
@given(n1=grid_n, n2=grid_n)
def test_stiffness_map(n1, n2):
    r = outcome("design.stiffness_map", lambda: design.stiffness_map(thesis_arm(), n1=n1, n2=n2),
                "n1", "n2")
    if r is not None:
        assert np.all(np.isfinite(r.data.drop(columns="holdable").to_numpy(float)))


@SLOW
@given(p_max=st.one_of(st.none(), st.floats(1e4, 1e6), anything),
       links=st.one_of(st.none(), st.just(identified_dynamic()), bad_types),
       n1=grid_n)
def test_max_load_map(p_max, links, n1):
    r = outcome("design.max_load_map",
                lambda: design.max_load_map(thesis_arm(), links=links, p_max=p_max, n1=n1, n2=4),
                "p_max", "links", "n1")
    if r is not None:
        assert np.all(np.isfinite(r.data.to_numpy(float))) and math.isfinite(r.minimum)


def test_counts_cover_every_entry_point():
    """Runs last in this module (pytest keeps file order): every entry point was exercised."""
    expected = {"ArmGeometry", "ArmParameters", "MuscleGroup", "MuscleSet", "Valve",
                "ValveSet.with_time_constants", "PneumaticParams", "BaseParameters",
                "LinkInertia", "HeadContactModel", "head_model", "hic", "hic_half_sine",
                "hic_rectangular", "head_fit.iso_effective_spring",
                "head_fit.hybrid3_drop_peak_g", "head_fit.hic_curve",
                "design.torque_function_curves", "design.stiffness_map", "design.max_load_map"}
    if len(_REC.counts) < 5:     # run alone (-k): nothing to check
        pytest.skip("run the whole module to collect the counts")
    assert expected <= set(_REC.counts)
