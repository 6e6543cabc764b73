"""The covering as a design parameter: sweep keys of safety_case, study files, envelopes."""

import pandas as pd
import pytest

from ppamsafety.envelope import safety_envelope
from ppamsafety.params.contact import THESIS_COVERING
from ppamsafety.params.iso_ts_15066 import SKULL_FOREHEAD
from ppamsafety.plots.sweep import plot_sweep
from ppamsafety.sweep_cases import check_case, contact_covering, safety_case


def test_thinner_covering_hits_harder_and_bottoms_out():
    rows = [safety_case("step", "PSMC joint", lam=0.4, contact="tool point",
                        covering_thickness=h) for h in (0.8e-3, 3e-3, 10e-3, 25e-3)]
    F = [r["F_max"] for r in rows]
    assert all(a > b for a, b in zip(F, F[1:]))                   # thicker: softer
    assert rows[0]["covering_use"] == pytest.approx(1.0)          # 0.8 mm bottoms out
    assert rows[-1]["covering_use"] < 0.5
    bare = safety_case("step", "PSMC joint", lam=0.4, contact="tool point")
    assert bare["F_max"] > F[0] and bare["covering_name"] == "bare metal"
    assert rows[1]["covering_name"].startswith("thesis-implied")
    assert rows[1]["body_region"] == "head (forehead)"


def test_stiffer_covering_hits_harder():
    F = [safety_case("step", "PSMC joint", lam=0.4, contact="forearm",
                     covering_modulus=e)["F_max"] for e in (0.3e6, 1.14e6, 5e6)]
    assert F[0] < F[1] < F[2]


def test_all_contact_points_gives_the_worst():
    one = {c: safety_case("step", "PID", contact=c)["F_max"]
           for c in ("tool point", "elbow", "forearm", "upper arm")}
    allp = safety_case("step", "PID", contact="all")
    assert allp["F_max"] == max(one.values())
    assert allp["contact_point"] == max(one, key=one.get)


def test_covering_keys_are_checked():
    with pytest.raises(ValueError, match="covering_thickness"):
        check_case(covering_thickness=-1.0)
    with pytest.raises(ValueError, match="covering_modulus"):
        check_case(covering_modulus=1e20)
    with pytest.raises(ValueError, match="has none"):
        check_case(covering="bare metal", covering_thickness=0.01)
    with pytest.raises(ValueError, match="contact"):
        check_case(contact="knee")
    with pytest.raises(ValueError, match="head"):
        check_case(contact="elbow", head="iso15066-face")
    c = contact_covering({"covering": None, "covering_thickness": 0.004,
                          "covering_modulus": None, "covering_hysteresis": 2.0})
    assert c.layers[0].thickness == 0.004 and c.layers[0].hysteresis == 2.0
    assert c.layers[0].modulus == THESIS_COVERING.layers[0].modulus


def test_envelope_thinnest_covering_under_the_forehead_limit():
    """The thinnest thesis-implied covering that keeps a PSMC (lambda 0.4 s) step below the
    ISO/TS 15066 transient forehead limit at the tool point: found by bisection, monotone."""
    env = safety_envelope("covering_thickness", (0.5e-3, 30e-3), limit="iso_ts_15066",
                          case={"controller": "PSMC joint", "lam": 0.4, "contact": "tool point"},
                          tolerance=0.02)
    assert env.direction == "smallest" and env.monotone
    assert 0.5e-3 < env.safe_value < 30e-3
    ok = safety_case("step", "PSMC joint", lam=0.4, contact="tool point",
                     covering_thickness=env.safe_value)
    bad = safety_case("step", "PSMC joint", lam=0.4, contact="tool point",
                      covering_thickness=env.unsafe_value)
    assert ok["F_max"] < SKULL_FOREHEAD.force_transient <= bad["F_max"]


def test_study_file_accepts_covering_keys(tmp_path):
    from ppamsafety.study_files import load_study

    f = tmp_path / "cov.toml"
    f.write_text('[study]\nname = "cov"\n[case]\nexperiment = "step"\ncontroller = "PSMC joint"\n'
                 'lam = 0.4\ncontact = "forearm"\n[grid]\ncovering_thickness = [0.002, 0.01]\n'
                 'covering_hysteresis = [1.0, 8.0]\n')
    study = load_study(f)
    assert study is not None


def test_sweep_figure_draws_the_region_limit():
    df = pd.DataFrame({"covering_thickness": [0.002, 0.01], "F_max": [400.0, 200.0],
                       "HIC36": [0.5, 0.2], "status": ["ok", "ok"],
                       "body_region": ["face", "face"]})
    fig = plot_sweep(df, ["covering_thickness"], region_limits={"face": {"F_max": 130.0},
                                                               "hand": {"F_max": 280.0}})
    ax = fig.axes[0]
    ys = {round(line.get_ydata()[0], 6) for line in ax.get_lines() if len(line.get_ydata()) == 2}
    assert 130.0 in ys and 280.0 not in ys
    assert any("face: 130" in t.get_text() for t in ax.get_legend().get_texts())
