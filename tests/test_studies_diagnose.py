"""The discrepancy-diagnosis report section (ppamsafety.sections.diagnose_cases), quick mode."""

import numpy as np

from ppamsafety.thesis_fits.summary_fit import AXES, axis, fit_summary, plant_at, whitened
from ppamsafety.params import thesis_arm
from ppamsafety.plant import packing
from ppamsafety.sections import REGISTRY, diagnose_cases


def test_section_quick_names_both_hidden_effects_and_shrinks_the_gap(tmp_path):
    st = diagnose_cases.compute(quick=True)
    # case (c): friction (3x Coulomb) and a 20 ms valve dead time, both named from 6 s
    assert {"joint_friction", "valve_dead_time"} <= set(st.case_c.names)
    d = st.case_c_table.set_index("parameter").loc["d"]
    # dead time within +-2 samples of 20 ms (the open-loop battery's tolerance), compared in
    # whole samples (the fit is a whole number of 1 ms samples)
    assert abs(round(d.fitted / 1e-3) - 20) <= 2
    gap = st.case_c_gap.set_index("channel")
    # the gap of the angles shrinks to within 20 % of the noise level
    assert np.all(gap.loc[["q1", "q2"], "after_over_noise"] < 1.2)
    assert np.all(gap.loc[["q1", "q2"], "before_over_noise"] > 2.0)
    # battery: nothing hidden -> nothing named; payload -> payload
    assert st.battery["correct"].all(), st.battery
    # case (b): a slower valve makes every tracking error larger, so it moves the
    # simulated statistics toward the (larger) thesis values
    row = st.summary.table.set_index("effect").loc["valve_time_constant_factor"]
    assert row.chi2_reduction > 0.5 and row.ratio_geo_mean > st.summary.metrics[
        "nominal_ratio_geo_mean"]
    sec = diagnose_cases.render(st)
    names = [a for a, _ in sec.artifacts]
    assert "diagnose_case_c_replay.png" in names and "diagnose_confusion.png" in names
    assert "Case (b)" in sec.markdown and "Case (c)" in sec.markdown
    assert "diagnose_cases" in REGISTRY


def test_effect_axes_cover_the_library_and_change_the_plant_row():
    from ppamsafety.params.effects import Effects

    arm = thesis_arm()
    # the axes are those the effects declare (derived), one per effect that has one
    assert AXES == Effects.axes()
    declared = [n for n in Effects.names() if Effects.axis(n) is not None]
    assert len(AXES) == len(declared) >= 9
    assert {"payload_mass", "valve_dead_time", "polytropic_n"} <= {a.name for a in AXES}
    base = packing.pack(arm)
    for a in AXES:
        assert plant_at(arm, a.name, 0.0) is arm
        assert not np.array_equal(packing.pack(plant_at(arm, a.name, 1.0)), base), a.name
    assert axis("valve_dead_time").value(0.5) == 0.015


def test_whitened_log_ratio_is_zero_at_the_thesis_values_and_scaled_by_the_uncertainty():
    thesis = np.array([[0.01, 0.02]])
    assert np.all(whitened(thesis, thesis) == 0.0)
    r = whitened(thesis * np.e, thesis)
    # ln(e) = 1 divided by sqrt(0.1^2 + (2.9e-5 / thesis)^2)
    np.testing.assert_allclose(r, 1.0 / np.sqrt(0.01 + (1e-4 / np.sqrt(12) / thesis) ** 2)
                               .ravel(), rtol=1e-12)


def test_fit_summary_rejects_a_bad_grid():
    import pytest

    with pytest.raises(ValueError, match="thetas"):
        fit_summary(thetas=(0.5, 1.0))
