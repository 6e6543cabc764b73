"""What a new user certifying their own arm reads after a slip: implausible contact point and
covering files refused or noted, error messages that name the argument, its value and what
is allowed, and units in what a person reads.

The inputs are those a new user wrote in a trial (a contact point 3200 mm out on a 400 mm
forearm, a foam modulus of 800 Pa meant as kPa, ...), rebuilt here on the thesis arm.
"""

import math

import numpy as np
import pandas as pd
import pytest

from ppamsafety.cli import main
from ppamsafety.experiments.catalog import run_thesis_experiment, thesis_variants
from ppamsafety.impact.anywhere import simulate_contacts, worst_contact
from ppamsafety.params import thesis_arm
from ppamsafety.params.arm_file import ArmFileError
from ppamsafety.params.contact import (POINT_EXTENT_FACTOR, SOFT_LAYER_MODULUS, THESIS_COVERING,
                                       ContactPoint, Covering, Layer, check_point_on_arm,
                                       covering_notes)
from ppamsafety.params.contact_files import load_covering, resolve_contact_point

ARM = thesis_arm()
L2 = ARM.geometry.L2


def _point_file(path, position_mm, link=2, covering='"bare metal"'):
    path.write_text('format = "ppamsafety-contact/1"\nname = "gripper bracket"\n'
                    f'link = {link}\nposition = {{ value = {position_mm}, unit = "mm" }}\n'
                    'shape = "cylinder"\nradius = { value = 25, unit = "mm" }\n'
                    f'covering = {covering}\nsource = "CAD"\n')
    return path


def _covering_file(path, modulus, unit):
    path.write_text('format = "ppamsafety-covering/1"\nname = "15 mm EVA foam sleeve"\n'
                    '[[layer]]\nname = "EVA foam"\nlaw = "thin-layer"\n'
                    f'modulus = {{ value = {modulus}, unit = "{unit}" }}\n'
                    'thickness = { value = 15, unit = "mm" }\nstrain_limit = 0.7\n'
                    'hysteresis = { value = 4.0, unit = "s/m" }\n')
    return path


# ---- 1. implausible contact point and covering files -----------------------------------------
def test_a_contact_point_beyond_its_link_is_refused_naming_key_value_length_and_range(tmp_path):
    f = _point_file(tmp_path / "far.toml", 10 * 1e3 * L2)      # 10 forearm lengths out
    with pytest.raises(ArmFileError) as e:
        resolve_contact_point(f, ARM)
    msg = str(e.value)
    for part in ("position", f"{1e4 * L2:.4g} mm", f"L2 = {L2:.4g} m",
                 f"[0, {POINT_EXTENT_FACTOR * L2:.4g}] m", "gripper bracket", "far.toml"):
        assert part in msg, msg
    # the same point as an object, through the Python API of the contact engine
    pt = ContactPoint("bracket", 2, 10 * L2, "sphere", 0.02, Covering("bare metal"))
    with pytest.raises(ValueError, match=r"position = .* allowed \[0, "):
        simulate_contacts(ARM, [0.8, -1.4], [2.0, 0.0], [85.0, 54.0], point=pt)
    with pytest.raises(ValueError, match="L1 = "):
        check_point_on_arm(pt.replace(link=1, position=5 * ARM.geometry.L1), ARM)


def test_a_contact_point_within_the_tool_margin_is_accepted(tmp_path):
    at_margin = _point_file(tmp_path / "tool.toml", 1e3 * POINT_EXTENT_FACTOR * L2 * 0.999)
    assert resolve_contact_point(at_margin, ARM).position == pytest.approx(
        POINT_EXTENT_FACTOR * L2 * 0.999)
    just_out = _point_file(tmp_path / "out.toml", 1e3 * POINT_EXTENT_FACTOR * L2 * 1.01)
    with pytest.raises(ValueError, match="position"):
        resolve_contact_point(just_out, ARM)


def test_the_cli_refuses_a_far_contact_point_with_one_line(tmp_path, capsys):
    f = _point_file(tmp_path / "far.toml", 3200)
    assert main(["impact", "--q", "50", "-80", "--qd", "2", "0", "--contact", str(f)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ppamsafety: error: --contact") and err.count("\n") == 1, err
    assert "3200 mm" in err and f"L2 = {L2:.4g} m" in err, err


def test_a_foam_modulus_in_pa_meant_as_kpa_gets_a_note_naming_the_slip(tmp_path):
    cov = load_covering(_covering_file(tmp_path / "pa.toml", 800, "Pa"))
    notes = covering_notes(cov)
    assert len(notes) == 1 and "layer[0].modulus = 800 Pa" in notes[0], notes
    assert "did you mean 800 kPa" in notes[0], notes
    # MPa given in Pa: the note names MPa
    cov = load_covering(_covering_file(tmp_path / "mpa.toml", 1.2, "Pa"))
    assert "did you mean 1.2 MPa" in covering_notes(cov)[0]
    # plausible coverings have no note
    assert covering_notes(load_covering(_covering_file(tmp_path / "ok.toml", 800, "kPa"))) == ()
    assert covering_notes(THESIS_COVERING) == ()
    assert SOFT_LAYER_MODULUS <= 55e3                # a silicone gel is not noted


def test_impact_notes_the_slip_and_says_the_covering_bottoms_out(tmp_path, capsys):
    f = _covering_file(tmp_path / "pa.toml", 800, "Pa")
    hist = tmp_path / "h.csv"
    assert main(["impact", "--q", "50", "-80", "--qd", "2", "0", "--covering", str(f),
                 "--history", str(hist)]) == 0
    out, err = capsys.readouterr()
    assert "ppamsafety: note:" in err and "did you mean 800 kPa" in err, err
    line = next(ln for ln in out.splitlines() if ln.startswith("covering use"))
    assert "1.00" in line and "BOTTOMS OUT" in line, line
    h = pd.read_csv(hist)
    use = next(c for c in h.columns if c.startswith("covering_use"))
    assert h[use].max() == pytest.approx(1.0, abs=1e-6)
    # a covering well within its limit: the line says its use, no bottoming out
    ok = _covering_file(tmp_path / "ok.toml", 800, "kPa")
    assert main(["impact", "--q", "50", "-80", "--qd", "0.3", "0", "--covering", str(ok)]) == 0
    out, err = capsys.readouterr()
    line = next(ln for ln in out.splitlines() if ln.startswith("covering use"))
    assert "BOTTOMS OUT" not in line and float(line.split()[2]) < 1.0, line
    assert "note:" not in err


def test_worst_contact_covering_use_is_zero_for_bare_points_never_nan():
    res = _step_record()
    cov = THESIS_COVERING
    pts = ["tool point", ContactPoint("covered forearm", 2, 0.5 * L2, "cylinder", 0.03, cov)]
    w = worst_contact(res, ARM, points=pts, every=50)
    assert w.worst["covering_use"].notna().all(), w.worst
    bare = w.worst.set_index("point").loc["tool point", "covering_use"]
    assert bare == 0.0
    assert 0.0 < w.worst.set_index("point").loc["covered forearm", "covering_use"] <= 1.0


def _step_record():
    return run_thesis_experiment(ARM, "step", [thesis_variants()[1]])[0]
