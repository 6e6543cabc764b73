"""Validation helpers and parameter-set consistency checks: one test per reported failure."""

import math

import numpy as np
import pytest

from ppamsafety import _validation as v
from ppamsafety import design
from ppamsafety.impact import head_fit as hf
from ppamsafety.impact.contact import max_penetration
from ppamsafety.impact.hic import hic, hic_half_sine, hic_rectangular
from ppamsafety.params import (ArmGeometry, BaseParameters, LinkInertia, MuscleGroup, MuscleSet,
                               PneumaticParams, Valve, ValveSet, identified_dynamic, thesis_arm,
                               thesis_geometry, thesis_muscles, thesis_valves)
from ppamsafety.params.geometry import group_lengths
from ppamsafety.impact.head import head_model
from ppamsafety.impact.contact import hunt_crossley_max_penetration
from ppamsafety.units import BAR


# --- helpers --------------------------------------------------------------------------

@pytest.mark.parametrize("value, exc, match", [
    ("abc", TypeError, r"n must be a real number, got 'abc'"),
    (None, TypeError, r"n must be a real number, got None"),
    (True, TypeError, r"n must be an integer, got a bool"),
    (2.5, ValueError, r"n must be an integer, got 2.5"),
    (math.nan, ValueError, r"n must be an integer"),
    (0, ValueError, r"n = 0 is outside \[1, 5\]"),
])
def test_check_int_names_the_argument(value, exc, match):
    with pytest.raises(exc, match=match):
        v.check_int("n", value, 1, 5)


def test_check_int_accepts_integral_numbers():
    assert v.check_int("n", 3.0, 1, 5) == 3 and type(v.check_int("n", np.int64(4), 1, 5)) is int


@pytest.mark.parametrize("value", ["1.5", None, {"a": 1}, 1j, True, [1.0], np.array([1.0])])
def test_check_finite_refuses_non_numbers_with_type_error(value):
    with pytest.raises(TypeError, match="x must be a real number"):
        v.check_finite("x", value)


def test_type_errors_are_also_value_errors_for_existing_handlers():
    with pytest.raises(ValueError):
        v.check_finite("x", "abc")


def test_range_message_names_value_and_interval():
    with pytest.raises(ValueError, match=r"valve 2 time_constant = -0.1 s is outside \(0, inf\) s"):
        v.check_positive("valve 2 time_constant", -0.1, unit="s")


@pytest.mark.parametrize("value, exc, match", [
    (np.array([1, "a"], dtype=object), TypeError, "q must be an array of real numbers"),
    (np.array([1j, 2.0]), TypeError, "complex"),
    (["a", "b"], TypeError, "strings"),
    ([[1.0, 2.0], [3.0]], ValueError, "ragged"),
    ([True, False], TypeError, "bool"),
    (np.zeros((3, 3)), ValueError, r"q must have trailing shape \(\.\.\., 2\), got shape \(3, 3\)"),
    ([1.0, np.inf], ValueError, "q contains NaN or inf"),
])
def test_as_float_array_refuses_with_named_messages(value, exc, match):
    with pytest.raises(exc, match=match):
        v.as_float_array("q", value, shape_tail=(2,))


def test_shape_helpers():
    with pytest.raises(ValueError, match="qd has 4 rows, q has 1"):
        v.check_same_rows("q", np.zeros((1, 2)), "qd", np.zeros((4, 2)))
    with pytest.raises(ValueError, match=r"t must be strictly increasing, but t\[1\] = 2"):
        v.check_increasing("t", np.array([1.0, 2.0, 2.0]))
    with pytest.raises(ValueError, match=r"x must have shape \(n, 2\), got \(3,\)"):
        v.check_shape("x", np.zeros(3), (None, 2))
    with pytest.raises(TypeError, match="flag must be True or False"):
        v.check_bool("flag", 1)


# --- parameter sets store converted values -------------------------------------------

def test_parameter_sets_store_converted_values():
    g = thesis_geometry().replace(L1=np.float32(0.3), d42=0)
    assert type(g.L1) is float and type(g.d42) is float
    grp = MuscleGroup("g", np.int64(3), np.array([1e-4, 1e-3, 0, 0, 0]))
    assert type(grp.n_muscles) is int and isinstance(grp.coefficients, tuple)
    assert all(type(c) is float for c in grp.coefficients)
    p = PneumaticParams(p_mean=np.array([1.0, 1.5]) * BAR)
    assert p.p_mean == (1.0e5, 1.5e5) and type(p.p_mean) is tuple


@pytest.mark.parametrize("make, match", [
    (lambda: thesis_geometry().replace(L22="0.2"), "ArmGeometry.L22 must be a real number"),
    (lambda: thesis_geometry().replace(L1=None), "ArmGeometry.L1 must be a real number"),
    (lambda: Valve(v1=0.0, v2=True, time_constant=0.05), "Valve.v2 must be a real number"),
    (lambda: MuscleGroup("g", "3", (1, 1, 1, 1, 1)), r"MuscleGroup.n_muscles \(group 'g'\)"),
    (lambda: MuscleSet(groups="abcd"), "MuscleSet.groups must be a tuple"),
    (lambda: ValveSet(valves=[1, 2, 3, 4]), r"ValveSet.valves\[0\] must be a Valve"),
    (lambda: thesis_arm().replace(links=identified_dynamic()),
     "ArmParameters.links must be a LinkInertia"),
    (lambda: PneumaticParams(p_mean="ab"), "PneumaticParams.p_mean must be a sequence"),
    (lambda: identified_dynamic().replace(coulomb=0.1), "BaseParameters.coulomb must be a seq"),
])
def test_wrong_types_raise_type_error_naming_class_and_field(make, match):
    with pytest.raises(TypeError, match=match):
        make()


# --- physically inconsistent sets ---------------------------------------------------

def test_zero_l22_is_refused_naming_the_group_and_fields():
    arm = thesis_arm()
    with pytest.raises(ValueError, match=r"muscle group 2 .* connection length L_conn = -0.1"
                                         r".*ArmGeometry.L22"):
        arm.replace(geometry=arm.geometry.replace(L22=0.0))


def test_coincident_attachment_points_are_refused_by_the_geometry():
    # A12 at the base point A11: group 1 has zero length at some q1
    with pytest.raises(ValueError, match=r"muscle group 1 has length .*ArmGeometry.X11"):
        thesis_geometry().replace(X11=0.0, Y11=0.0, L12=0.0, d12=0.0)


def test_too_large_working_area_for_the_muscles_is_refused():
    arm = thesis_arm()
    with pytest.raises(ValueError, match=r"contractions from .* outside \[0, 0.4\]"):
        arm.replace(geometry=arm.geometry.replace(q2_min=-3.0))


def test_working_area_must_lie_inside_minus_pi_pi():
    with pytest.raises(ValueError, match=r"ArmGeometry.q1_max = 3.2 rad is outside \(-3.14159"):
        thesis_geometry().replace(q1_max=3.2)


def test_numpy_group_lengths_match_the_compiled_kernels(arm, workspace_grid):
    from ppamsafety.plant import geometry as geo
    d = geo.muscle_lengths(workspace_grid, arm)
    np.testing.assert_allclose(group_lengths(arm.geometry, workspace_grid[:, 0],
                                             workspace_grid[:, 1]), d, rtol=1e-12)


def test_thesis_contractions_are_within_the_checked_range(arm, workspace_grid):
    from ppamsafety.plant import geometry as geo
    e = geo.contractions(workspace_grid, arm)
    assert e.min() >= 0.0 and e.max() <= 0.4


def test_valve_time_constant_below_one_millisecond_is_refused():
    with pytest.raises(ValueError, match=r"Valve.time_constant = 0.0005 s is outside \[0.001, 10\]"):
        Valve(v1=0.0, v2=1.0, time_constant=5e-4)
    with pytest.raises(ValueError, match=r"valve 2 time_constant = -0.1 s is outside"):
        thesis_valves().with_time_constants([0.05, -0.1, 0.05, 0.05])
    assert thesis_valves().with_time_constants([math.inf] * 4).valves[0].time_constant == math.inf


def test_identified_indefinite_model_is_accepted_but_singular_plant_inertia_is_not():
    from ppamsafety.params.arm import _check_plant_inertia
    th = identified_dynamic()   # Table 3.5: theta3 < m2 L1^2, indefinite; must stay accepted
    assert th.IO1_m2L1sq < 1.0 * 0.3 ** 2
    arm = thesis_arm()
    _check_plant_inertia(arm.geometry, arm.links)          # the plant: fine
    # point masses on straight links with q2 = 0 in the working area: det H = 0 there
    g = arm.geometry.replace(q2_min=-0.1, q2_max=0.1)
    point = LinkInertia(m1=1e-9, m2=1.0, LG1=0.1, dG1=0.0, LG2=0.2, dG2=0.0, IG1=1e-15,
                        IG2=1e-15)
    with pytest.raises(ValueError, match=r"inertia matrix is \(nearly\) singular at q2 = 0"):
        _check_plant_inertia(g, point)


def test_head_model_refuses_a_radius_the_tool_passes_through():
    with pytest.raises(ValueError, match=r"HeadContactModel.radius .* = 1e-09 m is outside"):
        head_model().replace(radius=1e-9)
    with pytest.raises(ValueError, match=r"penetrate .* beyond HeadContactModel.radius"):
        head_model("iso15066-face").replace(stiffness=1e3)


def test_head_model_refuses_a_contact_too_short_to_integrate():
    with pytest.raises(ValueError, match=r"HeadContactModel.damping too large"):
        head_model().replace(damping=1e15)


def test_head_check_uses_the_contact_closed_form():
    for b in (0.0, 1.0, 3.3e6):
        assert hunt_crossley_max_penetration(5.0, 5.0, 9.5e5, 1.5, b) == pytest.approx(
            max_penetration(5.0, 5.0, 9.5e5, 1.5, b), rel=1e-12)


def test_head_model_name_must_be_a_string():
    with pytest.raises(TypeError, match="name must be a string"):
        head_model(3)


# --- hic, head_fit, design --------------------------------------------------------------

def test_hic_refuses_overflow_instead_of_returning_inf():
    with pytest.raises(ValueError, match=r"a \(max 1e\+300 g\).*beyond the float64 range"):
        hic([1e300, 1e300, 0.0], 1e-4)
    with pytest.raises(ValueError, match="amplitude = 1e\\+200 g"):
        hic_rectangular(1e200, 0.01)
    with pytest.raises(ValueError, match="amplitude"):
        hic_half_sine(1e200, 0.01)


def test_hic_window_far_longer_than_the_record_is_fine():
    r = hic(np.ones(11), 1e-3, window=1e300)
    assert r.value == pytest.approx(0.01)
    r = hic(np.ones(11), 1e-9, window=1e300)      # window / dt overflows: capped
    assert math.isfinite(r.value)
    with pytest.raises(ValueError, match=r"dt = 1e-300 s is outside \[1e-09, 1000\] s"):
        hic(np.ones(11), 1e-300, window=1.0)      # a unit mistake, not a sample step (issue 22)


@pytest.mark.parametrize("call, exc, match", [
    (lambda: hic("abc", 1e-3), TypeError, "a must be an array of real numbers"),
    (lambda: hic([1.0, 2.0], "1e-3"), TypeError, "dt must be a real number"),
    (lambda: hic([1.0, 2.0], 1e-3, window=None), TypeError, "window must be a real number"),
    (lambda: hic([1.0, 2.0j], 1e-3), TypeError, "complex"),
    (lambda: hf.iso_effective_spring(-1.0, 1.0, 130.0), ValueError, "stiffness"),
    (lambda: hf.hybrid3_drop_peak_g(1e5, 1.0, 0.0, dt=1e-12), ValueError, "dt"),
    (lambda: hf.hic_curve(1e5, 1.0, 0.0, arm_mass=2.0, speeds=[1.0, -1.0]), ValueError,
     r"speeds\[1\]"),
    (lambda: hf.hic_curve(1e5, 1.0, 0.0, arm_mass="2"), TypeError, "arm_mass"),
    (lambda: hf.default_arm_mass(None), TypeError, "arm must be a ArmParameters"),
    (lambda: hf.fit_thesis_head(thesis_arm(), head_mass=0.0), ValueError, "head_mass"),
    (lambda: design.torque_function_curves("arm"), TypeError, "arm must be a ArmParameters"),
    (lambda: design.stiffness_map(thesis_arm(), n1=2.5), ValueError, "n1 must be an integer"),
    (lambda: design.max_load_map(thesis_arm(), links=identified_dynamic()), TypeError,
     "links must be a LinkInertia"),
    (lambda: design.max_load_map(thesis_arm(), p_max=math.nan), ValueError, "p_max"),
])
def test_public_functions_name_the_bad_argument(call, exc, match):
    with pytest.raises(exc, match=match):
        call()


def test_muscle_set_contraction_limit_is_the_ppam_maximum():
    with pytest.raises(ValueError, match=r"MuscleSet.eps_max = 0.5 is outside \(0, 0.4\]"):
        thesis_muscles().replace(eps_max=0.5)


def test_base_parameters_keep_float_fields():
    b = BaseParameters(1, 0, 1, 0, 0, 1, coulomb=[0, 0], viscous=np.array([0.1, 0.2]))
    assert type(b.m1LG1_m2L1) is float and b.viscous == (0.1, 0.2)
    li = LinkInertia(1, 1, 0.1, 0, 0.1, 0, 0.01, 0.01)
    assert type(li.m1) is float and li.coulomb == (0.0, 0.0)
    assert isinstance(ArmGeometry, type)
