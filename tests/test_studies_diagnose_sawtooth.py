"""Case study (a) (ppamsafety.sections.diagnose_sawtooth), quick mode."""

import pytest

from ppamsafety.sections import diagnose_sawtooth


@pytest.fixture(scope="module")
def study():
    return diagnose_sawtooth.compute(quick=True)


def test_quick_study_names_hysteresis_and_shrinks_the_gap(study):
    m = study.metrics
    assert m["hysteresis_named"] and m["named"] == "hysteresis" and not m["unexplained"]
    # hidden 0.139 (thesis §3.6.5): fitted within 5 %
    assert abs(m["delta_fit"] - 0.139) <= 0.007
    assert m["rho_before_muscle_forces"] > 3 > m["rho_after_muscle_forces"]
    assert m["rho_before_valves"] < 1.5
    assert m["rms_q1_after_deg"] < 0.2 * m["rms_q1_before_deg"]
    assert m["rms_q2_after_deg"] < 0.2 * m["rms_q2_before_deg"]


def test_render(study):
    sec = diagnose_sawtooth.render(study)
    names = [a for a, _ in sec.artifacts]
    assert "diagnose_sawtooth.png" in names and "diagnose_sawtooth.csv" in names
    assert "hysteresis" in sec.markdown and "0.139" in sec.markdown
