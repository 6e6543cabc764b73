"""The effects study (ppamsafety.sections.effects): quick compute -> render, and the sawtooth physics."""

import numpy as np
import pytest

from ppamsafety.sections import REGISTRY, effects


@pytest.fixture(scope="module")
def study():
    return effects.compute(quick=True)


def test_registered_after_lambda_sweep():
    assert REGISTRY.index("effects") == REGISTRY.index("lambda_sweep") + 1


def test_render_has_tables_figures_and_finite_numbers(study):
    sec = effects.render(study)
    names = [n for n, _ in sec.artifacts]
    for f in ("effects_sawtooth_angles.png", "effects_sawtooth_errors.png",
              "effects_sawtooth_forces.png", "effects_ratio_shift.png", "effects_sawtooth.csv",
              "effects_summary.csv", "effects_ratios.csv", "effects_table_5_2.csv",
              "effects_table_6_1.csv", "effects_conclusions.csv"):
        assert f in names
        assert f in sec.markdown or f.endswith(".csv")
    assert "2.47" in sec.markdown and "2.06" in sec.markdown
    assert "nan" not in sec.markdown.lower()
    s = study.sawtooth_summary
    assert np.all(np.isfinite(s[["rms_q1_deg", "rms_q2_deg", "gap_q1_deg", "gap_q2_deg"]]))
    assert np.all(np.isfinite(study.ratios["median |ln ratio|"]))
    assert len(study.ratios) == 8                       # 4 tables x 2 plants
    for lab in study.cases:
        assert len(study.comparison[lab]) == 30         # 10 variants x 3 periods
        assert len(study.table_6_1[lab]) == 20          # 10 variants x step/switch
        assert len(study.conclusions[lab]) == 6
        assert not study.circle_errors[lab].diverged.any()
    assert np.all(np.isfinite(study.limit_cycle[["mean_m", "max_m"]]))


def test_sawtooth_direction_pattern_with_hysteresis(study):
    """What the physics guarantees (thesis §3.5.1.6, §3.6).

    With hysteresis the force of a muscle is below the model on a rising branch of its
    contraction and above on a falling branch (at equal contraction the falling branch lies
    above the rising one, (3.35) with the Preisach memory).  For a joint set to rise, the
    contracting (agonist) muscle therefore pulls less and its antagonist more than the
    gravity compensation expects, so the joint settles lower than after a falling approach of
    the same set angle: the gap e_falling - e_rising at equal set angle is positive.  The
    nominal plant has no memory, so its gap is zero (to the settling residue).  Whether the
    error is below or above the *set point* also depends on the static bias of the identified
    gravity model (on q1 all nominal errors are negative), so the majority assertion is on
    the error relative to the joint's mean error over the windows.
    """
    s = study.sawtooth_summary.set_index("plant")
    h, n = s.loc["hysteresis"], s.loc["nominal"]
    for j in (1, 2):
        assert h[f"gap_q{j}_deg"] > 0.1                   # deg, a clear hysteresis gap
        assert abs(n[f"gap_q{j}_deg"]) < 0.02             # no memory: same angle both ways
        assert h[f"pattern_unbiased_q{j}"] > h[f"steps_q{j}"] / 2
    # the muscle forces: a growing contraction below the model, a shrinking one above
    assert h.contracting_below + h.extending_above > h.moving_groups / 2
    assert n.contracting_below + n.extending_above == 0   # nominal plant = the model


def test_sawtooth_reference_windows_and_validation(study):
    from ppamsafety.params import thesis_arm

    lv = effects.sawtooth_levels(quick=True)
    ref, w = effects.sawtooth_reference(thesis_arm(), lv)
    assert w.shape == (lv.shape[0], 2)
    qd = ref.field("q_d")
    for i, (a, b) in enumerate(w):                        # set angle constant in each window
        np.testing.assert_array_equal(qd[a:b], np.broadcast_to(lv[i], (b - a, 2)))
    assert np.all(np.diff(w[:, 0]) > 0) and w[-1, 1] == ref.n_steps
    with pytest.raises(ValueError, match="settle"):
        effects.sawtooth_reference(thesis_arm(), lv, settle=0.0)
    with pytest.raises(ValueError, match="levels"):
        effects.sawtooth_reference(thesis_arm(), lv[:1])
    with pytest.raises(ValueError, match="delta"):
        effects.compute(quick=True, delta=1.5)
