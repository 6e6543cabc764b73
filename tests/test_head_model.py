"""Head contact models and the reconstruction of the thesis' parameters."""

import math

import numpy as np
import pytest

from ppamsafety.impact import head_fit as hf
from ppamsafety.impact.head import HeadContactModel, head_model, head_model_names
from ppamsafety.units import G0


def test_named_models_and_errors():
    names = head_model_names()
    assert {"thesis-frontal", "iso15066-forehead", "iso15066-face", "child-frontal"} <= set(names)
    assert head_model("iso15066-forehead").stiffness == pytest.approx(150e3)   # 150 N/mm
    assert head_model().mass == 5.0                                          # thesis §6.3.2
    with pytest.raises(ValueError, match="unknown head model"):
        head_model("alien")
    with pytest.raises(ValueError, match="exponent"):
        head_model().replace(exponent=0.2)
    with pytest.raises(ValueError, match=r"HeadContactModel.mass \(model 'x'\) = -1 kg"):
        HeadContactModel("x", mass=-1, radius=0.1, stiffness=1e5, exponent=1, damping=0)


def test_force_is_never_negative():
    h = head_model()
    f = h.force(np.linspace(-1e-3, 5e-3, 50), -100.0)
    assert np.all(f >= 0) and np.all(f[:9] == 0)


def test_drop_test_oracle_for_a_linear_spring():
    """Linear undamped contact: peak force v sqrt(k m) exactly (energy balance)."""
    v = math.sqrt(2 * G0 * hf.HYBRID3_DROP_HEIGHT)
    m = hf.HYBRID3_HEAD_MASS
    k = (250 * m * G0) ** 2 / (m * v * v)
    assert hf.hybrid3_drop_peak_g(k, 1.0, 0.0, dt=1e-7) == pytest.approx(250.0, rel=1e-5)


def test_iso_effective_spring_of_a_linear_contact_is_k():
    assert hf.iso_effective_spring(150e3, 1.0, 130.0) == pytest.approx(150e3)


def test_stored_thesis_model_is_the_fit_output(arm):
    """impact.head stores the rounded output of fit_thesis_head (provenance check)."""
    fit = hf.fit_thesis_head(arm)
    h = head_model()
    assert h.exponent == fit.exponent == 1.5
    assert h.stiffness == pytest.approx(fit.stiffness, rel=0.03)
    assert h.damping == pytest.approx(fit.damping, rel=0.03)
    assert fit.rms_sigma < 1.0                         # Table 6.1 pairs within 1 sd on average


def test_force_is_the_engine_contact_law_and_broadcasts():
    """HeadContactModel.force evaluates the same compiled law as the impact engine (issue 7)."""
    from ppamsafety.impact.contact import hunt_crossley_force

    h = head_model()
    d = np.array([-1e-3, 0.0, 1e-4, 2e-3])[:, None]
    dd = np.array([-2.0, -0.1, 0.0, 0.5, 3.0])
    f = h.force(d, dd)
    assert f.shape == (4, 5)
    ref = [[hunt_crossley_force(a, b, h.stiffness, h.exponent, h.damping) for b in dd]
           for a in d[:, 0]]
    np.testing.assert_array_equal(f, ref)
    # thesis eq. 6.2 by hand where it is positive
    assert f[3, 3] == pytest.approx(2e-3 ** 1.5 * (h.stiffness + h.damping * 0.5), rel=1e-14)
    assert np.all(f[:2] == 0.0) and f[2, 0] == 0.0            # no contact / clipped at zero
    assert np.ndim(h.force(1e-3)) == 0 and h.force(1e-3) > 0
    with pytest.raises(ValueError, match="delta_dot"):
        h.force(1e-3, np.nan)
    with pytest.raises(ValueError, match="broadcast"):
        h.force(np.ones(3), np.ones(2))
