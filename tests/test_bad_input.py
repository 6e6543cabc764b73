"""Bad input, second pass (issue 22): one hypothesis strategy per input class, and the battery.

Each class of invalid input has a strategy that generates members of the class (not the
examples of the issue), and a property every member must meet: a ``ValueError`` /
``TypeError`` (exit 2 on the command line) naming the argument, option, key or column and
what is allowed, or a sane result; never a silent acceptance of the impossible, a hang, a
``MemoryError`` or a lost user file.  Example counts stay small (the default suite runs in
about ten minutes on two cores); ``pytest -m slow tests/test_bad_input.py`` runs more
examples and the whole command-line battery (``tests/bad_input_battery.py``).
"""

import json
import math
import os
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, assume, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from ppamsafety._validation import (InvalidTypeError, as_float_array, check_choice,  # noqa: E402
                                    check_int, check_numbers, check_real, check_seed)
from ppamsafety.cli import build_parser, main  # noqa: E402
from ppamsafety.data.measured import (PLAUSIBILITY, MeasuredData, MeasuredDataError,  # noqa: E402
                                      MeasuredDataWarning)
from ppamsafety.diagnose.arm.synthesize import plant_with  # noqa: E402
from ppamsafety.diagnose.bench.synthesize import EFFECTS as TESTER_EFFECTS  # noqa: E402
from ppamsafety.diagnose.bench.synthesize import _check_effects  # noqa: E402
from ppamsafety.impact.hic import hic  # noqa: E402
from ppamsafety.layouts import check_flag  # noqa: E402
from ppamsafety.control.laws.pid import PIDDerivative  # noqa: E402
from ppamsafety.output import MARKER, OutputError, OutputFolder, read_marker  # noqa: E402
from ppamsafety.params import thesis_arm  # noqa: E402
from ppamsafety.params.effects import Effects  # noqa: E402
from ppamsafety.study_files import (CONFIRM_HOURS, StudyFileError, check_run_size,  # noqa: E402
                                    estimate_cases, parse_study)
from ppamsafety.sweep import ResultColumnError, run_sweep  # noqa: E402
from ppamsafety.sweep_cases import check_case  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
FEW = settings(max_examples=25, deadline=None, suppress_health_check=list(HealthCheck),
               derandomize=True)
ARM = thesis_arm()


def _names(msg: str, *words) -> bool:
    return any(w.lower() in msg.lower() for w in words)


# ---- class: NAME=VALUE effects (synthesize --effect) --------------------------------------

ARM_EFFECTS = sorted(set(Effects.names()) - {"hysteresis_initial"}) + [
    "valve_time_constant_factor", "valve_gain_factor", "friction_coulomb_factor",
    "valve_offset_delta", "valve_dead_time", "pressure_sensor_offset", "geometry.L1"]
bad_number_text = st.one_of(
    st.sampled_from(["inf", "-inf", "nan", "NaN", "", " ", "abc", "1e400", ",", "1,,2", "0x10",
                     "1 2", "--1", "1e", "None", "[1, 2]"]),
    st.lists(st.sampled_from(["1", "0.5", "2e-3", "nan", ""]), min_size=2, max_size=7).map(
        ",".join),
    st.text(alphabet="0123456789.,-e+ ", max_size=8))


@FEW
@given(name=st.sampled_from(ARM_EFFECTS), value=bad_number_text)
def test_effect_values_as_text_are_parsed_or_refused_naming_the_effect(name, value):
    try:
        plant_with(ARM, {name: value})
    except (TypeError, ValueError) as exc:
        assert _names(str(exc), name), str(exc)
    else:                                    # accepted: it was numbers of a valid count
        vals = [float(v) for v in value.split(",")]
        assert all(math.isfinite(v) for v in vals)


@FEW
@given(name=st.sampled_from(TESTER_EFFECTS), value=bad_number_text)
def test_tester_effect_values_are_parsed_or_refused_naming_the_effect(name, value):
    try:
        _check_effects({name: value})
    except (TypeError, ValueError) as exc:
        assert _names(str(exc), name), str(exc)


@FEW
@given(value=bad_number_text)
def test_cli_effect_values_exit_2_naming_the_effect(value, tmp_path_factory):
    out = tmp_path_factory.mktemp("syn") / "x.csv"
    with _captured() as (err,):
        rc = main(["synthesize", "--duration", "0.5", "--out", str(out), "--effect",
                   f"payload_mass={value}"])
    if rc == 0:
        assert float(value) >= 0 and out.exists()
    else:
        assert rc == 2 and "payload_mass" in err.text() and "internal failure" not in err.text()


# ---- class: measured-data columns (physical plausibility) -----------------------------------

def _open_loop(n=40, dt=1e-3):
    t = np.arange(n) * dt
    df = pd.DataFrame({"t": t, "q1": 0.8 + 0.01 * np.sin(t), "q2": -1.4 + 0 * t,
                       "qd1": 0.01 * np.cos(t), "qd2": 0 * t,
                       **{f"p{i}": 1.5e5 + 1e3 * i + 0 * t for i in range(1, 5)},
                       **{f"u{i}": 1.5e5 + 0 * t for i in range(1, 5)}})
    return {"kind": "arm", "experiment": "open-loop", "sample_rate": 1000.0}, df


scales = st.sampled_from([1e-5, 1e-3, 1e-2, 180 / math.pi, 1e3, 1e4, 1e6, -1.0, 0.0])
offsets = st.sampled_from([0.0, -3e5, 2e6, 1e9, 7.0, -7.0, 1e300])


@FEW
@given(col=st.sampled_from(["q1", "q2", "qd1", "qd2", "p1", "p3", "u2", "u4"]), scale=scales,
       offset=offsets, strict=st.booleans())
def test_measured_columns_impossible_refused_suspicious_warned(col, scale, offset, strict):
    meta, df = _open_loop()
    df[col] = df[col] * scale + offset
    lo, hi = PLAUSIBILITY["arm"][col][:2]
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        try:
            d = MeasuredData(meta, df, strict_units=strict, source="X.csv")
        except MeasuredDataError as exc:
            assert f"'{col}'" in str(exc) and "X.csv" in str(exc), str(exc)
            return
    x = d.column(col)                     # accepted: nothing impossible, warnings one line
    assert np.all((x >= lo) & (x <= hi)), (col, x.min(), x.max())
    for m in w:
        assert issubclass(m.category, MeasuredDataWarning) and "\n" not in str(m.message)


def _csv_bytes(meta_lines, header, rows, sep=","):
    body = "".join(f"# {ln}\n" for ln in meta_lines) + sep.join(header) + "\n"
    return (body + "".join(sep.join(map(str, r)) + "\n" for r in rows)).encode("utf-8")


file_bodies = st.one_of(
    st.binary(max_size=300),
    st.sampled_from([b"", b"\n\n", b"\xef\xbb\xbf", b"\x00" * 50, "µ".encode("latin-1") * 9]),
    st.builds(lambda sep, enc, n: (_csv_bytes(['kind = "arm"', 'experiment = "open-loop"'],
                                              ["t", "q1", "q2", "qd1", "qd2", "p1", "p2", "p3",
                                               "p4"],
                                              [[i * 1e-3, 0.7, -1.4, 0, 0, 1.5e5, 1.5e5, 1.5e5,
                                                1.5e5] for i in range(n)], sep)
                                   .decode().encode(enc, errors="replace")),
              sep=st.sampled_from([",", ";", "\t", " ", "|"]),
              enc=st.sampled_from(["utf-8", "utf-16", "latin-1", "utf-8-sig"]),
              n=st.integers(0, 30)))


@FEW
@given(body=file_bodies)
def test_data_file_bytes_load_or_are_refused_naming_the_file(tmp_path_factory, body):
    from ppamsafety.data import load_measured
    f = tmp_path_factory.mktemp("data") / "d.csv"
    f.write_bytes(body)
    try:
        load_measured(f)
    except MeasuredDataError as exc:
        assert str(f) in str(exc), str(exc)


@FEW
@given(qd=st.tuples(st.floats(-200, 200), st.floats(-200, 200)),
       vh=st.sampled_from([None, (0.0, 0.0), (-40.0, 0.0), (5.0, 5.0)]))
def test_impossible_impact_speeds_are_refused_before_simulating(qd, vh):
    from ppamsafety.impact.model import MAX_SPEED, PLAUSIBLE_SPEED, simulate_impacts
    from ppamsafety.plant.geometry import jacobian
    q = np.radians([30.0, -80.0])
    speed = float(np.linalg.norm(jacobian(q[None], ARM)[0] @ np.array(qd)))
    hspeed = 0.0 if vh is None else float(np.hypot(*vh))
    try:
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            simulate_impacts(ARM, q, list(qd), [43.0, 27.0], head_velocity=vh, duration=0.005)
    except ValueError as exc:
        assert max(speed, hspeed) > MAX_SPEED or "pass through" in str(exc) or \
            "stiffness" in str(exc), str(exc)
        assert _names(str(exc), "qd", "head_velocity", "stiffness"), str(exc)
        return
    assert max(speed, hspeed) <= MAX_SPEED
    if max(speed, hspeed) > PLAUSIBLE_SPEED:
        assert any("plausible maximum" in str(m.message) for m in w)


# ---- class: study files ---------------------------------------------------------------------

KEYS = ["experiment", "controller", "lam", "kp_bar", "ki_bar", "stiffness", "head", "instants",
        "every", "noise_seed", "duration", "effects", "Experiment", "lamda", "x"]
toml_values = st.one_of(
    st.sampled_from(['"step"', '"Step"', '"PID"', '"pid"', '"PSMC joint"', '"all"', "true",
                     "nan", "inf", "-inf", "1e300", "-1", "0", "0.5", "1.5", "3", "12",
                     "1e9", '""', "[]", "[1, 2]", "[1, 2, 3]", "{}", "{ x = 1 }"]),
    st.integers(-10, 10 ** 6).map(str), st.floats(-1e4, 1e4).map(repr))


@FEW
@given(table=st.sampled_from(["case", "impact", "grid", "output", "study", "cases"]),
       key=st.sampled_from(KEYS + ["csv", "histories", "name"]), value=toml_values)
def test_study_file_values_refused_naming_the_key_or_loaded_and_costed(table, key, value):
    text = ('[case]\nexperiment = "step"\n' if table != "case" else "") + \
        f"[{table}]\n{key} = {value}\n"
    t0 = time.perf_counter()
    try:
        st_ = parse_study(text, where="s.toml")
    except StudyFileError as exc:
        assert str(exc).startswith("s.toml: ") and _names(str(exc), key, table), str(exc)
        return
    assert time.perf_counter() - t0 < 30
    est = estimate_cases(st_.cases)
    assert est["cases"] == len(st_.cases) >= 1 and est["bytes"] > 0


@FEW
@given(nums=st.lists(st.integers(1, 10 ** 9), min_size=1, max_size=3))
def test_huge_grids_load_at_once_and_are_refused_before_running(nums):
    keys = ["stiffness", "duration", "lam"][:len(nums)]
    gens = {"stiffness": "geomspace = [1, 100, {}]", "duration": "linspace = [3, 12, {}]",
            "lam": "geomspace = [0.1, 1.0, {}]"}
    text = '[case]\nexperiment = "step"\ncontroller = "PSMC joint"\n[grid]\n' + "".join(
        f"{k} = {{ {gens[k].format(n)} }}\n" for k, n in zip(keys, nums))
    t0 = time.perf_counter()
    s = parse_study(text, where="s.toml")
    assert time.perf_counter() - t0 < 30                    # never materialised
    assert len(s.cases) == math.prod(nums)
    est = estimate_cases(s.cases, processes=2)
    if est["wall_seconds"] > CONFIRM_HOURS * 3600:
        with pytest.raises(StudyFileError, match=r"--max-cases") as e:
            check_run_size(s, est)
        assert f"{len(s.cases):,} cases" in str(e.value)
    last = s.cases[len(s.cases) - 1]
    assert last["stiffness"] == pytest.approx(100.0 if nums[0] > 1 else 1.0)


# ---- class: command-line option values -----------------------------------------------------

OPTIONS = [(["diagnose", "d.csv", "--out", "o"], ["--seed", "--block", "--bootstrap", "--alpha",
                                                  "--rho-max"]),
           (["identify", "d.csv", "--kind", "static", "--out", "o"],
            ["--drop", "--confidence", "--sign-velocity"]),
           (["synthesize", "--out", "x.csv"], ["--seed", "--duration", "--cycles", "--period",
                                                "--sample-rate", "--jitter"]),
           (["sweep", "s.toml", "--out", "o"], ["--processes", "--max-cases"]),
           (["impact", "--q", "30", "-80", "--qd", "1", "0"], ["--dt", "--head"]),
           (["report"], ["--processes", "--only", "--outdir"])]
option_text = st.one_of(st.sampled_from(["", "nan", "inf", "-1", "0", "1e9", "1e400", "abc",
                                         "1.5", "-0", "99999999999999999999999", "0x1"]),
                        st.text(max_size=6))


@FEW
@given(cmd=st.sampled_from(OPTIONS), data=st.data())
def test_option_values_are_parsed_or_refused_naming_the_option(cmd, data):
    argv, opts = cmd
    opt = data.draw(st.sampled_from(opts))
    value = data.draw(option_text)
    with _captured() as (err,):
        try:
            build_parser().parse_args([*argv, f"{opt}={value}"])
        except SystemExit as e:
            assert e.code == 2
            assert f"argument {opt}" in err.text(), err.text()
        # any other exception fails the test: a value must never crash the parser


# ---- class: output folders and files ---------------------------------------------------------

folder_states = st.fixed_dictionaries({
    "kind": st.sampled_from([None, "report", "sweep", "diagnose", "identify"]),
    "foreign": st.booleans(), "bad_marker": st.booleans()})


@FEW
@given(state=folder_states, kind=st.sampled_from(["sweep", "diagnose", "report"]),
       overwrite=st.booleans(), replace_kind=st.booleans())
def test_output_folders_never_lose_a_file_and_refuse_another_kind(tmp_path_factory, state, kind,
                                                                  overwrite, replace_kind):
    d = tmp_path_factory.mktemp("o")
    files = {}
    if state["kind"] is not None:
        files["old.csv"] = "old"
        (d / MARKER).write_text("{not json" if state["bad_marker"] else json.dumps(
            {"tool": "ppamsafety", "version": "0", "kind": state["kind"], "files": ["old.csv"]}))
    if state["foreign"]:
        files["thesis.tex"] = "mine"
    for f, t in files.items():
        (d / f).write_text(t)
    try:
        with OutputFolder(d, kind=kind, overwrite=overwrite, replace_kind=replace_kind) as stage:
            (stage / "new.csv").write_text("new")
    except OutputError as exc:
        assert str(d) in str(exc)
        for f, t in files.items():
            assert (d / f).read_text() == t              # untouched
        if state["kind"] not in (None, kind) and not state["foreign"] and \
                not state["bad_marker"] and overwrite:
            assert "--replace-other-kind" in str(exc) and state["kind"] in str(exc)
        return
    assert (d / "new.csv").read_text() == "new"
    if state["foreign"]:
        pytest.fail("a folder with a foreign file was used")
    if state["kind"] not in (None, kind):
        assert overwrite and replace_kind
    assert read_marker(d)["kind"] == kind


def test_read_only_target_names_the_users_path_not_a_temporary_file(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    os.chmod(ro, 0o555)
    immutable = False
    if os.geteuid() == 0:                   # root ignores permissions: make it immutable
        immutable = subprocess.run(["chattr", "+i", str(ro)], capture_output=True).returncode == 0
        if not immutable:
            pytest.skip("cannot make a read-only folder as root here")
    try:
        with _captured() as (err,):
            rc = main(["impact", "--q", "30", "-80", "--qd", "1", "0", "--history",
                       str(ro / "h.csv")])
        assert rc == 2
        assert "'" + str(ro / "h.csv") + "'" in err.text() and ".tmp" not in err.text()
        with pytest.raises(OutputError, match="read-only") as e:
            with OutputFolder(ro / "sub", kind="report"):
                pass
        assert "staging" not in str(e.value)
    finally:
        if immutable:
            subprocess.run(["chattr", "-i", str(ro)])
        os.chmod(ro, 0o755)


def test_overwrite_lists_what_it_replaces(tmp_path, caplog):
    d = tmp_path / "o"
    with OutputFolder(d, kind="sweep") as stage:
        (stage / "a.csv").write_text("1")
    with caplog.at_level("INFO", logger="ppamsafety.output"):
        with OutputFolder(d, kind="sweep", overwrite=True) as stage:
            (stage / "b.csv").write_text("2")
    assert "replacing the previous ppamsafety sweep" in caplog.text and "'a.csv'" in caplog.text
    with pytest.raises(OutputError, match=r"holds a previous ppamsafety sweep output .*not a "
                                          r"diagnose.*--replace-other-kind"):
        with OutputFolder(d, kind="diagnose", overwrite=True):
            pass
    assert (d / "b.csv").read_text() == "2"


def test_single_file_into_a_toolkit_folder_is_refused(tmp_path):
    d = tmp_path / "o"
    with OutputFolder(d, kind="sweep") as stage:
        (stage / "r.csv").write_text("1")
    with _captured() as (err,):
        rc = main(["synthesize", "--duration", "1", "--out", str(d / "r.csv"), "--overwrite"])
    assert rc == 2 and "sweep output folder" in err.text()
    assert (d / "r.csv").read_text() == "1"


# ---- class: choices, loose types and magnitudes (the policy of _validation) -------------------

@FEW
@given(name=st.sampled_from(["thesis-frontal", "child-frontal", "open-loop", "PID"]),
       how=st.sampled_from([str.upper, str.title, lambda s: " " + s, lambda s: s + " ",
                            lambda s: s.replace("-", "_"), str.swapcase]))
def test_mis_cased_or_padded_choices_are_refused_with_the_right_spelling(name, how):
    bad = how(name)
    assume(bad != name)
    with pytest.raises(ValueError) as e:
        check_choice("x", bad, ["thesis-frontal", "child-frontal", "open-loop", "PID"])
    assert f"did you mean {name!r}" in str(e.value)


@FEW
@given(how=st.sampled_from([str.title, str.capitalize, lambda s: s[:-1] + s[-1].upper()]))
def test_enum_flags_accept_two_spellings_only(how):
    for m in PIDDerivative:
        good = m.name.lower()
        assert check_flag(PIDDerivative, good, "d") == int(m)
        assert check_flag(PIDDerivative, m.name, "d") == int(m)
        assert check_flag(PIDDerivative, good.replace("_", "-"), "d") == int(m)
        if how(good) not in (good, m.name):
            with pytest.raises(ValueError, match="did you mean"):
                check_flag(PIDDerivative, how(good), "d")


@FEW
@given(x=st.floats(-1e6, 1e6))
def test_zero_d_arrays_are_numbers_and_one_element_arrays_are_not(x):
    assert check_real("x", np.array(x)) == x and type(check_real("x", np.array(x))) is float
    with pytest.raises(InvalidTypeError):
        check_real("x", np.array([x]))
    assert check_int("n", np.array(3)) == 3
    assert check_case(controller="PSMC joint", lam=np.array(abs(x) % 50))["lam"] is not None


@FEW
@given(mask=st.lists(st.booleans(), min_size=4, max_size=4))
def test_masked_entries_are_refused_never_unmasked(mask):
    a = np.ma.masked_array([1.0, 2.0, 30.0, 4.0], mask=mask)
    if any(mask):
        with pytest.raises(ValueError, match=r"masked array with \d masked entr"):
            as_float_array("a", a)
        with pytest.raises(ValueError, match="a is a masked array"):
            hic(a, 1e-4)
    else:
        assert as_float_array("a", a).tolist() == [1.0, 2.0, 30.0, 4.0]


@FEW
@given(dt=st.sampled_from([1e-300, 1e-12, 0.0, -1e-4, 1e300, math.nan]),
       rows=st.integers(0, 2))
def test_hic_steps_and_batches(dt, rows):
    with pytest.raises(ValueError) as e:
        hic(np.ones((rows, 0 if rows == 2 else 100)) if rows != 1 else np.ones(100), dt)
    assert _names(str(e.value), "dt", "a "), str(e.value)


@FEW
@given(text=st.sampled_from(["-1", "1.5", "abc", str(2 ** 63), str(2 ** 70), "1e9", "-0"]))
def test_seeds_are_integers_in_0_to_2_63(text):
    try:
        v = int(text)
    except ValueError:
        with pytest.raises((TypeError, ValueError)):
            check_seed("seed", text)
        return
    if 0 <= v < 2 ** 63:
        assert check_seed("seed", v) == v
    else:
        with pytest.raises(ValueError, match=r"seed = .* is outside \[0, 9223372036854775807\]"):
            check_seed("seed", v)


def test_numbers_as_text():
    assert check_numbers("e", "1, 2,3", (1, 3)) == (1.0, 2.0, 3.0)
    assert check_numbers("e", np.array(0.5)) == (0.5,)
    for bad, word in (("inf", "finite"), ("", "empty"), ("1,,2", r"e\[1\] = ''"),
                      ("1,2", "takes 1 or 3 values")):
        with pytest.raises(ValueError, match=word):
            check_numbers("e", bad, (1, 3))


# ---- run_sweep contracts ---------------------------------------------------------------------

def _square(x):
    return {"sq": x * x}


def _clash(x):
    return {"x": 99, "r": 1}


def test_run_sweep_refuses_an_empty_cache_dir_and_a_result_named_like_a_parameter(tmp_path,
                                                                                  monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match="cache_dir = '' is an empty path"):
        run_sweep(_square, [{"x": 1}], cache_dir="", progress=False)
    assert list(tmp_path.iterdir()) == []
    for on_error in ("record", "raise"):
        with pytest.raises(ResultColumnError, match=r"\['x'\] have the name of a case parameter"):
            run_sweep(_clash, [{"x": 1}], progress=False, on_error=on_error)


def test_run_sweep_streams_a_grid():
    df = run_sweep(_square, grid={"x": [1, 2, 3]}, progress=False)
    assert df["sq"].tolist() == [1, 4, 9]


# ---- class: input text files (arm, head, study files, campaign manifests) --------------------

def _readers():
    from ppamsafety.data.campaign import load_campaign
    from ppamsafety.design import load_arm
    from ppamsafety.impact.head import load_head
    from ppamsafety.study_files import load_study
    return {"arm": load_arm, "head": load_head, "study": load_study, "campaign": load_campaign}


text_file_states = st.one_of(
    st.tuples(st.just("bytes"), st.one_of(
        st.binary(max_size=200),
        st.sampled_from([b"", b"\xef\xbb\xbf", b"\x00\x01", b"a = \xb5\n", b"[x]\r\n\x00",
                         b"\xff\xfe[\x00c\x00]\x00"]))),
    st.tuples(st.sampled_from(["folder", "fifo", "missing", "dangling-link", "dev-zero",
                               "under-a-file", "empty-path", "none", "bytes-path"]),
              st.just(b"")))


@FEW
@given(kind=st.sampled_from(["arm", "head", "study", "campaign"]), state=text_file_states)
def test_input_text_files_are_read_or_refused_naming_the_file(tmp_path_factory, kind, state):
    from ppamsafety._inputfiles import MissingFileError
    how, content = state
    d = tmp_path_factory.mktemp("in")
    f = d / "x.toml"
    arg = f
    if how == "bytes":
        f.write_bytes(content)
    elif how == "folder":
        f.mkdir()
    elif how == "fifo":
        os.mkfifo(f)
    elif how == "dangling-link":
        f.symlink_to(d / "nowhere.toml")
    elif how == "dev-zero":
        f.symlink_to("/dev/zero")
    elif how == "under-a-file":
        (d / "f.txt").write_text("x")
        arg = f = d / "f.txt" / "x.toml"
    elif how == "empty-path":
        arg = ""
    elif how == "none":
        arg = None
    elif how == "bytes-path":
        arg = b"x.toml"
    t0 = time.perf_counter()
    try:
        _readers()[kind](arg)
    except (TypeError, ValueError) as exc:   # MissingFileError is a ValueError too
        msg = str(exc)
        assert "\n" not in msg.strip() or kind == "campaign", msg
        if how in ("none", "bytes-path"):
            assert isinstance(exc, TypeError) and "path" in msg, msg
        elif how == "empty-path":
            assert "empty" in msg, msg
        else:
            assert str(f) in msg or f.name in msg, msg
        if how in ("missing", "dangling-link", "under-a-file"):
            assert isinstance(exc, MissingFileError) and isinstance(exc, FileNotFoundError)
    else:
        assert how == "bytes"                # only a readable file can load
    assert time.perf_counter() - t0 < 10     # never reads a pipe or a device


@FEW
@given(kind=st.sampled_from(["arm", "head", "study"]), bom=st.booleans(), crlf=st.booleans())
def test_bom_and_crlf_are_read_like_plain_utf8(tmp_path_factory, kind, bom, crlf):
    from ppamsafety.impact.head import head_model
    from ppamsafety.params.arm_file import arm_to_toml
    text = {"arm": arm_to_toml(ARM), "head": head_model().to_toml(),
            "study": '[case]\nexperiment = "step"\n'}[kind]
    raw = text.replace("\n", "\r\n" if crlf else "\n").encode()
    f = tmp_path_factory.mktemp("bom") / "x.toml"
    f.write_bytes((b"\xef\xbb\xbf" if bom else b"") + raw)
    got = _readers()[kind](f)
    plain = tmp_path_factory.mktemp("plain") / "x.toml"
    plain.write_text(text)
    want = _readers()[kind](plain)
    if kind == "study":
        assert list(got.cases) == list(want.cases)
    elif kind == "arm":
        assert arm_to_toml(got) == arm_to_toml(want)
    else:
        assert got.to_toml() == want.to_toml()


MANIFEST = ('profile = "profile.toml"\nexperiment = "tensile"\n[actuator]\ntype = "cylinder"\n'
            'bore = "25.7 mm"\n[[records]]\nfile = "r1.csv.xz"\n')
manifest_edits = st.sampled_from([
    ("records", "5"), ("records", "[]"), ("records", '["r1.csv.xz"]'), ("name", "5"),
    ("description", "[1]"), ("experiment", "3"), ("profile", "5"), ("profile", '""'),
    ("profile", '"nope.toml"'), ("actuator", '"cylinder"'), ("source", "true"),
    ("records[0].file", "5"), ("records[0].file", '""'), ("records[0].file", '"nope.csv"'),
    ("records[0].format", '"Raw"'), ("records[0].label", "1"), ("records[0].run", "1.5"),
    ("records[0].run", "true"), ("records[0].pressure_nominal", '"3 parsecs"'),
    ("records[0].pressure_nominal", "-1e300"), ("records[0].bore", "1"), ("pressure", "1")])


@FEW
@given(edit=manifest_edits)
def test_campaign_manifest_keys_are_checked_naming_the_key(tmp_path_factory, edit):
    import shutil
    from ppamsafety.data.campaign import load_campaign
    key, value = edit
    d = tmp_path_factory.mktemp("camp")
    src = ROOT / "ppamsafety" / "data" / "datasets" / "zillen2021"
    shutil.copy(src / "profile.toml", d / "profile.toml")
    shutil.copy(src / "O-ring257_1bar.csv.xz", d / "r1.csv.xz")
    top, _, sub = key.partition("].")
    if sub:                                   # a key of the first record
        text = MANIFEST.replace('file = "r1.csv.xz"\n', "") + (
            f"{sub} = {value}\n" if sub == "file" else f'file = "r1.csv.xz"\n{sub} = {value}\n')
    else:
        lines = [ln for ln in MANIFEST.splitlines() if not ln.startswith(f"{key} =")]
        if key == "records":
            lines = [ln for ln in lines if ln not in ("[[records]]", 'file = "r1.csv.xz"')]
        if key == "actuator":
            lines = [ln for ln in lines if ln not in ("[actuator]", 'type = "cylinder"',
                                                      'bore = "25.7 mm"')]
        text = f"{key} = {value}\n" + "\n".join(lines) + "\n"
    (d / "m.toml").write_text(text)
    with pytest.raises(MeasuredDataError) as e:
        load_campaign(d / "m.toml")
    leaf = key.split(".")[-1]
    assert "m.toml" in str(e.value) and _names(str(e.value), leaf, key), str(e.value)


# ---- class: a single-valued command-line option given twice -------------------------------------

DUPLICABLE = [(["impact", "--q", "30", "-80", "--qd", "1", "0"],
               [("--dt", "1e-5"), ("--q", "40 -80"), ("--head", "child-frontal"),
                ("--stiffness", "1 2"), ("--history", "h.csv"), ("--arm", "a.toml")]),
              (["synthesize", "--out", "x.csv"],
               [("--seed", "3"), ("--duration", "2"), ("--noise", "none"), ("--out", "y.csv"),
                ("--experiment", "closed-loop"), ("--kind", "arm")]),
              (["diagnose", "d.csv", "--out", "o"],
               [("--seed", "3"), ("--block", "0.1"), ("--alpha", "0.05"), ("--out", "p")]),
              (["identify", "d.csv", "--kind", "static", "--out", "o"],
               [("--kind", "dynamic"), ("--method", "WLS"), ("--drop", "3"), ("--out", "p")]),
              (["sweep", "s.toml", "--out", "o"],
               [("--processes", "1"), ("--max-cases", "3"), ("--backend", "local"),
                ("--out", "p")]),
              (["report"], [("--outdir", "r"), ("--processes", "1"), ("--only", "design")]),
              (["arm", "check", "a.toml"], [("--q", "50 -80")]),
              (["arm", "export"], [("--out", "a.toml")])]


@FEW
@given(cmd=st.sampled_from(DUPLICABLE), data=st.data(), same=st.booleans())
def test_an_option_given_twice_is_refused_naming_it(cmd, data, same):
    argv, opts = cmd
    opt, value = data.draw(st.sampled_from(opts))
    first = value.split()
    second = first if same else first  # the same value twice is refused too
    with _captured() as (err,):
        with pytest.raises(SystemExit) as e:
            build_parser().parse_args([*argv, opt, *first, opt, *second])
    assert e.value.code == 2
    assert f"argument {opt}" in err.text() and "given twice" in err.text(), err.text()


# ---- class: a single output file named like a folder --------------------------------------------

@FEW
@given(name=st.sampled_from(["x.csv", "h", "sub/x.csv", "a.toml"]),
       how=st.sampled_from([lambda s: s + "/", lambda s: s + "//", lambda s: ".",
                            lambda s: "..", lambda s: s + "/.", lambda s: s + "/.."]))
def test_a_single_file_named_like_a_folder_is_refused(tmp_path_factory, name, how):
    from ppamsafety.output import atomic_write, check_new_file
    d = tmp_path_factory.mktemp("f")
    (d / "sub").mkdir()
    before = sorted(p.name for p in d.rglob("*"))
    target = f"{d}/{how(name)}"                # as typed: pathlib would drop a trailing '/'
    with pytest.raises(OutputError) as e:
        check_new_file(target, name="--out")
    assert "--out" in str(e.value) and "folder" in str(e.value), str(e.value)
    with pytest.raises(OutputError):
        atomic_write(target, lambda t: Path(t).write_text("x"), overwrite=True, name="--out")
    assert sorted(p.name for p in d.rglob("*")) == before


# ---- class: requests sized before anything is allocated -----------------------------------------

@FEW
@given(n=st.integers(2 * 10 ** 6 + 1, 10 ** 9), what=st.sampled_from(["q", "qd", "stiffness"]))
def test_impact_batches_are_sized_before_allocating(n, what):
    import tracemalloc
    from ppamsafety.impact import simulate_impacts
    from ppamsafety.impact.model import BYTES_PER_CASE
    from ppamsafety._validation import MAX_BYTES
    args = {"q": np.radians([50.0, -80.0]), "qd": [1.0, 0.0], "stiffness": [43.0, 27.0]}
    args[what] = np.broadcast_to(np.asarray(args[what], float), (n, 2))
    tracemalloc.start()
    try:
        if n * BYTES_PER_CASE > MAX_BYTES:
            with pytest.raises(ValueError, match=rf"{n:,} impact cases .* GB"):
                simulate_impacts(ARM, args["q"], args["qd"], args["stiffness"])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 50 * 2 ** 20                 # nothing of the request's size was allocated


@FEW
@given(rows=st.integers(1, 10 ** 4), samples=st.integers(1, 10 ** 9))
def test_simulations_are_sized_before_allocating(rows, samples):
    from ppamsafety.plant.model import SIM_BYTES_PER_SAMPLE, simulate
    from ppamsafety._validation import MAX_BYTES
    assume(rows * samples * SIM_BYTES_PER_SAMPLE > MAX_BYTES)
    U = np.broadcast_to(np.full(4, 1e5), (rows, samples, 4) if rows > 1 else (samples, 4))
    with pytest.raises(ValueError, match=r"samples would need about .* GB"):
        simulate(ARM, np.array([0.8, -1.4, 0, 0, 1e5, 1e5, 1e5, 1e5]), U)


# ---- class: envelope ranges (both ends are cases that must be allowed) --------------------------

ENVELOPE_PARAMS = [("speed", {}, [0.0, 0.05, 1.0, 9.9, 10.0, 11.0, 1e3]),
                   ("lam", {"controller": "PSMC joint"}, [0.0, 0.1, 50.0, 100.0, 150.0, 1e300]),
                   ("duration", {}, [0.5, 2.0, 3.0, 1800.0, 1e6]),
                   ("arm.pneumatics.mean_pressure", {}, [-1e5, 0.0, 1.5e5, 3e5, 3.1e5, 1e7])]


@FEW
@given(spec=st.sampled_from(ENVELOPE_PARAMS), data=st.data())
def test_envelope_ranges_are_checked_at_both_ends_before_running(spec, data):
    from ppamsafety.envelope import check_bounds
    from ppamsafety.sweep_cases import check_impact_case
    par, case, values = spec
    lo, hi = sorted(data.draw(st.lists(st.sampled_from(values), min_size=2, max_size=2,
                                       unique=True)))

    def allowed(v):
        try:
            if par == "speed":
                check_impact_case(v, **case)
            else:
                check_case(**case, **{par: v})
        except (TypeError, ValueError):
            return False
        return True

    ok = [allowed(lo), allowed(hi)]
    if all(ok):
        check_bounds(par, (lo, hi), case)
    else:
        with pytest.raises(ValueError) as e:
            check_bounds(par, (lo, hi), case)
        assert f"bounds[{ok.index(False)}]" in str(e.value) and par in str(e.value)
    text = (f'[envelope]\nparameter = "{par}"\nrange = [{lo!r}, {hi!r}]\n' +
            "".join(f'[case]\n{k} = "{v}"\n' for k, v in case.items()))
    if all(ok):
        parse_study(text, where="s.toml")
    else:
        with pytest.raises(StudyFileError, match=r"s.toml: envelope\.(range|parameter)"):
            parse_study(text, where="s.toml")


# ---- class: seeds of every public function that draws -------------------------------------------

SEEDED = {
    "synthesize": lambda s: __import__("ppamsafety.diagnose", fromlist=["x"]).synthesize(
        "open-loop", duration=0.5, seed=s),
    "synthetic_static": lambda s: __import__("ppamsafety.data", fromlist=["x"]).synthetic_static(
        n=3, seed=s),
    "equilibrium_configurations": lambda s: __import__(
        "ppamsafety.identify.static", fromlist=["x"]).equilibrium_configurations(ARM, 3, seed=s),
    "default_excitation": lambda s: __import__(
        "ppamsafety.data.synthetic", fromlist=["x"]).default_excitation(ARM, seed=s)}


@FEW
@given(fn=st.sampled_from(sorted(SEEDED)),
       seed=st.one_of(st.sampled_from([-1, 2 ** 63, 2 ** 64, 1.5, "1", None, True, np.int64(-3),
                                       np.array(2 ** 62), 0, 2 ** 63 - 1]),
                      st.integers(-2 ** 70, 2 ** 70)))
def test_every_seed_is_an_integer_in_0_to_2_63(fn, seed):
    valid = (not isinstance(seed, (bool, str, float, type(None))) and
             0 <= int(seed) <= 2 ** 63 - 1)
    if valid:
        if fn == "synthesize":
            assume(False)                     # a simulation: covered by the battery's -0d case
        SEEDED[fn](seed)
    else:
        with pytest.raises((TypeError, ValueError), match="seed"):
            SEEDED[fn](seed)


# ---- class: a sweep cache folder that holds the user's files ------------------------------------

@FEW
@given(names=st.lists(st.sampled_from(["notes.txt", "z" * 20 + ".pkl", "0123456789abcdef0123.pkl",
                                       "0123456789abcdef0123.0badc0de.tmp", "data.csv",
                                       ".hidden", "sub/"]), max_size=3, unique=True))
def test_a_cache_folder_of_user_files_is_refused_and_left_alone(tmp_path_factory, names):
    d = tmp_path_factory.mktemp("cache")
    for n in names:
        if n.endswith("/"):
            (d / n).mkdir()
        else:
            (d / n).write_text("mine")
    before = sorted(p.name for p in d.iterdir())
    user = [n for n in names if not (n.startswith("0123456789abcdef0123"))]
    if user:
        with pytest.raises(ValueError, match="cache_dir = .* not sweep cache files"):
            run_sweep(_square, [{"x": 2}], cache_dir=d, progress=False)
        assert sorted(p.name for p in d.iterdir()) == before
    else:
        assert run_sweep(_square, [{"x": 2}], cache_dir=d, progress=False)["sq"].tolist() == [4]


# ---- class: Ctrl-C ------------------------------------------------------------------------------

def test_ctrl_c_stops_a_sweep_at_once_with_exit_130(tmp_path):
    import signal
    s = tmp_path / "s.toml"
    s.write_text('[case]\nexperiment = "circle10"\n[grid]\n'
                 'duration = { linspace = [60.0, 90.0, 40] }\n')
    p = subprocess.Popen([sys.executable, "-m", "ppamsafety.cli", "sweep", str(s), "--out",
                          str(tmp_path / "o"), "--processes", "2", "--no-progress"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path,
                         env={**os.environ, "PYTHONPATH": str(ROOT)},
                         preexec_fn=lambda: (signal.signal(signal.SIGINT, signal.SIG_DFL),
                                             os.setpgid(0, 0)))
    cache = tmp_path / "o" / "cache"
    try:
        for line in iter(p.stdout.readline, b""):      # the sweep has started its cases
            if b"study " in line:
                break
        deadline = time.monotonic() + 300            # a first case finished (kernels may
        while not (cache.is_dir() and any(cache.glob("*.pkl"))):   # compile first)
            assert p.poll() is None, "the sweep ended before it could be interrupted"
            assert time.monotonic() < deadline, "no case finished within 300 s"
            time.sleep(0.05)
        first = len(list(cache.glob("*.pkl")))
        assert p.poll() is None, "the sweep ended before it could be interrupted"
        os.killpg(p.pid, signal.SIGINT)
        _, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
    assert p.returncode == 130 and b"ppamsafety: interrupted" in err, err[-2000:]
    assert b"Traceback" not in err
    # stopped at once: the queued cases did not run (40 cases of 60-90 s of simulation each;
    # at most the two running when Ctrl-C came could have finished besides the first ones)
    done = len(list(cache.glob("*.pkl"))) if cache.is_dir() else 0
    assert first <= done <= first + 2, (first, done)
    assert read_marker(tmp_path / "o")["kind"] == "sweep"        # resumable


# ---- the command-line battery ------------------------------------------------------------------

#: A seeded subset of the battery for the default suite: one case of each class that needs no
#: simulation (the whole battery runs under `slow`).
SUBSET = ["synth-effect:payload_mass=inf", "synth-effect:payload_mass=abc",
          "synth-effect:valve_dead_time-wrong-length-3", "diagnose-option:seed--1",
          "diagnose-option:block-1e9", "output-folder:diagnose-empty-path",
          "output-folder:sweep-other-kind-overwrite", "study-file:grid-1e8-cases",
          "study-file:grid-1e9-points", "study-file:empty-file", "study-file:case-duration-1.0",
          "data-file:col-p-below-vacuum-diagnose", "data-file:col-q-degrees-identify",
          "impact-domain:qd-392ms-tool-speed", "impact-domain:qd-fast-but-possible",
          "api-hic:masked-array", "api-hic:empty-batch", "api-sweep:cache-dir-empty",
          "api-experiment:circle-1e5s", "api-experiment:step-duration-1",
          "campaign-file:record-file-number", "campaign-file:huge-record",
          "input-file:study-fifo", "input-file:arm-check-binary",
          "input-file-valid:study-bom-crlf", "cli-duplicate:synth-seed",
          "output-file:synth-slash", "study-envelope:lam-high-end",
          "api-size:impacts-1e8-cases", "api-path:load_arm-empty", "api-seed:synthesize-2**64"]
#: (Ctrl-C has its own test below; the xz bomb and the interrupts run in the whole battery.)


def _battery(args, tmp_path):
    out = tmp_path / "battery.json"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    r = subprocess.run([sys.executable, str(ROOT / "tests" / "bad_input_battery.py"), *args,
                        "--workdir", str(tmp_path / "w"), "--json", str(out)],
                       capture_output=True, text=True, env=env, cwd=ROOT, timeout=3600 * 3)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    return json.loads(out.read_text()), r.stdout


def test_battery_subset(tmp_path):
    res, log = _battery(["--names", ",".join(SUBSET)], tmp_path)
    assert len(res) == len(SUBSET)
    bad = [r for r in res if r["verdict"] != "clear"]
    assert not bad, log[-4000:]


@pytest.mark.slow
def test_whole_battery(tmp_path):
    """>= 99 % clear errors; no hang, exit 1, traceback or lost file; refused requests below
    1 GB of peak memory (the targets of issue 22)."""
    res, log = _battery([], tmp_path)
    inval = [r for r in res if r["expect"] == "error"]
    clear = sum(r["verdict"] == "clear" for r in inval)
    assert clear >= 0.99 * len(inval), log[-6000:]
    for v in ("hang", "exit1", "traceback", "lost", "memory"):
        assert not [r for r in res if r["verdict"] == v], (v, log[-6000:])
    assert not [r for r in res if r["expect"] != "error" and r["verdict"] != "clear"], log[-6000:]
    assert max(r["peak_mb"] for r in res if r["refused"]) < 1024


# ---- helpers ------------------------------------------------------------------------------------

class _Text:
    def __init__(self):
        self.parts = []

    def write(self, s):
        self.parts.append(s)

    def flush(self):
        pass

    def text(self):
        return "".join(self.parts)


class _captured:
    """Capture stderr of an in-process CLI run."""

    def __enter__(self):
        self.err, self.old = _Text(), sys.stderr
        self.out_old = sys.stdout
        sys.stderr = self.err
        sys.stdout = _Text()
        return (self.err,)

    def __exit__(self, *a):
        sys.stderr, sys.stdout = self.old, self.out_old
        return False
