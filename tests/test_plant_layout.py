"""The declared plant parameter row (plant/layout.py) and the single-source force polynomial."""

import re
from pathlib import Path

import numpy as np
import pytest

import ppamsafety
from ppamsafety.params.muscles import TABLE_B1_N_PER_BAR
from ppamsafety.plant import layout as lay
from ppamsafety.plant import packing
from ppamsafety.plant import muscle
from ppamsafety.units import BAR

#: Offsets numbered by hand before the declared layout (commit 4530509); the kernels'
#: memory order must not change.
HAND_OFFSETS = dict(X11=0, Y11=1, X21=2, Y21=3, L12=4, D12=5, L22=6, D22=7, L32=8, D32=9,
                    L42=10, D42=11, L33=12, D33=13, L43=14, D43=15, L1=16, L2=17, LL=18, DL=19,
                    LCONN=20, NM=24, L0=28, COEF=32, EPS_A=52, V_C=56, EPS_F0=60, TV=64, V1=68,
                    V2=72, PM1=76, PM2=77, PMAX=78, PATM=79, NPOLY=80, TH=81, COUL=87, VISC=89,
                    GRAV=91, VFRIC=92)


def test_declared_layout_keeps_the_hand_numbered_order():
    for name, off in HAND_OFFSETS.items():
        assert getattr(lay, name) == off, name
    assert lay.EFFECTS_START == 93                          # effects appended, nothing moved
    assert lay.NP == lay.PLANT.size == 93 + lay.EFFECTS.size
    assert [lay.THETA1, lay.THETA6] == [lay.TH, lay.TH + 5]
    assert lay.PLANT.columns()[lay.COEF:lay.COEF + 6] == ["a0_g1", "a1_g1", "a2_g1", "a3_g1",
                                                          "a4_g1", "a0_g2"]


def test_pack_fills_fields_by_name(arm):
    P = packing.pack(arm)
    assert P.shape == (lay.NP,) and not P.flags.writeable
    np.testing.assert_array_equal(lay.PLANT.read(P, "theta"), arm.plant_base.as_vector())
    np.testing.assert_array_equal(lay.PLANT.read(packing.model_view(arm), "theta"),
                                  arm.model.as_vector())
    np.testing.assert_array_equal(lay.PLANT.read(packing.controller_view(arm), "theta"),
                                  arm.model_gravity.as_vector())
    assert P[lay.THETA4] == arm.plant_base.as_vector()[3]
    np.testing.assert_array_equal(lay.PLANT.read(P, "p_mean"), arm.pneumatics.p_mean)
    assert lay.PLANT.read(P, "L1") == arm.geometry.L1
    assert lay.PLANT.read(P, "dL") == arm.geometry.dL
    np.testing.assert_array_equal(lay.PLANT.read(P, "tv"),
                                  [v.time_constant for v in arm.valves.valves])
    np.testing.assert_array_equal(lay.PLANT.read(P, "coef"),
                                  np.concatenate([g.coefficients for g in arm.muscles.groups]))


def test_kernels_name_the_base_parameters():
    """No ``TH + i`` offsets outside layout.py: theta1..theta6 have their own constants."""
    root = Path(ppamsafety.__file__).parent
    pat = re.compile(r"\bTH\s*\+\s*\d")
    hits = [f"{p.relative_to(root)}:{i + 1}" for p in root.rglob("*.py") if p.name != "layout.py"
            for i, line in enumerate(p.read_text().splitlines()) if pat.search(line)]
    assert not hits, hits


@pytest.mark.parametrize("group", [1, 2, 3, 4])
def test_polynomial_and_antiderivative_kernels(arm, group):
    """polynomial = Table B.1 form of (3.9); d/deps antiderivative = polynomial."""
    coef = arm.muscles.groups[group - 1].coefficients
    a0, a1, a2, a3, a4 = np.array(TABLE_B1_N_PER_BAR[group - 1]) / BAR
    eps = np.linspace(0.02, 0.5, 49)
    np.testing.assert_allclose(muscle.polynomial(coef, eps),
                               a0 / eps + a1 + a2 * eps + a3 * eps ** 2 + a4 * eps ** 3,
                               rtol=1e-12, atol=1e-18)
    h = 1e-6
    num = (muscle.antiderivative(coef, eps + h) - muscle.antiderivative(coef, eps - h)) / (2 * h)
    np.testing.assert_allclose(num, muscle.polynomial(coef, eps), rtol=1e-7, atol=1e-12)
    # the group-indexed raw polynomial (used by the design study) is the same kernel
    np.testing.assert_array_equal(muscle.force_polynomial(group, eps, arm),
                                  muscle.polynomial(coef, eps))
    with pytest.raises(ValueError, match="coefficients"):
        muscle.polynomial(coef[:4], eps)


def test_pack_time_muscle_data_use_the_kernel_polynomial(arm, monkeypatch):
    """Zero-force root, anchor volume and volume constant go through muscle.polynomial /
    muscle.poly_value / muscle.antiderivative (no second copy of (3.9))."""
    calls = {"polynomial": 0, "poly_value": 0, "antiderivative": 0}
    for name in calls:
        orig = getattr(muscle, name)

        def spy(*a, _orig=orig, _name=name):
            calls[_name] += 1
            return _orig(*a)
        monkeypatch.setattr(muscle, name, spy)
    terms = muscle.muscle_terms.__wrapped__(arm.muscles)       # bypass the cache
    assert all(n >= 4 for n in calls.values()), calls
    assert terms == muscle.muscle_terms(arm.muscles)
    assert packing._muscle_terms(arm.geometry, arm.muscles)[1:] == terms    # pack uses them
    # the root is where the kernel force law reaches zero
    P = packing.pack(arm)
    for k, grp in enumerate(arm.muscles.groups):
        e0 = P[lay.EPS_F0 + k]
        if e0 < 0.6:
            assert abs(float(muscle.polynomial(grp.coefficients, e0))) < 1e-12 * BAR
            assert muscle.force_polynomial(k + 1, e0 + 1e-3, arm) < 0.0
            assert muscle.force_function(k + 1, e0 + 1e-3, arm) == 0.0
