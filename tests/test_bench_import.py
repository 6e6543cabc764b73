"""Import of raw bench files and campaigns (issue 20 items 1-2, 3: bad input).

Reference values: the shipped files are the source's bytes (sha256 from the source
repository's blobs, ``ppamsafety/data/datasets/zillen2021/SHA256SUMS``); the spike counts,
gaps and sign conventions were established in the groundwork (``NOTICE.md``).
"""

import hashlib
import lzma
import warnings

import numpy as np
import pytest

from ppamsafety.data import Actuator, BenchProfile, Campaign, import_bench, load_campaign
from ppamsafety.data.bench_import import despike
from ppamsafety.data.datasets import (ZILLEN2021, ZILLEN2021_SEALS, zillen2021_file,
                                      zillen2021_manifest)
from ppamsafety.data.measured import MeasuredDataError, MeasuredDataWarning
from ppamsafety.diagnose.bench.cylinder_synth import raw_text, synthesize_cylinder

PROFILE = ZILLEN2021 / "profile.toml"
CYL = {"type": "cylinder", "bore": "25.7 mm"}


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeasuredDataWarning)
        yield


def test_shipped_files_are_the_source_bytes_and_small():
    sums = dict(reversed(line.split()) for line in
                (ZILLEN2021 / "SHA256SUMS").read_text().splitlines())
    files = sorted(ZILLEN2021.glob("*.csv.xz"))
    assert len(files) == 15
    # two hashes copied from the source repository listing (git blobs of 6e0bcb4)
    assert sums["O-ring257_3bar.csv"].startswith("3294ab343633987485d7df9aeda7310e")
    assert sums["Kidney_lc_1bar.csv"].startswith("4a9305f5a8a6abed8dd1fa67cbdaa047")
    for f in files:
        raw = lzma.decompress(f.read_bytes())
        assert hashlib.sha256(raw).hexdigest() == sums[f.name[:-3]]
    assert sum(f.stat().st_size for f in files) < 1.0e6
    names = {f.name.split("_")[0] for f in files}
    assert names <= {"O-ring257", "X-ring257", "Kidney"}        # no held-out seal shipped
    assert (ZILLEN2021 / "NOTICE.md").is_file() and (ZILLEN2021 / "LICENSE-CC0-1.0.txt").is_file()
    assert set(ZILLEN2021_SEALS) == {"O-ring257", "X-ring257", "Kidney_lc"}


def test_import_of_a_real_file_units_signs_spikes_gaps():
    d = import_bench(zillen2021_file("O-ring257", 3), PROFILE, actuator=CYL,
                     record={"pressure_nominal": "3 bar"})
    assert d.actuator_type == "cylinder" and d.kind == "actuator"
    assert d.channels == ("force", "pressure", "position")
    p = d.column("pressure")
    assert 2.8e5 < np.median(p) < 3.2e5                     # bar -> Pa, gauge
    x = d.column("position")
    assert -0.045 < x.min() < -0.03 and x.max() < 0.006     # mm -> m, sign flipped
    assert d.meta["record"]["pressure_nominal"] == pytest.approx(3e5)
    assert d.meta["force_law"]["a"][1] == pytest.approx(np.pi / 4 * 0.0257 ** 2)
    imp = d.meta["import"]
    # groundwork: 57-93 laser spikes per O-/X-ring file; a 273 ms start-up gap after row 0
    assert 50 <= imp["despiked"]["position"]["count"] <= 100
    assert imp["rows_read"] == 6340 and imp["rows_kept"] == 6339
    assert any("dropped 1 segment" in n for n in d.notes)
    assert any("despiked column 'position'" in n for n in d.notes)
    # dissipation: about the Coulomb level (groundwork c = 5.9 N at 3 bar) on every stroke
    assert imp["checks"]["strokes_giving_energy_back"] == 0.0
    assert 4.5 < imp["checks"]["dissipation_median_N"] < 7.0


def test_campaign_manifests_load_every_pressure():
    for seal, n in (("O-ring257", 4), ("Kidney_lc", 7)):
        c = load_campaign(zillen2021_manifest(seal))
        assert len(c) == n and c.actuator_type == "cylinder"
        np.testing.assert_allclose(c.pressure_levels(), 1e5 * np.array(
            [1, 3, 5, 7] if n == 4 else range(1, 8)))


def _raw(tmp_path, text, name="rec.csv"):
    f = tmp_path / name
    f.write_text(text, newline="")
    return f


@pytest.fixture(scope="module")
def synthetic():
    return synthesize_cylinder({"coulomb": 5.0}, seed=3, pressures=(3e5,), cycles=4)


def test_raw_round_trip_with_spikes(tmp_path, synthetic):
    rec = synthetic.records[0]
    f = _raw(tmp_path, raw_text(rec, spikes=12, seed=1))
    d = import_bench(f, PROFILE, actuator=CYL)
    assert d.meta["import"]["despiked"]["position"]["count"] == 12
    # 3-decimal raw values: position within 0.5 um, force within 0.5 mN; a despiked sample
    # is the line through its neighbours: within a few position noise levels (13 um)
    np.testing.assert_allclose(d.column("force"), np.round(rec.column("force"), 3), atol=6e-4)
    spiked = np.array(d.meta["import"]["despiked"]["position"]["rows"]) - 1   # the start-up row
    clean = np.setdiff1d(np.arange(len(d)), spiked)
    np.testing.assert_allclose(d.column("position")[clean], rec.column("position")[clean],
                               atol=6e-7)
    np.testing.assert_allclose(d.column("position")[spiked], rec.column("position")[spiked],
                               atol=6e-5)
    np.testing.assert_allclose(d.column("t"), rec.column("t") - rec.column("t")[0], atol=6e-4)


def test_despike_leaves_reversals_alone():
    t = np.arange(400) * 0.01
    x = 0.01 * np.abs(((t + 1.0) % 2.0) - 1.0)             # sharp triangle, 1 cm/s
    y, k = despike(t, x + np.random.default_rng(0).normal(0, 1e-5, t.size))
    assert k.size == 0
    x2 = x.copy()
    x2[[50, 151, 260]] += 4e-4
    y, k = despike(t, x2)
    assert list(k) == [50, 151, 260]
    np.testing.assert_allclose(y, x, atol=1e-12)


@pytest.mark.parametrize("edit, match", [
    (lambda L: L[:100] + [L[99]] + L[100:], r"column 'time' \(time\) repeats: row 99"),
    (lambda L: L[:100] + L[101:102] + L[100:101] + L[102:], "column 'time' .* goes backwards"),
    (lambda L: L[:5] + ["1\t2\t3"] + L[6:], "line 6 has 3 field"),
    (lambda L: L[:7] + ["\t".join(L[7].split("\t")[:6] + ["12,5x"])] + L[8:],
     r"column 'force' \(channel 'force'\), row 7 \(line 8\): '12,5x' is not a number"),
])
def test_bad_raw_files_name_the_column(tmp_path, synthetic, edit, match):
    lines = raw_text(synthetic.records[0]).split("\r\n")[:-1]
    f = _raw(tmp_path, "\r\n".join(edit(lines)) + "\r\n")
    with pytest.raises(MeasuredDataError, match=match):
        import_bench(f, PROFILE, actuator=CYL)


def test_sign_mismatch_and_units_and_reference(tmp_path, synthetic):
    f = _raw(tmp_path, raw_text(synthetic.records[0]))
    prof = BenchProfile.from_toml(PROFILE).to_dict()
    flipped = {**prof, "channels": {**prof["channels"], "position": {"column": "position"}}}
    with pytest.raises(MeasuredDataError, match=r"sign mismatch between force and position.*"
                                                r"sign = -1 for column 'position'"):
        import_bench(f, flipped, actuator=CYL)
    d = import_bench(f, flipped, actuator=CYL, check_signs=False)     # asked to keep them
    assert d.meta["import"]["checks"] == {}
    fneg = {**prof, "channels": {**prof["channels"], "force": {"column": "force", "sign": -1}}}
    with pytest.raises(MeasuredDataError, match="force column 'force' is opposite"):
        import_bench(f, fneg, actuator=CYL)
    bad_unit = {**prof, "columns": [c if c[0] != "pressure" else ["pressure", "barr"]
                                    for c in prof["columns"]]}
    with pytest.raises(MeasuredDataError, match=r"profile column 'pressure'.*unknown unit 'barr'"):
        BenchProfile.from_dict(bad_unit)
    wrong_dim = {**prof, "columns": [c if c[0] != "force" else ["force", "mm"]
                                     for c in prof["columns"]]}
    with pytest.raises(MeasuredDataError, match=r"column 'force'.*needs \[force\]|"
                                                r"'force'.*\[length\]"):
        BenchProfile.from_dict(wrong_dim)
    no_ref = {k: v for k, v in prof.items() if k != "pressure_reference"}
    with pytest.raises(MeasuredDataError, match="'gauge' or 'absolute'"):
        BenchProfile.from_dict(no_ref)
    absolute = {**prof, "pressure_reference": "absolute"}
    da = import_bench(f, absolute, actuator=CYL, check_signs=False)
    np.testing.assert_allclose(da.column("pressure"), d.column("pressure") - 1.013e5, atol=1e-6)
    assert any("absolute" in n for n in da.notes)


def test_gaps_split_the_record_and_are_noted(tmp_path, synthetic):
    d = import_bench(_raw(tmp_path, raw_text(synthetic.records[0])), PROFILE, actuator=CYL)
    assert len(d.segments) == len(synthetic.records[0].segments)
    assert any("gap(s) in 'time'" in n for n in d.notes) == (len(d.segments) > 1)


def test_actuator_and_campaign_validation():
    with pytest.raises(MeasuredDataError, match="bore or its area"):
        Actuator(type="cylinder")
    with pytest.raises(MeasuredDataError, match="'piston'"):
        Actuator(type="piston", bore=0.02)
    assert Actuator(type="cylinder", bore="1 in").working_area == pytest.approx(
        np.pi / 4 * 0.0254 ** 2)
    with pytest.raises(ValueError, match="at least one record"):
        Campaign(())
    a = synthesize_cylinder(None, seed=1, pressures=(2e5,), cycles=2).records[0]
    b = synthesize_cylinder(None, seed=1, pressures=(2e5,), cycles=2, bore=0.02).records[0]
    with pytest.raises(ValueError, match="one nominal law"):
        Campaign((a, b))


def test_cli_diagnoses_a_manifest_of_measured_files(tmp_path, capsys):
    import json

    from ppamsafety.cli import main

    camp = synthesize_cylinder({"coulomb": 4.0, "coulomb_pressure": 6e-6}, seed=5,
                               pressures=(2e5, 5e5), cycles=4)
    lines = ['name = "two records"', ""]
    for i, r in enumerate(camp.records):
        r.save(tmp_path / f"r{i}.csv")
        lines += ["[[records]]", f'file = "r{i}.csv"', 'format = "measured"', ""]
    (tmp_path / "c.toml").write_text("\n".join(lines))
    out = tmp_path / "diag"
    assert main(["diagnose", str(tmp_path / "c.toml"), "--out", str(out)]) == 0
    assert "effect coulomb" in capsys.readouterr().out
    d = json.loads((out / "diagnosis.json").read_text())
    assert {"confounded", "records"} <= set(d) and len(d["records"]) == 2
    assert d["records"][1]["pressure_Pa"] == pytest.approx(5e5)
    assert (out / "diagnosis_replay.png").is_file()
    bad = tmp_path / "bad.toml"
    bad.write_text('[[records]]\nfile = "r0.csv"\nformat = "measured"\nspeed = 3\n')
    assert main(["diagnose", str(bad), "--out", str(tmp_path / "d2")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ppamsafety: error:") and "unknown key(s) ['speed']" in err


def test_a_cylinder_rod_position_may_be_negative_but_not_metres_for_millimetres(tmp_path):
    """A cylinder's ``position`` is a rod position with any zero (docs/measured_data.md), not
    a length: negative values load; 20 m (millimetres written as metres) is refused naming
    the column."""
    from ppamsafety.data import MeasuredData, load_measured

    rec = synthesize_cylinder(None, seed=2, pressures=(2e5,), cycles=2).records[0]
    frame = rec.frame.copy()
    frame["position"] = frame["position"] - frame["position"].max() - 1e-3    # all < 0
    MeasuredData(rec.meta, frame).save(tmp_path / "neg.csv")
    assert (load_measured(tmp_path / "neg.csv").column("position") < 0).all()
    frame["position"] = frame["position"] * 0 + 20.0
    with pytest.raises(MeasuredDataError, match="'position'.*10 m"):
        MeasuredData(rec.meta, frame)
