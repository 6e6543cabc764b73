"""The whole command-line path on the shipped example arm, as a user runs it.

``ppamsafety arm check``, ``impact``, ``sweep`` (a grid and an envelope study file naming the
arm file), ``synthesize``, ``diagnose`` and a quick ``report``, each a fresh
``python -m ppamsafety.cli`` process given ``examples/arms/forty_fibre_heavy_forearm.toml``:
exit 0, no traceback, no error line, and outputs that exist and are sane (finite, positive
where physics says so, the example arm's name and fingerprint where the output records it).
CI runs it with the slow tests.
"""

import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from ppamsafety.data import load_measured
from ppamsafety.design import load_arm
from ppamsafety.params.arm_file import arm_fingerprint

#: A minute or two of fresh processes: behind ``-m slow``, which CI runs (``.ci/run``).
pytestmark = pytest.mark.slow

ROOT = Path(__file__).parent.parent
EXAMPLE = ROOT / "examples" / "arms" / "forty_fibre_heavy_forearm.toml"
NAME = "40-fibre muscles, heavier forearm"


def _run(folder: Path, *argv, timeout=900):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    r = subprocess.run([sys.executable, "-m", "ppamsafety.cli", *map(str, argv)], cwd=folder,
                       capture_output=True, text=True, env=env, timeout=timeout)
    assert r.returncode == 0, (argv, r.returncode, r.stdout[-2000:], r.stderr[-2000:])
    assert "Traceback" not in r.stderr and "ppamsafety: error" not in r.stderr, r.stderr
    return r.stdout, r.stderr


def _number(text: str, label: str) -> float:
    m = re.search(rf"^\s*{re.escape(label)}\s+(-?[\d.]+(?:e[-+]?\d+)?)", text, re.M)
    assert m, (label, text)
    return float(m.group(1))


def _finite_csv(path: Path, columns=()) -> pd.DataFrame:
    """The table, with ``columns`` (those present) finite; no numeric column but ``error``
    (empty when every case ran) NaN throughout."""
    df = pd.read_csv(path)
    assert len(df), path
    for c in columns:
        if c in df.columns:
            assert np.isfinite(df[c].to_numpy(dtype=float)).all(), (path, c)
    num = df.select_dtypes("number").drop(columns=["error"], errors="ignore")
    assert not num.isna().all().any(), (path, list(num.columns[num.isna().all()]))
    return df


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    return tmp_path_factory.mktemp("example_arm_cli")


def test_arm_check(work):
    out, err = _run(work, "arm", "check", EXAMPLE)
    assert f"valid arm file ({NAME}; sha256 {arm_fingerprint(load_arm(EXAMPLE))[:16]})" in out
    assert "note" not in err
    k1 = _number(out, "joint stiffness K1 at the pose (2.18)")
    k2 = _number(out, "joint stiffness K2 at the pose (2.18)")
    assert 0 < k2 < k1 < 200                          # N m/rad; the thesis arm: 43 and 27
    assert 0 < _number(out, "holdable share of the working area (Delta-p)") <= 100
    # kg; the heavier forearm cannot carry itself at p_max everywhere (a negative minimum)
    assert -20 < _number(out, "maximum load at A_L, min over the working area") < 20
    assert 0 < _number(out, "maximum load at A_L, median over the area") < 20


def test_impact(work):
    out, _ = _run(work, "impact", "--q", "50", "-80", "--qd", "1", "0", "--arm", EXAMPLE)
    assert re.search(rf"^arm\s+{re.escape(NAME)}$", out, re.M), out
    f = _number(out, "F_max")
    assert 10 < f < 5000                              # N, a 0.47 m/s impact on a head
    assert 0 <= _number(out, "HIC36") < 1000
    m = re.search(r"energy to head\s+([\d.e-]+) J of ([\d.e-]+) J", out)
    assert m and 0 < float(m.group(1)) <= float(m.group(2)), out


def test_sweep_over_the_arm_file(work):
    (work / "grid.toml").write_text(f"""
[study]
name = "example arm, two mean pressures"
[arm]
file = "{EXAMPLE}"
[case]
experiment = "step"
controller = "PSMC joint"
duration = 4.0
[impact]
instants = "max TCP speed"
[grid]
arm.pneumatics.mean_pressure = {{ values = [1.4, 1.8], unit = "bar" }}
""")
    out, _ = _run(work, "sweep", "grid.toml", "--out", "grid", "--processes", "1",
                  "--no-progress")
    assert "2 ok, 0 failed" in out
    folder = work / "grid"
    df = _finite_csv(folder / "results.csv", ("F_max [N]", "HIC36 [-]"))
    assert list(df["status"]) == ["ok", "ok"] and (df["F_max [N]"] > 0).all()
    # the swept key in the unit the study file wrote it in
    assert sorted(df["arm.pneumatics.mean_pressure [bar]"]) == [1.4, 1.8]
    assert load_arm(folder / "arm.toml") == load_arm(EXAMPLE)
    assert NAME in (folder / "summary.html").read_text()


def test_envelope_study(work):
    (work / "env.toml").write_text(f"""
[study]
name = "example arm speed envelope"
[arm]
file = "{EXAMPLE}"
[envelope]
parameter = "speed"
range = [0.2, 3.0]
limit = "F_max"
tolerance = 0.05
pose = [50.0, -80.0]
""")
    _run(work, "sweep", "env.toml", "--out", "env", "--processes", "1", "--no-progress")
    df = _finite_csv(work / "env" / "results.csv", ("speed [m/s]", "F_max [N]", "margin [N]"))
    assert set(df["status"]) == {"ok"} and df["safe"].any() and not df["safe"].all()
    safe, unsafe = df[df["safe"]], df[~df["safe"]]
    assert safe["speed [m/s]"].max() < unsafe["speed [m/s]"].min()   # one boundary, bracketed
    assert (safe["F_max [N]"] < 660).all() and (unsafe["F_max [N]"] >= 660).all()
    assert np.allclose(df["margin [N]"], 660 - df["F_max [N]"])
    assert "safe for speed &lt;=" in (work / "env" / "summary.html").read_text()


@pytest.fixture(scope="module")
def record(work):
    _run(work, "synthesize", "--arm", EXAMPLE, "--out", "rec.csv", "--duration", "5",
         "--seed", "3")
    return work / "rec.csv"


def test_synthesize(record):
    rec = load_measured(record)
    assert rec.meta["arm"]["sha256"] == arm_fingerprint(load_arm(EXAMPLE))
    t = rec.frame["t"].to_numpy()
    assert t[-1] == pytest.approx(5.0, abs=0.01) and np.isfinite(rec.frame.to_numpy(float)).all()
    q = rec.frame[["q1", "q2"]].to_numpy()
    g = load_arm(EXAMPLE).geometry
    assert (q[:, 0] > g.q1_min - 0.2).all() and (q[:, 0] < g.q1_max + 0.2).all()


def test_diagnose(work, record):
    out, _ = _run(work, "diagnose", record, "--arm", EXAMPLE, "--out", "dg")
    assert re.search(r"^unexplained: (no|yes)", out, re.M) and "diagnosis written to dg" in out
    files = {p.name for p in (work / "dg").iterdir()}
    assert {"diagnosis.md", "diagnosis.json"} <= files, files
    dg = json.loads((work / "dg" / "diagnosis.json").read_text())
    rms = dg["residual_rms"]
    assert rms and all(math.isfinite(v["before"]) and math.isfinite(v["after"])
                       for v in rms.values())


def test_quick_report(work):
    out, _ = _run(work, "report", "--quick", "--arm", EXAMPLE, "--only", "design,stiffness",
                  "--outdir", "rep", "--processes", "1")
    rep = work / "rep"
    md = (rep / "index.md").read_text()
    assert f"**{NAME}**" in md and md.count(f"*Computed for arm `{NAME}`") == 2
    assert load_arm(rep / "arm.toml") == load_arm(EXAMPLE) and (rep / "index.html").is_file()
    csvs = list(rep.glob("*.csv"))
    assert csvs
    for f in csvs:
        _finite_csv(f, ("F_max", "F_max [N]", "HIC36", "K1_Nm_per_rad", "K2_Nm_per_rad"))
