"""PPAM force law (3.9) and the volume derived from it (dV/deps = l0 F/p)."""

import numpy as np
import pytest

from ppamsafety.params.muscles import TABLE_B1_N_PER_BAR
from ppamsafety.plant import muscle
from ppamsafety.units import BAR


@pytest.mark.parametrize("group", [1, 2, 3, 4])
def test_force_law_matches_table_B1(arm, group):
    """F = p (a0/eps + a1 + a2 eps + a3 eps^2 + a4 eps^3), p in bar (3.9)."""
    a0, a1, a2, a3, a4 = TABLE_B1_N_PER_BAR[group - 1]
    eps = np.linspace(0.06, 0.25, 9)
    p_bar = 1.7
    expected = p_bar * (a0 / eps + a1 + a2 * eps + a3 * eps ** 2 + a4 * eps ** 3)
    np.testing.assert_allclose(muscle.muscle_force(group, eps, p_bar * BAR, arm), expected,
                               rtol=1e-12)


@pytest.mark.parametrize("group", [1, 2, 3, 4])
def test_volume_derivative_equals_force_per_pressure(arm, group):
    """dV/deps = l0 F/p for one muscle (from F = -p dV/dl, eq. (2.1))."""
    l0 = arm.muscles.groups[group - 1].l0
    eps = np.linspace(0.02, 0.40, 77)
    h = 1e-5
    dV = (muscle.muscle_volume_of(group, eps + h, arm)
          - muscle.muscle_volume_of(group, eps - h, arm)) / (2 * h)
    np.testing.assert_allclose(dV, l0 * muscle.force_function(group, eps, arm), rtol=1e-6,
                               atol=1e-12)


@pytest.mark.parametrize("group", [1, 2, 3, 4])
def test_force_is_never_negative_and_volume_increases(arm, group):
    eps = np.linspace(-0.05, 0.6, 400)
    assert np.all(muscle.force_function(group, eps, arm) >= 0)
    assert np.all(np.diff(muscle.muscle_volume_of(group, eps, arm)) >= 0)


def test_group_volume_is_n_times_muscle_volume(arm):
    eps = np.array([0.1, 0.2])
    for g in (1, 2):
        n = arm.muscles.groups[g - 1].n_muscles
        np.testing.assert_allclose(muscle.group_volume(g, eps, arm),
                                   n * muscle.muscle_volume_of(g, eps, arm))


def test_volume_anchor_is_above_the_uncontracted_cylinder(arm):
    """V(eps) is anchored on the cylinder pi R^2 l0 (R = l0/6) at eps = 0."""
    grp = arm.muscles.groups[0]
    v_cyl = np.pi * grp.radius ** 2 * grp.l0
    v5 = muscle.muscle_volume_of(1, 0.05, arm)
    assert v_cyl < v5 < 4 * v_cyl


def test_group_number_is_validated(arm):
    with pytest.raises(ValueError, match="group"):
        muscle.force_function(5, 0.1, arm)
