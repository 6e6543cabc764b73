"""Fast tests of the discrepancy workflow (ppamsafety.diagnose)."""

import json

import numpy as np
import pytest

from ppamsafety.cli import main
from ppamsafety.data import load_measured, synthetic_static
from ppamsafety.diagnose import diagnose, synthesize
from ppamsafety.diagnose.arm.candidates import REGISTRY, VOCABULARY, Candidate, register
from ppamsafety.diagnose.core.noise import second_difference_sigma
from ppamsafety.diagnose.arm.residuals import arm_record, block_system, model_vector
from ppamsafety.plant import packing


def test_noise_estimator_recovers_white_noise_on_smooth_signal():
    rng = np.random.default_rng(0)
    t = np.arange(20000) * 1e-3
    x = np.sin(2 * np.pi * 0.5 * t)[:, None] * [1.0, 3.0] + rng.normal(size=(20000, 2)) * [
        1e-3, 5e-3]
    # MAD scale of 20000 samples: relative standard error ~1 %; 5 % tolerance
    np.testing.assert_allclose(second_difference_sigma(x), [1e-3, 5e-3], rtol=0.05)


def test_block_residual_of_the_exact_model_is_zero(arm):
    """Noise-free record of the nominal plant: the block equations hold to integration error
    (trapezoid at 1 kHz), far below the noise (500 Pa, 2e-3 N m s)."""
    rec, _ = arm_record(synthesize(noise="none", seed=0, duration=3.0))
    bs = block_system(rec, arm)
    r = bs.y - bs.X @ model_vector(packing.pack(arm))
    assert np.max(np.abs(r[:, :4])) < 5.0           # Pa
    assert np.max(np.abs(r[:, 4:])) < 2e-5          # N m s


def test_synthesized_record_carries_no_hint(tmp_path):
    a = synthesize(effects={"payload_mass": 0.4}, seed=3, duration=1.0)
    b = synthesize(effects={"valve_time_constant_factor": 1.5}, seed=3, duration=1.0)
    assert a.meta == b.meta
    np.testing.assert_array_equal(a.column("u1"), b.column("u1"))   # same commands
    path = a.save(tmp_path / "rec.csv")
    head = "".join(ln for ln in path.read_text().splitlines(True) if ln.startswith("#"))
    for word in ("payload", "mass", "lag", "friction", "valve", "polytropic", "effect",
                 "hidden", "0.4"):
        assert word not in head.lower()


def test_synthesize_rejects_unknown_effect():
    with pytest.raises(ValueError, match="unknown effect 'warp'"):
        synthesize(effects={"warp": 1.0}, duration=1.0)


def test_diagnose_refuses_a_static_record_without_pressures():
    from ppamsafety.data import MeasuredData

    s = synthetic_static(n=5)
    f = s.frame.drop(columns=["p1", "p2", "p3", "p4"])
    with pytest.raises(ValueError, match="missing column"):
        diagnose(MeasuredData(s.meta, f))
    with pytest.raises(ValueError, match="open-loop or closed-loop"):
        arm_record(s)


def test_register_checks_the_vocabulary():
    assert set(REGISTRY) <= set(VOCABULARY)
    with pytest.raises(ValueError, match="not in the vocabulary"):
        register(Candidate("gremlin", "torque", (), "", lambda mu, phi, s: np.zeros(0)))


def test_cli_synthesize_then_diagnose_writes_the_schema(tmp_path):
    rec = tmp_path / "rec.csv"
    assert main(["synthesize", "--effect", "payload_mass=0.45", "--seed", "5",
                 "--duration", "8", "--out", str(rec)]) == 0
    assert load_measured(rec).experiment == "open-loop"
    out = tmp_path / "diag"
    assert main(["diagnose", str(rec), "--out", str(out)]) == 0
    d = json.loads((out / "diagnosis.json").read_text())
    assert d["schema_version"] == 1 and d["unexplained"] is False
    assert [e["name"] for e in d["effects"]] == ["payload"]
    m = d["effects"][0]["parameters"]["M"]
    assert m["unit"] == "kg" and m["ci_low"] <= 0.45 <= m["ci_high"]
    assert set(d["residual_rms"]["q1"]) == {"unit", "before", "after", "noise"}
    assert d["residual_rms"]["q2"]["after"] < d["residual_rms"]["q2"]["before"]
    assert (out / "diagnosis.md").is_file() and (out / "diagnosis_replay.png").is_file()
    # refuses to overwrite without the flag, exit code 2 (bad usage), output intact
    assert main(["diagnose", str(rec), "--out", str(out)]) == 2
    assert json.loads((out / "diagnosis.json").read_text()) == d
