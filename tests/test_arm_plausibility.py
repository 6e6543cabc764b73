"""An implausible arm file is refused or noted; a physically valid unusual arm is not.

A new user's likeliest mistake is a unit slip (mm for m, Pa for bar, N/Pa for N/bar, g for
kg, deg for rad, s for ms).  Each slip below is written into the shipped example arm's file
the way a user would, and must be refused with a one-line error naming the keys involved
(and the likely slip), or reported as a note, by ``ppamsafety arm check`` and by every
command that reads the file (``ppamsafety.design.load_arm``).

The converse: arms drawn at random (seeded) from the valid range -- scaled 0.4 to 2.5 times,
links with counterweights or masses near the tip, weaker or stronger muscles, other mean and
maximum pressures, slow and fast valves, a horizontal arm -- whose holding itself at some pose
is shown by an independent witness (the pressures that balance gravity, solved from the
muscle torques (2.17) and the plant's gravity torque, held for one second in the simulated
plant, which stays within 0.2 deg) are accepted without a note.
"""

import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from ppamsafety.cli import main
from ppamsafety.design import arm_notes, check_arm, load_arm
from ppamsafety.params import ArmParameters, BaseParameters, LinkInertia, thesis_arm
from ppamsafety.params.arm_file import ArmFileError, apply_arm_changes
from ppamsafety.params.effects import Effects
from ppamsafety.plant import dynamics
from ppamsafety.plant.model import simulate
from ppamsafety.plant.pneumatics import valve_set_values
from ppamsafety.plant.torque import joint_torques
from ppamsafety.units import BAR, DEG

ROOT = Path(__file__).parent.parent
EXAMPLE = ROOT / "examples" / "arms" / "forty_fibre_heavy_forearm.toml"
TEXT = EXAMPLE.read_text()


def _set(text, key, value, table=None):
    """``text`` with the first ``key = ...`` line (after ``[table]``) set to ``value``."""
    pat = re.compile(rf"^{re.escape(key)} = .*$", re.M)
    start = 0 if table is None else text.index(f"[{table}]")
    m = pat.search(text, start)
    assert m, key
    return text[:m.start()] + f"{key} = {value}" + text[m.end():]


def _write(tmp_path, text, name="arm.toml"):
    f = tmp_path / name
    f.write_text(text)
    return f


#: Table B.1's group 1 coefficients in N/Pa and in N/bar (the example arm's force law).
FL_PA = "[8.16906e-05, 0.00295069, -0.0158659, 0.036231, -0.0572879]"
FL_BAR = "[8.16906, 295.069, -1586.59, 3623.1, -5728.79]"

#: slip -> (edit of the example file, words the one-line error must hold)
REFUSED = {
    "forearm length in mm": (lambda t: _set(t, "L2", '{ value = 0.31, unit = "mm" }'),
                             ["geometry.L2 = 0.00031 m", "geometry.L33", "links.LG2",
                              "Did you mean geometry.L2 = 0.31 m"]),
    "upper arm length in mm for cm": (lambda t: _set(t, "L1", '{ value = 30, unit = "mm" }'),
                                      ["geometry.L1 = 0.03 m", "geometry.L32",
                                       "Did you mean geometry.L1 = 0.3 m"]),
    "centre of gravity beyond the forearm": (
        lambda t: _set(t, "LG2", '{ value = 1.5, unit = "m" }'),
        ["links.LG2 = 1.5 m", "geometry.L2 = 0.31 m"]),
    "mean pressure in Pa for bar": (
        lambda t: _set(t, "mean_pressure", '{ value = [1.4, 1.5], unit = "Pa" }'),
        ["pneumatics.mean_pressure = [1.4, 1.5] Pa", "pneumatics.max_pressure",
         "cannot hold itself anywhere", "Did you mean mean_pressure", "[1.4, 1.5] bar"]),
    "mean and max pressure in Pa for bar": (
        lambda t: _set(_set(t, "mean_pressure", '{ value = [1.4, 1.5], unit = "Pa" }'),
                       "max_pressure", '{ value = 3, unit = "Pa" }'),
        ["pneumatics.mean_pressure = [1.4, 1.5] Pa", "max_pressure = 3e+05 Pa (3 bar)"]),
    "mean pressure in Pa for kPa": (
        lambda t: _set(t, "mean_pressure", '{ value = [165.8, 176.2], unit = "Pa" }'),
        ["pneumatics.mean_pressure", "[1.658, 1.762] bar", "kPa written as Pa"]),
    "force law in N/Pa written as N/bar": (
        lambda t: _set(t, "force_law", f'{{ value = {FL_PA}, unit = "N/bar" }}', "muscles.group1"),
        ["muscles.group1.force_law", "muscles.group1.l0", 'write unit = "N/Pa"']),
    "force law in N/bar written as N/Pa": (
        lambda t: _set(t, "force_law", f'{{ value = {FL_BAR}, unit = "N/Pa" }}', "muscles.group3"),
        ["muscles.group3.force_law", 'write unit = "N/bar"']),
    "force law of the wrong sign": (
        lambda t: _set(t, "force_law", '{ value = [-0.0, -0.003, 0.0, 0.0, 0.0], unit = "N/Pa" }',
                       "muscles.group2"),
        ["muscles.group2.force_law", "only pulls"]),
    "forearm mass in g": (lambda t: _set(t, "m2", '{ value = 1.6, unit = "g" }'),
                          ["links.IG2", "links.m2 = 0.0016 kg", "geometry.L2"]),
    "forearm inertia in g m^2": (lambda t: _set(t, "IG2", '{ value = 17.28, unit = "kg m^2" }'),
                                 ["links.IG2 = 17.28 kg m^2", "links.m2"]),
    "valve time constant in ms written as s": (
        lambda t: _set(t, "time_constant", '{ value = 60, unit = "s" }', "valves.valve1"),
        ["valves.valve1.time_constant = 60 s"]),
    "working area in deg written as rad": (
        lambda t: _set(t, "q2_min", '{ value = -130, unit = "rad" }'), ["geometry.q2_min"]),
}

#: slip -> (edit, words of the one note)
NOTED = {
    "valve time constant in ms written as s": (
        lambda t: _set(t, "time_constant", '{ value = 5, unit = "s" }', "valves.valve2"),
        ["valves.valve2.time_constant = 5 s", 'unit = "ms"']),
    "working area in rad written as deg": (
        lambda t: _set(_set(t, "q1_min", '{ value = 0.349, unit = "deg" }'), "q1_max",
                       '{ value = 1.83, unit = "deg" }'),
        ["geometry.q1_min, geometry.q1_max", "1.48 deg", 'unit = "rad"']),
    "forearm heavier than the controllers' model": (
        lambda t: _set(_set(t, "m2LG2", '{ value = 0.3028, unit = "kg m" }', "model"),
                       "m2LG2", '{ value = 0.2943, unit = "kg m" }', "model_gravity"),
        ["model.m2LG2", "model_gravity.m2LG2", "links", "heavier", "re-identification"]),
    "model inertia in g m^2": (
        lambda t: _set(t, "IO1_m2L1sq", '{ value = 59.9, unit = "kg m^2" }', "model"),
        ["model.IO1_m2L1sq", "320 times", "g m^2"]),
    "encoder resolution in deg written as rad": (
        lambda t: _set(t, "encoder_resolution", '{ value = 0.045, unit = "rad" }'),
        ["sensors.encoder_resolution = 0.045 rad", "2.58 deg per count", 'unit = "deg"']),
    "timing clock in MHz written as Hz": (
        lambda t: _set(t, "timing_clock", '{ value = 2, unit = "Hz" }'),
        ["sensors.timing_clock = 2 Hz", "MHz"]),
}


@pytest.mark.parametrize("slip", sorted(REFUSED))
def test_arm_check_refuses_a_slip_naming_the_keys(slip, tmp_path, capsys):
    edit, words = REFUSED[slip]
    f = _write(tmp_path, edit(TEXT))
    assert main(["arm", "check", str(f)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"ppamsafety: error: {f}: "), err
    for w in words:
        assert w in err[0], (w, err[0])


@pytest.mark.parametrize("slip", sorted(NOTED))
def test_arm_check_notes_a_possible_slip_once(slip, tmp_path, capsys):
    edit, words = NOTED[slip]
    f = _write(tmp_path, edit(TEXT))
    assert main(["arm", "check", str(f)]) == 0
    cap = capsys.readouterr()
    assert "valid arm file" in cap.out and "1 note on stderr" in cap.out
    notes = [ln for ln in cap.err.splitlines() if ln.startswith("ppamsafety: note: ")]
    assert len(notes) == 1, cap.err
    for w in words:
        assert w in notes[0], (w, notes[0])


def test_the_example_and_the_thesis_arm_pass_without_a_note(tmp_path, capsys):
    thesis = _write(tmp_path, thesis_arm().to_toml(), "thesis.toml")
    for f in (EXAMPLE, thesis):
        assert main(["arm", "check", str(f)]) == 0
        cap = capsys.readouterr()
        assert "valid arm file" in cap.out and "note" not in cap.out + cap.err, cap.err
    assert arm_notes(thesis_arm()) == () and arm_notes(load_arm(EXAMPLE)) == ()


@pytest.mark.parametrize("argv", [
    ["impact", "--q", "50", "-80", "--qd", "1", "0"],
    ["synthesize", "--out", "x.csv", "--duration", "1"],
    ["report", "--quick", "--only", "design", "--outdir", "r"],
    ["arm", "export", "--out", "copy.toml"],
])
def test_every_command_reads_arm_files_with_the_checks(argv, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    f = _write(tmp_path, REFUSED["mean pressure in Pa for bar"][0](TEXT))
    assert main([*argv, "--arm", str(f)]) == 2
    err = capsys.readouterr().err
    assert "--arm" in err and "cannot hold itself anywhere" in err and "bar" in err
    assert not (tmp_path / "x.csv").exists() and not (tmp_path / "copy.toml").exists()


def test_a_study_file_arm_is_checked_and_its_note_printed(tmp_path, capsys):
    bad = _write(tmp_path, REFUSED["centre of gravity beyond the forearm"][0](TEXT), "bad.toml")
    study = _write(tmp_path, f'[arm]\nfile = "{bad.name}"\n[case]\nexperiment = "step"\n'
                             f'controller = "PID"\nduration = 3.0\n', "s.toml")
    assert main(["sweep", str(study), "--out", str(tmp_path / "o"), "--no-progress"]) == 2
    assert "links.LG2 = 1.5 m" in capsys.readouterr().err
    noted = _write(tmp_path, NOTED["forearm heavier than the controllers' model"][0](TEXT),
                   "bad.toml")
    assert noted == bad
    assert main(["sweep", str(study), "--out", str(tmp_path / "o"), "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert err.count("ppamsafety: note: ") == 1 and "model.m2LG2" in err


def test_the_note_on_the_model_comes_with_every_command(tmp_path, capsys):
    f = _write(tmp_path, NOTED["forearm heavier than the controllers' model"][0](TEXT))
    assert main(["impact", "--q", "50", "-80", "--qd", "1", "0", "--arm", str(f)]) == 0
    err = capsys.readouterr().err
    assert err.count("ppamsafety: note: ") == 1 and "model.m2LG2" in err


def test_an_effect_that_makes_the_arm_drop_is_a_note_not_an_error():
    arm = load_arm(EXAMPLE)
    heavy = arm.replace(effects=replace(arm.effects, joint_torque_bias=(20.0, 20.0)))
    check_arm(heavy)                                       # the arm itself holds
    notes = arm_notes(heavy)
    assert len(notes) == 1 and "joint_torque_bias" in notes[0] and "without them it can" in \
        notes[0]


def test_sweeps_name_every_key_of_a_cross_field_check_as_they_write_it():
    with pytest.raises(ArmFileError) as info:
        apply_arm_changes(thesis_arm(), {"arm.geometry.L2": 0.05})
    msg = str(info.value)
    assert msg.startswith("arm.geometry.L2 = 0.05 m") and "arm.links.LG2" in msg
    assert " links.LG2" not in msg
    with pytest.raises(ArmFileError, match=r"^arm\.gravity = -1 m/s\^2: must be in"):
        apply_arm_changes(thesis_arm(), {"gravity": -1.0})          # a root key too


# ---- physically valid unusual arms stay valid -------------------------------------------------

def _unusual_arm(seed: int) -> ArmParameters:
    """A self-consistent arm drawn from the valid range (module docstring); may not hold itself
    (the witness decides)."""
    rng = np.random.default_rng(seed)
    base = thesis_arm()
    s = float(np.exp(rng.uniform(np.log(0.4), np.log(2.5))))          # size
    g = base.geometry
    lengths = {f: getattr(g, f) * s for f in g.__dataclass_fields__ if not f.startswith("q")}
    shrink = rng.uniform(0.0, 25.0, 4) * DEG
    geometry = g.replace(**lengths, q1_min=g.q1_min + shrink[0], q1_max=g.q1_max - shrink[1],
                         q2_min=g.q2_min + shrink[2], q2_max=g.q2_max - shrink[3])
    # a muscle of the same shape s times larger pulls s^2 times more (thesis (2.2)); each
    # group 0.5 to 1.5 times stronger still (another membrane)
    groups = tuple(grp.__class__(name=grp.name, n_muscles=grp.n_muscles, l0=grp.l0 * s,
                                 slenderness=grp.slenderness,
                                 coefficients=tuple(c * s * s * f for c in grp.coefficients))
                   for grp, f in zip(base.muscles.groups, rng.uniform(0.5, 1.5, 4)))
    muscles = replace(base.muscles, groups=groups)
    ln = (geometry.L1, geometry.L2)
    m = [base.links.m1 * s * s * rng.uniform(0.3, 1.6),
         base.links.m2 * s * s * rng.uniform(0.3, 1.6)]
    lg = [rng.uniform(-0.2, 0.9) * ln[0], rng.uniform(-0.2, 1.0) * ln[1]]      # counterweights too
    dg = [rng.uniform(-0.1, 0.1) * ln[0], rng.uniform(-0.1, 0.1) * ln[1]]
    ig = [m[k] * (rng.uniform(0.5, 1.3) * ln[k]) ** 2 / 12.0 for k in range(2)]
    links = LinkInertia(m1=m[0], m2=m[1], LG1=lg[0], dG1=dg[0], LG2=lg[1], dG2=dg[1], IG1=ig[0],
                        IG2=ig[1], coulomb=base.links.coulomb, viscous=base.links.viscous)
    theta = links.base_parameters(geometry.L1).as_vector() * (1 + rng.normal(0, 0.02, 6))
    model = BaseParameters(*theta, coulomb=links.coulomb, viscous=links.viscous)
    p_max = rng.uniform(2.5, 6.0) * BAR
    pneumatics = replace(base.pneumatics, p_max=p_max,
                         p_mean=tuple(rng.uniform(0.3, 0.8, 2) * p_max))
    valves = base.valves.with_time_constants(np.exp(rng.uniform(np.log(0.01), np.log(0.5), 4)))
    gravity = float(rng.choice([9.81, rng.uniform(0.0, 9.81), 0.0], p=[0.6, 0.3, 0.1]))
    effects = Effects(hysteresis_delta=(0.299,) * 4) if rng.random() < 0.3 else Effects()
    return ArmParameters(geometry=geometry, muscles=muscles, valves=valves, pneumatics=pneumatics,
                         links=links, model=model, model_gravity=model, gravity=gravity,
                         effects=effects, name=f"unusual arm {seed}")


def _holds_itself(arm) -> bool:
    """The witness: at one of five poses, the pressures p_m +- dp that balance gravity lie in
    [0, p_max] and the simulated plant (effects off) held there stays within 0.2 deg for 1 s."""
    arm = arm.replace(effects=Effects())
    g = arm.geometry
    pm, p_max = arm.pneumatics.p_mean, arm.pneumatics.p_max
    for f1, f2 in ((0.5, 0.5), (0.2, 0.2), (0.8, 0.8), (0.2, 0.8), (0.8, 0.2)):
        q = np.array([g.q1_min + f1 * (g.q1_max - g.q1_min), g.q2_min + f2 * (g.q2_max - g.q2_min)])
        base = np.array([pm[0], pm[0], pm[1], pm[1]])
        t0 = joint_torques(q, base, arm)
        slope = joint_torques(q, base + np.array([1.0, -1.0, 1.0, -1.0]), arm) - t0
        dp = (dynamics.gravity(q, arm) - t0) / slope               # tau(p) = G(q): at rest
        p = np.array([pm[0] + dp[0], pm[0] - dp[0], pm[1] + dp[1], pm[1] - dp[1]])
        if not np.all((p >= 0) & (p <= p_max)):
            continue
        u = np.tile(valve_set_values(p, arm), (1000, 1))
        x = simulate(arm, np.r_[q, 0.0, 0.0, p], u, dt=1e-3, substeps=2)
        if np.max(np.abs(x[:, :2] - q)) < 0.2 * DEG:
            return True
    return False


def _valid_unusual_arms(seeds):
    drawn = [_unusual_arm(s) for s in seeds]
    held = [a for a in drawn if _holds_itself(a)]
    assert len(held) >= 0.5 * len(drawn), (len(held), len(drawn))    # the sampler is not empty
    return held


@pytest.mark.parametrize("seeds", [range(12)])
def test_unusual_valid_arms_stay_valid_without_a_note(seeds, tmp_path):
    arms = _valid_unusual_arms(seeds)
    assert {a.gravity for a in arms} - {9.81}                   # not only the thesis' gravity
    for arm in arms:
        f = _write(tmp_path, arm.to_toml(), "unusual.toml")
        assert load_arm(f) == arm, arm.name
        assert arm_notes(arm) == (), (arm.name, arm_notes(arm))


@pytest.mark.slow
def test_unusual_valid_arms_stay_valid_without_a_note_many_seeds(tmp_path):
    arms = _valid_unusual_arms(range(12, 212))
    for arm in arms:
        check_arm(arm)
        assert arm_notes(arm) == (), (arm.name, arm_notes(arm))
    f = _write(tmp_path, arms[0].to_toml(), "unusual.toml")
    assert main(["arm", "check", str(f)]) == 0


def test_the_package_reads_arm_files_only_through_the_checked_front_door():
    """``ppamsafety.params.load_arm`` (the former path, data checks only) is for old scripts:
    no module of the package may read an arm file with it."""
    pkg = ROOT / "ppamsafety"
    pattern = re.compile(r"from \.+params(?:\.arm)? import [^\n]*\bload_arm\b|params\.load_arm\(")
    users = [str(f.relative_to(ROOT)) for f in pkg.rglob("*.py")
             if f.parent.name != "params" and pattern.search(f.read_text())]
    assert not users, users
