"""The measured-data format (docs/measured_data.md): loading, every validation rule, writing.

Frames here are built by hand (no simulation, no compiled kernels) so each rule is tested in
isolation; the round trips through the synthetic writers and the example files in
tests/data/measured/ are at the end.
"""

import math
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from ppamsafety.data import (MeasuredData, MeasuredDataError, MeasuredDataWarning,
                             load_measured, read_metadata)
from ppamsafety.data.measured import dumps_toml

EXAMPLES = Path(__file__).parent / "data" / "measured"
LAW = {"a": [8.16906e-05, 0.00295069, -0.0158659, 0.036231, -0.0572879], "l0": 0.06}


def open_loop(n=50, dt=1e-3):
    """A plausible open-loop arm record in SI units (1 kHz)."""
    t = np.arange(n) * dt
    df = pd.DataFrame({"t": t, "q1": 0.8 + 0.1 * np.sin(t), "q2": -1.2 + 0.05 * np.cos(t),
                       "qd1": 0.1 * np.cos(t), "qd2": -0.05 * np.sin(t)})
    for i in range(4):
        df[f"p{i + 1}"] = 1.5e5 + 1e4 * i + 1e3 * np.sin(t)
    return {"kind": "arm", "experiment": "open-loop"}, df


def tensile(n=20, position=False):
    eps = np.linspace(0.05, 0.3, n)
    df = pd.DataFrame({"t": np.arange(n) * 0.1, "pressure": np.full(n, 2e5)})
    a = np.array(LAW["a"])
    df["force"] = 2e5 * (a[0] / eps + a[1] + a[2] * eps + a[3] * eps ** 2 + a[4] * eps ** 3)
    if position:
        df["position"] = LAW["l0"] * (1 - eps)
    else:
        df["contraction"] = eps
    return {"kind": "actuator", "experiment": "tensile", "force_law": dict(LAW)}, df


def write_csv(path, meta, df, *, header=True):
    text = dumps_toml(meta)
    with open(path, "w", encoding="utf-8") as fh:
        if header:
            fh.write("".join("# " + ln + "\n" for ln in text.splitlines()))
        df.to_csv(fh, index=False, lineterminator="\n")
    if not header:
        Path(path).with_suffix(".toml").write_text(text, encoding="utf-8")
    return path


def refuse(meta, df, *words, **kw):
    with pytest.raises(MeasuredDataError) as ei:
        MeasuredData(meta, df, source="X.csv", **kw)
    msg = str(ei.value)
    assert "X.csv" in msg
    for w in words:
        assert w in msg, msg
    return msg


# -- accessors and round trips ------------------------------------------------------------

def test_accessors_and_copy():
    meta, df = open_loop()
    d = MeasuredData(meta, df)
    assert d.kind == "arm" and d.experiment == "open-loop"
    assert d.channels == ("q1", "q2", "qd1", "qd2", "p1", "p2", "p3", "p4")
    assert d.dt == pytest.approx(1e-3, rel=1e-12)
    assert d.segments == ((0, 50),) and d.gaps == () and len(d) == 50
    out = d.to_pandas()
    out.loc[0, "q1"] = 99.0                               # a copy: the record is unchanged
    assert d.column("q1")[0] == pytest.approx(0.8)
    assert out.attrs["meta"] == meta
    meta["kind"] = "actuator"                             # the record holds its own copy
    assert d.kind == "arm"
    assert d.column("q1", "q2").shape == (50, 2)
    with pytest.raises(KeyError, match="u1"):
        d.column("u1")


@pytest.mark.parametrize("sidecar", [False, True])
def test_csv_round_trip_is_exact(tmp_path, sidecar):
    meta, df = open_loop()
    meta.update(description="a \"quoted\" text, λ", source="lab", sample_rate=1000.0,
                units={"t": "s", "q1": "rad", "p1": "Pa"})
    d = MeasuredData(meta, df)
    f = d.save(tmp_path / "DATA.csv", sidecar=sidecar)
    assert (tmp_path / "DATA.toml").exists() == sidecar
    back = load_measured(f)
    pd.testing.assert_frame_equal(back.frame, d.frame, check_exact=True)
    assert back.meta == {"format_version": 1, **meta}
    assert read_metadata(f)["description"] == meta["description"]


def test_save_never_overwrites(tmp_path):
    meta, df = open_loop()
    d = MeasuredData(meta, df)
    f = tmp_path / "DATA.csv"
    f.write_text("user data\n")
    with pytest.raises(ValueError, match="already exists"):
        d.save(f)
    assert f.read_text() == "user data\n"
    d.save(f, overwrite=True)
    assert load_measured(f).frame.shape == (50, 9)
    # a sidecar in the way: nothing is written at all
    g = tmp_path / "OTHER.csv"
    (tmp_path / "OTHER.toml").write_text("mine = 1\n")
    with pytest.raises(ValueError, match="already exists"):
        d.save(g, sidecar=True)
    assert not g.exists() and (tmp_path / "OTHER.toml").read_text() == "mine = 1\n"


def test_parquet_needs_pyarrow(tmp_path):
    pytest.importorskip("numpy")
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        meta, df = open_loop()
        with pytest.raises(MeasuredDataError, match="pip install pyarrow"):
            MeasuredData(meta, df).save(tmp_path / "DATA.parquet")
        (tmp_path / "R.parquet").write_bytes(b"PAR1")
        with pytest.raises(MeasuredDataError, match="pip install pyarrow"):
            load_measured(tmp_path / "R.parquet")
        return
    meta, df = open_loop()
    d = MeasuredData(meta, df)
    d.save(tmp_path / "DATA.parquet")
    assert (tmp_path / "DATA.toml").exists()
    pd.testing.assert_frame_equal(load_measured(tmp_path / "DATA.parquet").frame, d.frame)


def test_unknown_file_type_and_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="does not exist"):
        load_measured(tmp_path / "nope.csv")
    (tmp_path / "a.xlsx").write_text("x")
    with pytest.raises(MeasuredDataError, match="CSV"):
        load_measured(tmp_path / "a.xlsx")


# -- metadata ---------------------------------------------------------------------------

def test_metadata_missing_twice_and_bad_toml(tmp_path):
    meta, df = open_loop()
    f = tmp_path / "D.csv"
    df.to_csv(f, index=False)
    with pytest.raises(MeasuredDataError, match="no metadata"):
        load_measured(f)
    write_csv(f, meta, df)
    f.with_suffix(".toml").write_text(dumps_toml(meta))
    with pytest.raises(MeasuredDataError, match="given twice"):
        load_measured(f)
    f.with_suffix(".toml").unlink()
    f.write_text('# kind = "arm"\n# experiment = open-loop\n' + df.to_csv(index=False))
    with pytest.raises(MeasuredDataError, match=r"not valid TOML.*line 2"):
        load_measured(f)
    f.with_suffix(".toml").write_text("kind = [\n")
    df.to_csv(f, index=False)
    with pytest.raises(MeasuredDataError, match="D.toml.*not valid TOML"):
        load_measured(f)


@pytest.mark.parametrize("change, words", [
    ({"kind": None}, ["no 'kind'"]),
    ({"experiment": None}, ["no 'experiment'"]),
    ({"kind": "robot"}, ["'robot'", "'arm', 'actuator'"]),
    ({"experiment": "sawtooth"}, ["'sawtooth'", "'static-sawtooth'"]),
    ({"experiment": "tensile"}, ["not allowed for kind = 'arm'"]),
    ({"sample_rate": -5.0}, ["sample_rate"]),
    ({"sample_rate": "fast"}, ["sample_rate"]),
    ({"description": 3}, ["description must be a string"]),
    ({"format_version": 7}, ["format_version = 7"]),
    ({"units": {"p1": "bar"}}, ["'p1'", "'bar'", "SI", "* 100000"]),
    ({"units": {"q2": "deg"}}, ["'q2'", "rad"]),
    ({"units": "SI"}, ["units must be a table"]),
])
def test_bad_metadata(change, words):
    meta, df = open_loop()
    for k, v in change.items():
        if v is None:
            del meta[k]
        else:
            meta[k] = v
    refuse(meta, df, *words)


def test_unknown_metadata_and_columns_warn_and_are_kept():
    meta, df = open_loop()
    meta["operator"] = "MVD"
    meta["units"] = {"temperature": "K"}                 # units of an extra column are free
    df["temperature"] = 293.0
    with pytest.warns(MeasuredDataWarning) as rec:
        d = MeasuredData(meta, df)
    text = " ".join(str(w.message) for w in rec)
    assert "'operator'" in text and "'temperature'" in text
    assert d.meta["operator"] == "MVD" and d.extra_columns == ("temperature",)
    assert "temperature" not in d.channels and len(d.notes) == 2


def test_closed_loop_controller_and_reference():
    meta, df = open_loop()
    meta["experiment"] = "closed-loop"
    refuse(dict(meta, reference="step"), df, "[controller]")
    ok = dict(meta, reference="step", controller={"variant": "PSMC joint Ki=2 λ=0.4"})
    assert MeasuredData(ok, df).meta["reference"] == "step"
    refuse(dict(ok, controller={"variant": "PSMC Ki=3"}), df, "not a thesis variant", "'PID'")
    fam = dict(ok, controller={"family": "PID", "gains": {"kp": [1.2e5, 8e4], "kd": 3e3}})
    MeasuredData(fam, df)
    refuse(dict(ok, controller={"family": "PID"}), df, "gains")
    refuse(dict(ok, controller={"family": "PID", "gains": {"kp": "high"}}), df, "kp")
    refuse(dict(ok, controller={"family": "LQR", "gains": {"k": 1.0}}), df, "'LQR'")
    refuse(dict(ok, reference="square"), df, "'square'", "'circle10'")
    noref = dict(ok)
    del noref["reference"]
    refuse(noref, df, "reference", "q1_d, q2_d")
    df2 = df.assign(q1_d=0.8, q2_d=-1.2)
    MeasuredData(noref, df2)                                  # reference as columns
    refuse(ok, df2, "given twice")
    # a top-level key written after the [controller] header lands in that table
    stray = dict(noref, controller={"variant": "PID", "reference": "step"})
    with pytest.warns(MeasuredDataWarning, match=r"'reference' in \[controller\]"):
        MeasuredData(stray, df2)


def test_force_law_rules():
    meta, df = tensile()
    del meta["force_law"]
    refuse(meta, df, "nominal force law", "N/Pa")
    meta, df = tensile()
    meta["force_law"] = {"a": [8.17, 295.07, -1586.59, 3623.1, -5728.79], "l0": 0.06}
    refuse(meta, df, "N/bar")
    meta["force_law"] = {"a": [1e-4, 2e-3]}
    refuse(meta, df, "5 coefficients")
    meta, df = tensile(position=True)
    del meta["force_law"]["l0"]
    refuse(meta, df, "'position' needs force_law.l0")
    meta["force_law"]["l0"] = 60.0
    refuse(meta, df, "l0 = 60 m", "mm")


# -- columns -----------------------------------------------------------------------------

@pytest.mark.parametrize("drop, words", [
    (["t"], ["no time column 't'"]),
    (["qd1"], ["(qd1, qd2)", "missing qd1"]),
    (["p3"], ["(p1, p2, p3, p4)", "missing p3"]),
])
def test_missing_columns_arm(drop, words):
    meta, df = open_loop()
    refuse(meta, df.drop(columns=drop), *words)


def test_missing_columns_static_and_actuator():
    meta, df = open_loop()
    refuse({"kind": "arm", "experiment": "static-sawtooth"}, df[["t", "q1", "q2"]],
           "(F1, F2, F3, F4) or (p1, p2, p3, p4)")
    # forces instead of pressures are enough
    stat = df[["t", "q1", "q2"]].assign(F1=1.0, F2=1.0, F3=1.0, F4=1.0)
    MeasuredData({"kind": "arm", "experiment": "static-sawtooth"}, stat)
    meta, df = tensile()
    refuse(meta, df.drop(columns="contraction"), "(contraction) or (position)")
    refuse(meta, df.drop(columns="force"), "missing force")


def test_non_numeric_value_names_column_row_and_line(tmp_path):
    meta, df = open_loop()
    df = df.astype({"p2": object})
    df.loc[7, "p2"] = "1.5 bar"
    f = write_csv(tmp_path / "D.csv", meta, df)
    n_head = len(dumps_toml(meta).splitlines())
    with pytest.raises(MeasuredDataError) as ei:
        load_measured(f)
    msg = str(ei.value)
    assert "'p2'" in msg and "row 7" in msg and f"line {n_head + 2 + 7}" in msg
    assert "'1.5 bar'" in msg and str(f) in msg
    # the line number is right: that file line holds the value
    assert "1.5 bar" in f.read_text().splitlines()[n_head + 2 + 7 - 1]


def test_duplicate_columns(tmp_path):
    meta, df = open_loop()
    f = tmp_path / "D.csv"
    write_csv(f, meta, df)
    lines = f.read_text().splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.startswith("t,"))
    lines[i] = lines[i].replace("qd2", "qd1")
    f.write_text("\n".join(lines) + "\n")
    with pytest.raises(MeasuredDataError, match="duplicate column"):
        load_measured(f)


# -- units by value ----------------------------------------------------------------------

@pytest.mark.parametrize("col, factor, words", [
    ("p1", 1e-5, ["'p1'", "bar", "1e5"]),
    ("qd1", 180 / math.pi * 10, ["'qd1'", "deg/s"]),
])
def test_unit_hints_arm(col, factor, words):
    meta, df = open_loop()
    df[col] = df[col] * factor
    refuse(meta, df, *words, "strict_units=False")
    with pytest.warns(MeasuredDataWarning, match=words[1]):
        d = MeasuredData(meta, df, strict_units=False)
    assert d.column(col)[0] == pytest.approx(df[col].iloc[0])   # warned, not converted


def test_angles_beyond_a_turn_are_impossible_whatever_the_units_flag():
    """Issue 22: |q| > 2 pi is no joint angle of this arm (degrees): refused even with
    strict_units=False, with the conversion."""
    meta, df = open_loop()
    df["q1"] = df["q1"] * 180 / math.pi
    for strict in (True, False):
        msg = refuse(meta, df, "'q1'", "physically impossible", "degrees", "pi/180",
                     strict_units=strict)
        assert "strict_units=False" not in msg


def test_degree_hint_on_typical_thesis_angles():
    meta, df = open_loop()
    df["q1"], df["q2"] = 50.0, -80.0                  # the step-impact configuration in degrees
    refuse(meta, df, "degrees")


def test_unit_hints_actuator():
    meta, df = tensile(position=True)
    df["position"] = df["position"] * 1e3
    refuse(meta, df, "'position'", "mm", "1e-3")
    meta, df = tensile()
    df["contraction"] = df["contraction"] * 100
    refuse(meta, df, "percent")
    meta, df = tensile()
    df["pressure"] = 2.0
    refuse(meta, df, "bar")


def test_zero_pressure_is_not_bar():
    meta, df = open_loop()
    df["p4"] = 0.0                                     # a vented muscle
    assert MeasuredData(meta, df).column("p4").max() == 0.0


# -- NaN / inf, time, sampling -------------------------------------------------------------

def test_nan_and_inf_refused_with_counts_and_rows():
    meta, df = open_loop()
    df.loc[[10, 11, 12, 13], "q2"] = np.nan
    df.loc[30, "p1"] = np.inf
    msg = refuse(meta, df, "q2: 4 NaN/inf", "row 10", "p1: 1 NaN/inf", "row 30",
                 "allow_gaps=True")
    assert "5 row(s)" in msg


def test_nan_allow_gaps_drops_and_splits():
    meta, df = open_loop()
    df.loc[[10, 11], "q2"] = np.nan
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        d = MeasuredData(meta, df, allow_gaps=True)
    text = [str(w.message) for w in rec]
    assert any("dropped 2 row" in m for m in text) and any("split at 1 gap" in m for m in text)
    assert len(d) == 48 and d.dropped_rows == 2
    assert d.segments == ((0, 10), (10, 48))
    assert d.gaps == (pytest.approx((0.009, 0.012)),)
    assert np.isfinite(d.frame.to_numpy()).all()
    assert [len(s) for s in d.segment_frames()] == [10, 38]


def test_t_must_increase():
    meta, df = open_loop()
    df.loc[20, "t"] = df.loc[19, "t"]
    refuse(meta, df, "increase strictly", "row 19", "row 20", "t = 0.019")
    meta, df = tensile()
    df.loc[5, "t"] = 0.0
    refuse(meta, df, "increase strictly")


def test_irregular_sampling_refused():
    meta, df = open_loop()
    df.loc[25:, "t"] += 0.0003                          # one interval 1.3 ms among 1 ms
    refuse(meta, df, "not uniformly sampled", "row 25", "0.0013")


def test_gaps_refused_then_split():
    meta, df = open_loop()
    df.loc[20:, "t"] += 0.5
    refuse(meta, df, "1 gap(s)", "0.019..0.52 s", "allow_gaps=True")
    with pytest.warns(MeasuredDataWarning, match="split"):
        d = MeasuredData(meta, df, allow_gaps=True)
    assert d.segments == ((0, 20), (20, 50)) and d.dt == pytest.approx(1e-3)


def test_static_readings_need_not_be_uniform():
    meta, df = open_loop(n=5)
    stat = df[["t", "q1", "q2", "p1", "p2", "p3", "p4"]].copy()
    stat["t"] = [0.0, 10.0, 25.0, 31.0, 60.0]
    d = MeasuredData({"kind": "arm", "experiment": "static-sawtooth"}, stat)
    assert d.segments == ((0, 5),)
    refuse({"kind": "arm", "experiment": "static-sawtooth", "sample_rate": 0.1}, stat,
           "not uniformly sampled")


def test_sample_rate_checked_against_t():
    meta, df = open_loop()
    MeasuredData(dict(meta, sample_rate=1000.0), df)
    refuse(dict(meta, sample_rate=500.0), df, "sample_rate = 500 Hz", "1000 Hz")


def test_too_short():
    meta, df = open_loop(n=9)
    refuse(meta, df, "too short", "9 row(s)", "at least 10")
    meta, df = open_loop(n=12)
    df.loc[[3, 4, 5], "q1"] = np.nan
    with pytest.warns(MeasuredDataWarning, match="dropped 3"):
        refuse(meta, df, "too short", "after dropping 3", allow_gaps=True)


def test_constructor_types():
    meta, df = open_loop()
    with pytest.raises(TypeError, match="frame"):
        MeasuredData(meta, df.to_numpy())
    with pytest.raises(TypeError, match="meta"):
        MeasuredData([("kind", "arm")], df)
    with pytest.raises(TypeError, match="allow_gaps"):
        MeasuredData(meta, df, allow_gaps="yes")


# -- actuator helpers, example files, synthetic round trips ---------------------------------

def test_position_gives_contraction_and_nominal_force():
    meta, df = tensile(position=True)
    d = MeasuredData(meta, df)
    eps = np.linspace(0.05, 0.3, 20)
    np.testing.assert_allclose(d.contraction(), eps, rtol=1e-12)
    np.testing.assert_allclose(d.nominal_force(), df["force"], rtol=1e-12)


def test_example_files_load():
    s = load_measured(EXAMPLES / "equilibria.csv")
    assert (s.kind, s.experiment, len(s)) == ("arm", "static-sawtooth", 31)
    assert set(s.channels) >= {"q1", "q2", "F1", "p4", "u4"}
    t = load_measured(EXAMPLES / "tensile_group1.csv")          # metadata in the sidecar
    assert (t.kind, t.experiment, t.channels) == ("actuator", "tensile",
                                                   ("force", "pressure", "position"))
    assert t.meta["force_law"]["l0"] == 0.06
    for f in EXAMPLES.iterdir():
        assert f.stat().st_size < 8000, f                       # tiny files only


def test_synthetic_tensile_round_trip(tmp_path):
    from ppamsafety.data import synthetic_tensile

    d = synthetic_tensile(noise=False, position=True, group=3)
    np.testing.assert_allclose(d.nominal_force(), d.column("force"), rtol=1e-12)
    back = load_measured(d.save(tmp_path / "T.csv"))
    pd.testing.assert_frame_equal(back.frame, d.frame, check_exact=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")                          # a clean record: no warning
        load_measured(tmp_path / "T.csv")


def test_docs_worked_example_is_valid(tmp_path):
    """The metadata block and the CSV example of docs/measured_data.md load as documented."""
    import re
    import tomllib

    doc = (Path(__file__).parents[1] / "docs" / "measured_data.md").read_text(encoding="utf-8")
    toml_blocks = re.findall(r"```toml\n(.*?)```", doc, re.S)
    meta = tomllib.loads(toml_blocks[0])
    assert meta["reference"] == "step" and meta["controller"]["variant"]
    _, df = open_loop(n=20)
    d = MeasuredData(meta, df)
    assert d.experiment == "closed-loop" and d.meta["units"]["q1"] == "rad"
    law = tomllib.loads(toml_blocks[1])["force_law"]
    m, dft = tensile()
    assert MeasuredData(dict(m, force_law=law), dft).meta["force_law"]["l0"] == 0.06
    text = re.findall(r"```text\n(.*?)```", doc, re.S)[0]
    lines = text.splitlines()
    last = [float(x) for x in lines[-1].split(",")]
    for k in range(1, 20):                            # the example shows the first rows only
        lines.append(",".join([f"{last[0] + k * 1e-3:.3f}"] + lines[-1].split(",")[1:]))
    f = tmp_path / "step.csv"
    f.write_text("\n".join(lines) + "\n", encoding="utf-8")
    d = load_measured(f)
    assert (d.kind, d.experiment, d.dt) == ("arm", "closed-loop", pytest.approx(1e-3))
    assert d.meta["controller"]["variant"] == "PSMC joint Ki=2 λ=0.4"
    assert d.channels[:4] == ("q1", "q2", "qd1", "qd2")


def test_synthetic_static_round_trip(tmp_path, arm):
    from ppamsafety.data import identify_measured, synthetic_static

    d = synthetic_static(arm, n=31, seed=1)
    assert len(d) == 31 and d.channels == ("q1", "q2", *(f"p{i}" for i in range(1, 5)),
                                           *(f"u{i}" for i in range(1, 5)),
                                           *(f"F{i}" for i in range(1, 5)))
    back = load_measured(d.save(tmp_path / "S.csv"))
    pd.testing.assert_frame_equal(back.frame, d.frame, check_exact=True)
    a = identify_measured(d, "static").results["gravity"].estimates
    b = identify_measured(back, "static").results["gravity"].estimates
    np.testing.assert_array_equal(a, b)                   # the file loses nothing
