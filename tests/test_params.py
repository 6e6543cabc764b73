"""Parameter sets: immutability, validation with clear messages, provenance."""

import dataclasses
import math

import pytest

from ppamsafety.params import (ArmGeometry, LinkInertia, MuscleGroup, PneumaticParams, Valve,
                               derive_physical_links, identified_dynamic, thesis_arm,
                               thesis_geometry)
from ppamsafety.units import BAR, MM


def test_thesis_values_converted_to_si():
    g = thesis_geometry()
    assert g.L12 == pytest.approx(0.315)          # Table 2.1: 315.0 mm
    assert g.q1_max == pytest.approx(math.radians(105))
    arm = thesis_arm()
    a = arm.muscles.groups[1].coefficients        # Table B.1 group 2, N/bar -> N/Pa
    assert a[1] == pytest.approx(-671.791 / BAR)
    assert arm.valves.valves[3].v1 == pytest.approx(0.0078 * BAR)   # Table B.2
    assert arm.pneumatics.p_max == pytest.approx(3 * BAR)


def test_parameter_sets_are_immutable():
    arm = thesis_arm()
    with pytest.raises(dataclasses.FrozenInstanceError):
        arm.gravity = 0.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        arm.geometry.L1 = 1.0


@pytest.mark.parametrize("make, field", [
    (lambda: thesis_geometry().replace(L1=-0.3), "ArmGeometry.L1"),
    (lambda: thesis_geometry().replace(d12=float("nan")), "ArmGeometry.d12"),
    (lambda: thesis_geometry().replace(q1_min=2.0, q1_max=1.0), "q1_min"),
    (lambda: Valve(v1=0.0, v2=0.99, time_constant=-0.1), "Valve.time_constant"),
    (lambda: Valve(v1=0.0, v2=7.0, time_constant=0.05), "Valve.v2"),
    (lambda: MuscleGroup("g", 0, (1, 1, 1, 1, 1)), "MuscleGroup.n_muscles"),
    (lambda: MuscleGroup("g", 3, (1, 1, 1)), "MuscleGroup.coefficients"),
    (lambda: PneumaticParams(p_mean=(4 * BAR, 1 * BAR)), "PneumaticParams.p_mean[0]"),
    (lambda: LinkInertia(m1=-1, m2=1, LG1=0.1, dG1=0, LG2=0.1, dG2=0, IG1=0.01, IG2=0.01),
     "LinkInertia.m1"),
    (lambda: identified_dynamic().replace(viscous=(0.1, -0.2)), "BaseParameters.viscous[1]"),
    (lambda: thesis_arm().replace(gravity=-9.81), "ArmParameters.gravity"),
])
def test_invalid_values_raise_value_error_naming_the_field(make, field):
    with pytest.raises(ValueError, match=field.replace("[", r"\[").replace("]", r"\]")):
        make()


def test_range_error_states_the_allowed_interval():
    with pytest.raises(ValueError, match=r"Valve.time_constant = 20 s is outside \[0.001, 10\] s"):
        Valve(v1=0.0, v2=1.0, time_constant=20.0)


def test_closed_valve_is_allowed():
    assert Valve(v1=0.0, v2=1.0, time_constant=math.inf).time_constant == math.inf


def test_physical_links_reconcile_the_thesis_evidence():
    """The plant's links come from a documented weighted least-squares compromise."""
    res = derive_physical_links()
    links = res.links
    # masses near the text's 1.5 / 'just over 1' kg, total ~2.5 kg (§6.3.3, §2.3.3.5)
    assert 2.2 < links.m1 + links.m2 < 2.7
    # the well-identified gravity moment is met within its standard deviation
    fit, target, sd = res.residuals["m1 L_G1 + m2 L1 [kg m]"]
    assert abs(fit - target) < sd
    # every piece of evidence within 3 standard deviations
    for name, (fit, target, sd) in res.residuals.items():
        assert abs(fit - target) < 3 * sd, name


def test_plant_base_parameters_satisfy_parallel_axis(arm):
    L, b = arm.links, arm.plant_base
    L1 = arm.geometry.L1
    assert b.IS2 == pytest.approx(L.IG2 + L.m2 * (L.LG2 ** 2 + L.dG2 ** 2), rel=1e-12)
    assert b.IO1_m2L1sq == pytest.approx(L.IG1 + L.m1 * (L.LG1 ** 2 + L.dG1 ** 2) + L.m2 * L1 ** 2)
    # physically consistent: theta3 > m2 L1^2, unlike the identified Table 3.5 set
    assert b.IO1_m2L1sq > L.m2 * L1 ** 2
    assert identified_dynamic().IO1_m2L1sq < L.m2 * L1 ** 2


def test_replace_returns_validated_copy():
    g = thesis_geometry()
    g2 = g.replace(L2=0.4)
    assert g2.L2 == 0.4 and g.L2 == pytest.approx(310 * MM)
    assert isinstance(g2, ArmGeometry)
