"""Static-sawtooth records, the hysteresis candidate and the bootstrap frequency (issue 10)."""

import json

import numpy as np
import pytest

from ppamsafety.cli import main
from ppamsafety.data import load_measured
from ppamsafety.diagnose import diagnose, synthesize
from ppamsafety.diagnose.arm.residuals import hysteresis_signature
from ppamsafety.diagnose.arm.static import static_record
from ppamsafety.params import thesis_arm
from ppamsafety.params.effects import Effects
from ppamsafety.plant.model import hysteresis_factors


def test_hysteresis_signature_is_the_plant_factor():
    """W - W_fit of the signature is the plant's own factor - 1 at delta = 1 (same operator)."""
    arm = thesis_arm()
    t = np.linspace(0, 4, 400)
    q = np.stack([0.9 + 0.3 * np.sin(2 * t), -1.2 + 0.2 * np.cos(3 * t)], 1)
    p = np.full((t.size, 4), 1.5e5)
    h, h_tau, eps = hysteresis_signature(q, p, arm)
    states = np.zeros((t.size, 8))
    states[:, :2] = q
    _, fac = hysteresis_factors(states, arm.replace(effects=Effects(hysteresis_delta=(0.2,) * 4)))
    np.testing.assert_allclose(0.2 * h, fac - 1.0, atol=1e-12)
    assert np.ptp(h) > 0.1            # the loop is traversed: W - W_fit moves by >= 0.1


def test_static_sawtooth_record_and_hysteresis_localised(tmp_path):
    data = synthesize("static-sawtooth", {"hysteresis_delta": 0.139}, seed=2, duration=36.0)
    assert data.experiment == "static-sawtooth"
    path = data.save(tmp_path / "saw.csv")
    back = load_measured(path)
    rec, _ = static_record(back)
    assert rec.m == 7 and rec.F is not None and rec.u is not None
    dg = diagnose(back, bootstrap=10)
    assert dg.names == ("hysteresis",) and not dg.unexplained
    d = dg.effects[0].parameters["delta"].value
    assert abs(d - 0.139) <= 0.007
    assert dg.effects[0].evidence["bootstrap_frequency"] >= 0.9
    f = dg.subsystems["forces"]
    # §3.5.1.6 localisation: the forces are wrong (>> noise), the valves are not
    assert min(f["rho_before"]) > 3 and max(f["rho_after"]) < 1.5
    assert dg.residual_rms["block_p1"]["before"] < 1.5
    # the model's rest angles move onto the measured ones
    for q in ("q1", "q2"):
        assert dg.residual_rms[q]["after"] < 0.2 * dg.residual_rms[q]["before"]
    js = dg.to_dict()
    assert js["forces"]["delta_forces"] == pytest.approx(0.139, abs=0.007)


def test_cli_synthesize_static_sawtooth(tmp_path):
    rec = tmp_path / "saw.csv"
    assert main(["synthesize", "--experiment", "static-sawtooth", "--duration", "16",
                 "--seed", "1", "--out", str(rec)]) == 0
    out = tmp_path / "diag"
    assert main(["diagnose", str(rec), "--out", str(out), "--bootstrap", "5"]) == 0
    d = json.loads((out / "diagnosis.json").read_text())
    assert d["effects"] == [] and d["settings"]["rest_points"] == 3
    assert d["settings"]["bootstrap"]["replicates"] == 5


def test_bootstrap_frequency_in_the_evidence():
    dg = diagnose(synthesize(effects={"payload_mass": 0.4}, seed=4, duration=6.0), bootstrap=8)
    ev = dg.effects[0].evidence
    assert dg.names == ("payload",) and 0.0 <= ev["bootstrap_frequency"] <= 1.0
    assert ev["bootstrap_frequency"] >= 0.75
    with pytest.raises(ValueError, match="bootstrap"):
        diagnose(synthesize(duration=1.0), bootstrap=-1)
