"""Blind battery of the discrepancy workflow (issue 10 item 7).

Each case hides effects in :func:`ppamsafety.diagnose.synthesize` (10 s
open-loop record, Table 3.2 noise) and checks what :func:`diagnose` names,
never telling it what was hidden.  Magnitudes (why):

* payload 0.4 kg -- middle of the 0.3-0.5 kg objects the arm is meant to hold
  (it holds ~2 kg, §2.3.3.5);
* valve offset +5000 Pa on every valve -- 0.05 bar, half the "as high as
  0.1 bar" deviations of §3.5.1.2;
* valve lag x1.5 -- T from 45/60 ms to 68/90 ms, a valve ageing or a longer
  tube;
* Coulomb friction x3 -- c from (0.030, 0.071) to (0.091, 0.214) N m, a worn
  bearing; still small against gravity;
* polytropic n = 1.0 vs 1.4 -- isothermal against the model's isentropic;
* valve dead time 20 ms -- a slow fieldbus (two 10 ms frames).

Hysteresis hidden alone (3.35) at the thesis's delta = 0.139 (§3.6.5), in
the open-loop record and in the static sawtooth (§3.5.1.6, 21 rest points);
delta within +-0.007 (5 %: the record registers the Preisach turning points
at the 1 kHz samples, the plant at its 0.5 ms steps, and the sawtooth's
unrecorded overshoots leave minor loops).  Nothing hidden in the sawtooth:
nothing named (the false-positive check of the new candidate on the record
type it is made for).

In the sawtooth also a payload (0.4 kg, +-0.02 kg) and a valve offset
(+5000 Pa, each offset within 100 Pa): the new candidate must not take them.

Out of the library: link 1 2 % short in the plant (``geometry.L1`` 0.294 m).
Tolerances on the fitted parameters: payload +-0.02 kg (5 %), T +-10 %,
c +-35 % (errors in variables: the smooth Coulomb law of noisy velocities,
sigma_qd = 13 mrad/s against v_s = 10 mrad/s, biases c), n +-0.15, dead time
+-2 ms, valve offsets: the 95 % interval covers the truth.
"""

import os

import numpy as np
import pytest

from ppamsafety.diagnose import diagnose, synthesize
from ppamsafety.params import thesis_arm

ARM = thesis_arm()
NOM_T = np.array([v.time_constant for v in ARM.valves.valves])
NOM_V1 = np.array([v.v1 for v in ARM.valves.valves])
NOM_C = np.array(ARM.plant_base.coulomb)

#: case -> (hidden effects, expected named set)
CASES = {
    "nothing": ({}, set()),
    "payload": ({"payload_mass": 0.4}, {"payload"}),
    "valve_offset": ({"valve_offset_delta": 5000.0}, {"valve_offset_gain"}),
    "valve_lag": ({"valve_time_constant_factor": 1.5}, {"valve_lag"}),
    "friction": ({"friction_coulomb_factor": 3.0}, {"joint_friction"}),
    "polytropic": ({"polytropic_n": 1.0}, {"polytropic_exponent"}),
    "dead_time": ({"valve_dead_time": 0.02}, {"valve_dead_time"}),
    "payload+lag": ({"payload_mass": 0.4, "valve_time_constant_factor": 1.5},
                    {"payload", "valve_lag"}),
    "outside:L1": ({"geometry.L1": 0.294}, None),
    "hysteresis": ({"hysteresis_delta": 0.139}, {"hysteresis"}),
    "sawtooth:nothing": ({}, set()),
    "sawtooth:hysteresis": ({"hysteresis_delta": 0.139}, {"hysteresis"}),
    "sawtooth:payload": ({"payload_mass": 0.4}, {"payload"}),
    "sawtooth:valve_offset": ({"valve_offset_delta": 5000.0}, {"valve_offset_gain"}),
}
#: Tolerance on the fitted hysteresis delta (module docstring).
DELTA_TOL = 0.007


def check_parameters(case, dg):
    """Fitted parameters within the stated tolerances (module docstring).

    Only the effects hidden in ``case`` have a truth: an effect named in another case (e.g.
    a polytropic exponent below "high" on the out-of-library record) is not compared with
    the truth of the case that hides it.
    """
    p = {e.name: e.parameters for e in dg.effects}
    hidden = set(CASES[case][0])
    if "payload" in p and "payload_mass" in hidden:
        assert abs(p["payload"]["M"].value - 0.4) < 0.02
    if "valve_lag" in p and "valve_time_constant_factor" in hidden:
        T = np.array([p["valve_lag"][f"T_{i}"].value for i in range(1, 5)])
        np.testing.assert_allclose(T, 1.5 * NOM_T, rtol=0.10)
    if "joint_friction" in p and "friction_coulomb_factor" in hidden:
        c = np.array([p["joint_friction"]["c1"].value, p["joint_friction"]["c2"].value])
        np.testing.assert_allclose(c, 3 * NOM_C, rtol=0.35)
    if "polytropic_exponent" in p and "polytropic_n" in hidden:
        assert abs(p["polytropic_exponent"]["n"].value - 1.0) < 0.15
    if "valve_dead_time" in p and "valve_dead_time" in hidden:
        assert abs(p["valve_dead_time"]["d"].value - 0.02) <= 0.002
    if "hysteresis" in p and "hysteresis_delta" in hidden:
        assert abs(p["hysteresis"]["delta"].value - 0.139) <= DELTA_TOL
    if "valve_offset_gain" in p and case == "valve_offset":
        for i in range(4):
            v = p["valve_offset_gain"][f"v1_{i + 1}"]
            assert v.ci_low <= NOM_V1[i] + 5000 <= v.ci_high
    if "valve_offset_gain" in p and case == "sawtooth:valve_offset":
        # 21 rest points, 8 intervals per record: the all-cover rule would fail one record in
        # three by chance; the offsets must be within 100 Pa (1 mbar, 2 % of the offset)
        for i in range(4):
            v = p["valve_offset_gain"][f"v1_{i + 1}"].value
            assert abs(v - NOM_V1[i] - 5000) <= 100.0, (i, v)


def outcome(case, dg):
    """'correct' / the named set / 'unexplained (low)' for the confusion matrix."""
    named = set(dg.names)
    expected = CASES[case][1]
    if expected is None:
        high = [e.name for e in dg.effects if e.confidence_level == "high"]
        return "refused" if not high else "named high: " + "+".join(sorted(high))
    return "correct" if named == expected else ("named: " + "+".join(sorted(named)) or "none")


def run_case(case, seed):
    effects, _ = CASES[case]
    if case.startswith("sawtooth:"):
        return diagnose(synthesize("static-sawtooth", effects=effects, seed=seed), bootstrap=0)
    dg = diagnose(synthesize(effects=effects, seed=seed, duration=10.0), bootstrap=0)
    return dg


@pytest.mark.parametrize("case", ["nothing", "payload", "valve_lag", "hysteresis",
                                  "sawtooth:nothing", "sawtooth:hysteresis"])
def test_battery_fast_subset(case):
    dg = run_case(case, seed=11)
    assert outcome(case, dg) == "correct", (case, dg.names, dg.ranking().head())
    check_parameters(case, dg)
    if CASES[case][1]:
        assert all(e.confidence_level == "high" for e in dg.effects)
        # the gap shrinks in the full simulation
        assert dg.residual_rms["q2"]["after"] < dg.residual_rms["q2"]["before"] or \
            dg.residual_rms["p1"]["after"] < dg.residual_rms["p1"]["before"]


@pytest.mark.slow
def test_battery_full():
    seeds = tuple(int(x) for x in os.environ.get("PPAMSAFETY_BATTERY_SEEDS", "1,2,3,4,5").split(","))
    rows, failures = {}, []
    for case in CASES:
        counts = {}
        for s in seeds:
            dg = run_case(case, s)
            o = outcome(case, dg)
            counts[o] = counts.get(o, 0) + 1
            if o in ("correct", "refused"):
                try:
                    check_parameters(case, dg)
                except AssertionError as exc:
                    failures.append(f"{case} seed {s}: {exc}")
        rows[case] = counts
    lines = [f"diagnose blind battery: 10 s open-loop records, seeds {seeds}",
             f"{'case':<14} outcome counts"]
    for case, counts in rows.items():
        lines.append(f"{case:<14} " + "; ".join(f"{k}: {v}" for k, v in sorted(counts.items())))
    text = "\n".join(lines) + "\n"
    print(text)
    if os.environ.get("PPAMSAFETY_DIAGNOSE_BATTERY"):
        with open("/work/diagnose_confusion.txt", "w", encoding="utf-8") as fh:
            fh.write(text + ("\nparameter failures:\n" + "\n".join(failures) if failures else ""))
    n = len(seeds)
    for case, counts in rows.items():
        good = counts.get("correct", 0) + counts.get("refused", 0)
        need = 0.85 if "+" in case else (0.90 if case.startswith("outside") else 0.95)
        assert good >= need * n, (case, counts)
    assert not failures, failures
