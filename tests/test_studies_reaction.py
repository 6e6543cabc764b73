"""The reaction study in quick mode: physics it must show (issue 12 item 7)."""

import numpy as np
import pytest

from ppamsafety.impact.collision import Reaction
from ppamsafety.sections import reaction


@pytest.fixture(scope="module")
def study():
    return reaction.compute(quick=True)


def test_reaction_cannot_shape_the_first_impact(study):
    tm = study.timing
    # the first impact's force peak comes before detection; the valves (T >= 45 ms) follow
    # less than a third of any set-value change before the first contact is over
    assert np.all(tm["detect_delay_tight_ms"] > tm["t_to_Fmax_ms"])
    assert np.all(tm["valve_fraction_by_contact_end"] < 1.0 / 3.0)
    # hence every reaction gives the same first-impact F_max (within 1 %)
    assert np.all(tm["Fmax_1_spread_rel"] < 0.01)
    # PID: the muscles' whole torque range is < 20 % of the contact torque J^T n F_max
    assert tm[tm.controller == "PID"]["span_over_contact_torque"].iloc[0] < 0.2


def test_reaction_removes_or_softens_later_impacts(study):
    t = study.table
    for ctrl in t.controller.unique():
        c = t[t.controller == ctrl]
        none = c[c.reaction == "NONE"].iloc[0]
        assert none["impacts"] >= 2          # without reaction the arm hits the head again
        for rea in ("STOP", "RETRACT"):
            r = c[c.reaction == rea].iloc[0]
            assert r["F_max_later_N"] < none["F_max_later_N"], (ctrl, rea)


def test_engine_agreement_and_energy(study):
    e = study.engine
    assert np.all(np.abs(e["F_max_rel_diff"]) < 0.01)
    assert np.all(e["max_dF_over_Fmax"] < 0.02)
    assert study.metrics["energy_error_max"] < 1e-6


def test_render_and_frame(study):
    sec = reaction.render(study)
    names = [a for a, _ in sec.artifacts]
    assert "reaction_results.csv" in names and any(n.endswith(".png") for n in names)
    assert len(study.to_pandas()) == len(Reaction) * 2
    assert "Why reaction cannot shape the first impact" in sec.markdown
