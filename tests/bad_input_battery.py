"""A battery of invalid input for every subcommand and the public entry points (issue 22).

Each *case* is one invalid (or odd but valid) input of one *input class*: a command line of
``ppamsafety`` with the files it needs (measured-data files, study files, output folders
holding user or toolkit files), or one call of a public function.  Every case runs in its own
child process (forked from a parent that imported the package once, or with ``--real`` as a
fresh ``python -m ppamsafety.cli`` process) with a time limit, and is classified:

clear
    Command line: exit status 2, no traceback, the ``ppamsafety: error: ...`` line (or
    argparse's usage error) names one of the case's expected words (the option, key, column
    or argument).  Python: a ``ValueError``/``TypeError`` naming one of them.  For a case that
    expects a *warning*: exit 0 and a one-line ``ppamsafety: warning: ...`` naming it, with no
    raw Python warning (``UserWarning`` and its source line).  For a case that is valid (odd
    but legal input): exit 0.
vague
    Exit 2 (or a ValueError/TypeError) whose message does not name what was wrong.
exit1 / traceback / accepted / hang / memory / lost / noisy
    Exit status 1 ("internal failure"), a Python traceback, invalid input accepted (exit 0),
    no answer within the time limit, more than :data:`MEMORY_KILL` of resident memory, a user
    file changed or deleted, or a raw Python warning printed beside the error.

A case that expects an *interrupt* gets Ctrl-C (SIGINT to its process group, as a terminal
sends it) after ``interrupt`` seconds, or as soon as its stderr shows ``interrupt_on`` (a line
the command prints once its work has started, on an input long enough that the work cannot
end in the moment between that line and the signal: no dependence on how fast the work is),
and is clear when it exits 130 with ``ppamsafety: interrupted`` having spent at most
:data:`INTERRUPT_GRACE` seconds of CPU after it (else "hang"; "not-interrupted" if it finished
first).

The classes of the first pass (``synth-effect``, ``data-file``, ``study-file``,
``output-folder`` ...) were joined in the second pass by ``campaign-file`` (bench campaign
manifests), ``input-file`` (arm, head and study files as files: binary, folders, pipes,
devices, dangling links, oversized), ``cli-duplicate`` (an option given twice),
``study-envelope``, ``interrupt`` (Ctrl-C), and the ``api-*`` classes of the public
functions (sizes estimated before allocating, paths, seeds, sections, identification and
diagnosis options that change nothing); ``*-valid`` classes hold odd but valid input (BOM,
CRLF) that must work.

The peak resident memory of every case is measured (``wait4``); the report gives the share of
clear results per class, the failures, and the largest peak memory of a refused request.

Usage (from the repository root)::

    PYTHONPATH=$PWD PPAMSAFETY_CACHE_DIR=/tmp/x-cache python tests/bad_input_battery.py
    ... --only CLASS[,CLASS]   --real   --json out.json   --list   --show NAME

``tests/test_bad_input.py`` runs a seeded subset in the default suite and the whole battery
behind ``@pytest.mark.slow``.
"""

from __future__ import annotations

import argparse
import hashlib
import io
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
#: Seconds a case may take before it counts as a hang.
TIMEOUT = 90.0
#: Resident memory at which a case is killed (and counted as "memory") [bytes].
MEMORY_KILL = 3 * 2 ** 30
#: A refused request must stay below this peak resident memory [bytes] (issue 22 target).
MEMORY_TARGET = 2 ** 30
NOBODY = 65534


@dataclass
class Case:
    """One input of the battery (see the module docstring)."""

    cls: str
    name: str
    argv: list | None = None            # command line ({d}: the case folder)
    api: object = None                  # callable run in the child (Python entry point)
    setup: object = None                # setup(d: Path) writes the input files
    names: tuple = ()                   # the message must name one of these (case-insensitive)
    expect: str = "error"               # "error", "warn" (exit 0 + one-line warning), "ok",
    #                                     "interrupt" (Ctrl-C: exit 130 at once)
    unprivileged: bool = False          # run as user nobody (read-only targets)
    timeout: float = TIMEOUT
    interrupt: float | None = None      # send Ctrl-C (SIGINT to the process group) after this [s]
    interrupt_on: str | None = None     # ... or once the command's stderr shows this text


CASES: list[Case] = []


def case(cls, name, argv=None, *, names=(), **kw):
    CASES.append(Case(cls, name, argv=argv, names=tuple(names), **kw))


def api(cls, name, call, *, names=(), **kw):
    CASES.append(Case(cls, name, api=call, names=tuple(names), **kw))


# ------------------------------------------------------------------------------ base files

BASE: Path | None = None          # folder of the valid baseline files (made once)


def make_base(folder: Path) -> None:
    """Valid records and a valid study file that the cases mutate."""
    from ppamsafety.data import synthetic_static
    from ppamsafety.diagnose import synthesize

    folder.mkdir(parents=True, exist_ok=True)
    if not (folder / "ol.csv").exists():
        synthesize("open-loop", duration=1.0, seed=1).save(folder / "ol.csv")
    if not (folder / "cl.csv").exists():
        synthesize("closed-loop", duration=3.0, seed=1, reference="step",
                   controller="PID").save(folder / "cl.csv")
    if not (folder / "st.csv").exists():
        synthetic_static().save(folder / "st.csv")
    if not (folder / "ol_long.csv").exists():
        # a record whose diagnosis takes far longer than the moment between the line that
        # starts it and Ctrl-C (the interrupt of diagnose), with a metadata key the loader
        # only notes: that note is the line
        synthesize("open-loop", duration=10.0, seed=2).save(folder / "ol_long.csv")
        m, df = _split(folder / "ol_long.csv")
        m["interrupt_marker"] = "the diagnosis starts after this note"
        write_record(folder / "ol_long.csv", m, df)
    if not (folder / "ten.csv").exists():
        synthesize(kind="actuator", seed=1, cycles=1).save(folder / "ten.csv")
    (folder / "study.toml").write_text('[case]\nexperiment = "step"\ncontroller = "PID"\n'
                                       'duration = 3.0\n')


def _split(path: Path):
    """(meta dict, header line count, DataFrame) of a record written with a header block."""
    from ppamsafety.data.measured import _read_meta
    meta, n = _read_meta(path, "csv")
    return meta, pd.read_csv(path, skiprows=n)


def write_record(path: Path, meta: dict | None, df: pd.DataFrame | None = None, *,
                 header_text: str | None = None, body: str | None = None) -> None:
    from ppamsafety.data.measured import dumps_toml
    head = ""
    if header_text is not None:
        head = "".join("# " + ln + "\n" for ln in header_text.splitlines())
    elif meta is not None:
        head = "".join(("# " + ln).rstrip() + "\n" for ln in dumps_toml(meta).splitlines())
    if body is None:
        body = df.to_csv(index=False, lineterminator="\n")
    path.write_text(head + body, encoding="utf-8")


def record(base: str, meta=None, frame=None, *, to="data.csv", header_text=None, body=None):
    """A setup writing ``to`` from the baseline record ``base`` (ol, cl, st, ten) mutated by
    ``meta(m)`` / ``frame(df)`` (functions changing them in place or returning new ones)."""
    def setup(d: Path):
        m, df = _split(BASE / f"{base}.csv")
        if meta is not None:
            m = meta(m) or m
        if frame is not None:
            r = frame(df)
            df = r if r is not None else df
        write_record(d / to, m, df, header_text=header_text, body=body)
    return setup


def _set(col, fn):
    def f(df):
        df[col] = fn(df[col]) if callable(fn) else fn
        return df
    return f


def _meta_set(**kv):
    def f(m):
        for k, v in kv.items():
            if v is _DEL:
                m.pop(k, None)
            else:
                m[k] = v
        return m
    return f


_DEL = object()


def files(**content):
    """A setup writing text (str) or bytes files, and folders for values ``None``."""
    def setup(d: Path):
        for name, c in content.items():
            p = d / name.replace("__", "/")
            p.parent.mkdir(parents=True, exist_ok=True)
            if c is None:
                p.mkdir(exist_ok=True)
            elif isinstance(c, bytes):
                p.write_bytes(c)
            else:
                p.write_text(c, encoding="utf-8")
    return setup


def chain(*setups):
    def setup(d):
        for s in setups:
            if s is not None:
                s(d)
    return setup


def marked_folder(name, kind, files_=("result.csv",)):
    """A previous ppamsafety output folder of ``kind`` (marker and its files)."""
    def setup(d: Path):
        f = d / name
        f.mkdir(parents=True, exist_ok=True)
        for x in files_:
            (f / x).write_text(f"{kind} output {x}\n")
        (f / ".ppamsafety-output").write_text(json.dumps(
            {"tool": "ppamsafety", "version": "0", "kind": kind, "files": list(files_)}))
    return setup


def foreign_folder(name):
    return files(**{f"{name}__thesis.tex": "years of work\n"})


def readonly_folder(name):
    """A folder nothing can be written into, not even by root (``chattr +i``; as a user,
    ``chmod 555`` does the same)."""
    def setup(d: Path):
        f = d / name
        f.mkdir(exist_ok=True)
        os.chmod(f, 0o555)
        if os.geteuid() == 0:
            subprocess.run(["chattr", "+i", str(f)], check=True)
    return setup


def copy_base(src, to=None):
    def setup(d: Path):
        shutil.copy(BASE / src, d / (to or src))
    return setup


# ------------------------------------------------------------------------------ the cases
# Shorthands of valid command lines the cases mutate.

IMPACT = ["impact", "--q", "30", "-80", "--qd", "1", "0"]
DIAG = ["diagnose", "data.csv", "--out", "o"]
IDENT_D = ["identify", "data.csv", "--kind", "dynamic", "--out", "o"]
IDENT_S = ["identify", "data.csv", "--kind", "static", "--out", "o"]
SYN = ["synthesize", "--out", "x.csv", "--duration", "1"]
SYN_A = ["synthesize", "--kind", "actuator", "--out", "x.csv"]
SWEEP = ["sweep", "s.toml", "--out", "o"]
REPORT = ["report", "--quick", "--only", "design"]


def _cli_cases():
    # ---- top level -------------------------------------------------------------------
    case("cli", "no-subcommand", [], names=["command", "required", "usage"])
    case("cli", "unknown-subcommand", ["simulate"], names=["simulate", "invalid choice"])
    case("cli", "mis-cased-subcommand", ["Impact"], names=["Impact", "invalid choice"])
    case("cli", "info-extra-argument", ["info", "extra"], names=["extra", "unrecognized"])
    case("cli", "unknown-option", IMPACT + ["--speed", "2"], names=["--speed"])
    case("cli", "option-abbrev-ambiguous", ["sweep", "s.toml", "--o", "x"],
         names=["--o", "ambiguous", "--out", "required"])

    # ---- impact: numbers ---------------------------------------------------------------
    for v in ("nan", "inf", "-inf", "1e400", "abc", "", "1,5", "0x10", "30deg"):
        case("impact-number", f"q-{v or 'empty'}", ["impact", "--q", v, "-80", "--qd", "1", "0"],
             names=["--q", "Q1"])
        case("impact-number", f"qd-{v or 'empty'}", ["impact", "--q", "30", "-80", "--qd", v,
                                                     "0"], names=["--qd", "QD1"])
    for v in ("400", "-400", "1e5"):
        case("impact-number", f"q-{v}", ["impact", "--q", v, "-80", "--qd", "1", "0"],
             names=["--q", "Q1", "360"])
    case("impact-number", "q-one-value", ["impact", "--q", "30", "--qd", "1", "0"],
         names=["--q"])
    case("impact-number", "q-three-values", ["impact", "--q", "30", "-80", "10", "--qd", "1",
                                             "0"], names=["10", "unrecognized", "--q"])
    case("impact-number", "q-outside-working-area", ["impact", "--q", "200", "-80", "--qd",
                                                     "1", "0"], names=["q", "working area"],
         expect="warn")
    for v in ("-1", "nan", "inf", "1e300", "abc"):
        case("impact-number", f"stiffness-{v}", IMPACT + ["--stiffness", v, "27"],
             names=["--stiffness", "stiffness", "K1"])
    case("impact-number", "stiffness-unresolvable", IMPACT + ["--stiffness", "1e9", "1e9"],
         names=["stiffness", "--dt"])
    for v in ("0", "-1", "1e-300", "1e300", "nan", "0.5", "abc"):
        case("impact-number", f"dt-{v}", IMPACT + ["--dt", v], names=["--dt", "dt"])
    # ---- impact: physics -------------------------------------------------------------------
    case("impact-domain", "qd-392ms-tool-speed", ["impact", "--q", "30", "-80", "--qd", "500",
                                                  "0"], names=["qd", "tool speed", "m/s"])
    case("impact-domain", "qd-1e3", ["impact", "--q", "30", "-80", "--qd", "1000", "0"],
         names=["qd", "tool speed"])
    case("impact-domain", "qd-1e4", ["impact", "--q", "30", "-80", "--qd", "1e4", "0"],
         names=["qd", "tool speed"])
    case("impact-domain", "qd-deg-per-s", ["impact", "--q", "30", "-80", "--qd", "90", "-45"],
         names=["qd", "tool speed", "deg/s"])
    case("impact-domain", "qd-fast-but-possible", ["impact", "--q", "30", "-80", "--qd", "25",
                                                   "0"], names=["tool speed", "plausible"],
         expect="warn")
    case("impact-domain", "qd-negative-away", ["impact", "--q", "30", "-80", "--qd", "-1", "0"],
         names=[], expect="ok")
    case("impact-domain", "zero-speed", ["impact", "--q", "30", "-80", "--qd", "0", "0"],
         names=["speed", "qd", "moving", "zero"])
    # ---- impact: choices ---------------------------------------------------------------------
    for v in ("dummy", "", "Thesis-Frontal", "THESIS-FRONTAL", " thesis-frontal"):
        case("choice", f"impact-head-{v.strip() or 'empty'}{'-space' if v.startswith(' ') else ''}",
             IMPACT + ["--head", v], names=["--head", "head", "thesis-frontal"],
             expect="error")
    for v in ("elbo", "", "Tool Point", "gripper"):
        case("choice", f"impact-contact-{v.replace(' ', '-') or 'empty'}",
             IMPACT + ["--contact", v], names=["--contact", "tool point", "elbow"],
             expect="error")
    for v in ("foam", "", "Bare Metal"):
        case("choice", f"impact-covering-{v.replace(' ', '-') or 'empty'}",
             IMPACT + ["--covering", v], names=["--covering", "bare metal", "thesis-implied"],
             expect="error")
    case("input-file", "impact-covering-missing", IMPACT + ["--covering", "c.toml"],
         names=["--covering", "c.toml", "does not exist"])
    case("input-file", "impact-covering-region-file", IMPACT + ["--covering", "c.toml"],
         setup=files(**{"c.toml": 'format = "ppamsafety-region/1"\nname = "x"\n'}),
         names=["--covering", "format", "ppamsafety-covering/1"])
    case("input-file", "impact-covering-bad-unit", IMPACT + ["--covering", "c.toml"],
         setup=files(**{"c.toml": 'format = "ppamsafety-covering/1"\nname = "x"\n[[layer]]\n'
                                  'name = "a"\nlaw = "thin-layer"\n'
                                  'modulus = { value = 1, unit = "MPa" }\n'
                                  'thickness = { value = 5, unit = "parsec" }\n'}),
         names=["--covering", "thickness.unit", "parsec"])
    case("input-file", "impact-contact-no-radius", IMPACT + ["--contact", "p.toml"],
         setup=files(**{"p.toml": 'format = "ppamsafety-contact/1"\nname = "x"\nlink = 2\n'
                                  'position = { value = 0.1, unit = "m" }\nshape = "edge"\n'}),
         names=["--contact", "radius"])
    case("impact-domain", "contact-elbow-at-rest", ["impact", "--q", "30", "-80", "--qd", "0",
                                                     "1", "--contact", "elbow"],
         names=["elbow", "does not move"])
    # ---- output files (impact --history) ---------------------------------------------------
    case("output-file", "history-empty", IMPACT + ["--history", ""], names=["--history"])
    case("output-file", "history-existing", IMPACT + ["--history", "h.csv"],
         setup=files(**{"h.csv": "mine\n"}), names=["--history", "h.csv", "exists"])
    case("output-file", "history-folder", IMPACT + ["--history", "dir"],
         setup=files(dir=None), names=["--history", "dir", "folder"])
    case("output-file", "history-missing-parent", IMPACT + ["--history", "no/such/h.csv"],
         names=["--history", "no/such"])
    case("output-file", "history-under-a-file", IMPACT + ["--history", "f.txt/h.csv"],
         setup=files(**{"f.txt": "mine\n"}), names=["--history", "f.txt"])
    case("output-file", "history-readonly-folder", IMPACT + ["--history", "ro/h.csv"],
         setup=readonly_folder("ro"), names=["--history", "ro", "permission", "read-only"])
    case("output-file", "history-overwrite-folder", IMPACT + ["--history", "dir",
                                                              "--overwrite"],
         setup=files(dir=None), names=["--history", "dir", "folder"])

    # ---- diagnose / identify options -------------------------------------------------------
    ol = copy_base("ol.csv", "data.csv")
    for opt, vals in (("--seed", ("-1", "1e9", "1.5", "abc", "99999999999999999999999")),
                      ("--block", ("0", "-1", "1e9", "1e-9", "nan", "inf")),
                      ("--bootstrap", ("-1", "1e9", "abc", "1.5")),
                      ("--alpha", ("0", "1", "1.5", "-0.1", "nan")),
                      ("--rho-max", ("0", "0.5", "1e300", "nan"))):
        for v in vals:
            case("diagnose-option", f"{opt[2:]}-{v}", DIAG + [opt, v], setup=ol, names=[opt])
    case("diagnose-option", "experiment-mismatch", DIAG + ["--experiment", "tensile"],
         setup=ol, names=["--experiment", "experiment", "tensile"])
    case("diagnose-option", "experiment-miscased", DIAG + ["--experiment", "Open-Loop"],
         setup=ol, names=["--experiment"])
    for opt, vals in (("--drop", ("-1", "1e9", "abc", "100000000")),
                      ("--confidence", ("0", "1", "1.5", "nan", "-0.5", "95")),
                      ("--sign-velocity", ("0", "-1", "1e300", "nan"))):
        for v in vals:
            case("identify-option", f"{opt[2:]}-{v}", IDENT_D + [opt, v], setup=ol, names=[opt])
    case("identify-option", "kind-miscased", ["identify", "data.csv", "--kind", "Dynamic",
                                              "--out", "o"], setup=ol, names=["--kind"])
    case("identify-option", "method-miscased", IDENT_D + ["--method", "ls"], setup=ol,
         names=["--method"])
    case("identify-option", "kind-mismatch", IDENT_S, setup=ol,
         names=["static", "--kind", "experiment", "open-loop"])

    # ---- output folders ------------------------------------------------------------------
    for cmd, argv, outopt, setup in (
            ("diagnose", ["diagnose", "data.csv"], "--out", ol),
            ("identify", ["identify", "data.csv", "--kind", "dynamic"], "--out", ol),
            ("sweep", ["sweep", "s.toml"], "--out", copy_base("study.toml", "s.toml")),
            ("report", REPORT, "--outdir", None)):
        case("output-folder", f"{cmd}-empty-path", argv + [outopt, ""], setup=setup,
             names=[outopt])
        case("output-folder", f"{cmd}-is-a-file", argv + [outopt, "f.txt"],
             setup=chain(setup, files(**{"f.txt": "mine\n"})), names=[outopt, "f.txt"])
        case("output-folder", f"{cmd}-under-a-file", argv + [outopt, "f.txt/o"],
             setup=chain(setup, files(**{"f.txt": "mine\n"})), names=[outopt, "f.txt"])
        for ow in ((), ("--overwrite",)):
            tag = "-overwrite" if ow else ""
            case("output-folder", f"{cmd}-foreign{tag}", argv + [outopt, "o", *ow],
                 setup=chain(setup, foreign_folder("o")), names=[outopt, "thesis.tex", "'o'"])
            case("output-folder", f"{cmd}-bad-marker{tag}", argv + [outopt, "o", *ow],
                 setup=chain(setup, files(**{"o__.ppamsafety-output": "{not json",
                                             "o__r.csv": "1\n"})),
                 names=[outopt, "marker", "'o'"])
        other = "diagnose" if cmd != "diagnose" else "sweep"
        case("output-folder", f"{cmd}-other-kind", argv + [outopt, "o"],
             setup=chain(setup, marked_folder("o", other)), names=[outopt, other, "'o'"])
        case("output-folder", f"{cmd}-other-kind-overwrite", argv + [outopt, "o", "--overwrite"],
             setup=chain(setup, marked_folder("o", other)), names=[outopt, other])
        case("output-folder", f"{cmd}-readonly", argv + [outopt, "ro"],
             setup=chain(setup, readonly_folder("ro")),
             names=[outopt, "'ro'", "permission", "read-only"])
        case("output-folder", f"{cmd}-readonly-parent", argv + [outopt, "ro/o"],
             setup=chain(setup, readonly_folder("ro")),
             names=[outopt, "'ro", "permission", "read-only"])
    case("output-folder", "sweep-resume-other-kind", SWEEP + ["--resume"],
         setup=chain(copy_base("study.toml", "s.toml"), marked_folder("o", "diagnose")),
         names=["--resume", "'o'", "sweep"])
    case("output-folder", "report-only-empty", ["report", "--only", ","], names=["--only"])
    case("output-folder", "report-only-unknown", ["report", "--only", "nonexistent"],
         names=["nonexistent", "--only", "only"])
    case("output-folder", "report-only-miscased", ["report", "--only", "Design", "--outdir",
                                                   "o"], names=["Design", "only"])
    for v in ("0", "-1", "abc", "1.5", "1e9", "99999"):
        case("output-folder", f"report-processes-{v}", REPORT + ["--processes", v,
                                                                 "--outdir", "o"],
             names=["--processes", "processes"])

    # ---- synthesize --effect -----------------------------------------------------------------
    for v in ("inf", "nan", "-inf", "abc", "", "1e400", "1,,2", ",", "0x1", "1 2"):
        case("synth-effect", f"payload_mass={v or 'empty'}", SYN + ["--effect",
                                                                   f"payload_mass={v}"],
             names=["payload_mass"])
    for name, v in (("valve_dead_time", "1,2,3"), ("valve_time_constant_factor", "1,2"),
                    ("valve_time_constant_factor", "1,2,3,4,5"), ("friction_coulomb", "1,2,3"),
                    ("pressure_sensor_offset", "1,2"), ("valve_offset_delta", "1,2,3"),
                    ("payload_mass", "1,2"), ("polytropic_n", "1.2,1.3"),
                    ("joint_torque_bias", "1,2,3")):
        case("synth-effect", f"{name}-wrong-length-{v.count(',') + 1}",
             SYN + ["--effect", f"{name}={v}"], names=[name])
    for name, v in (("payload_mass", "-1"), ("payload_mass", "1e300"),
                    ("valve_dead_time", "5"), ("valve_dead_time", "-0.1"),
                    ("valve_time_constant_factor", "-1"), ("valve_time_constant_factor", "0"),
                    ("friction_coulomb", "-1"), ("polytropic_n", "0.5"),
                    ("geometry.L1", "-1"), ("geometry.L1", "abc"), ("geometry.L1", "inf"),
                    ("geometry.nonexistent", "1"), ("hysteresis_exact_stages", "1.5"),
                    ("hysteresis_initial", "sideways"), ("hysteresis_delta", "2"),
                    ("valve_gain_factor", "1e300"), ("pressure_sensor_offset", "1e300"),
                    ("valve_offset_delta", "nan"), ("joint_torque_bias", "1e9")):
        case("synth-effect", f"{name}={v}", SYN + ["--effect", f"{name}={v}"], names=[name])
    case("synth-effect", "no-equals", SYN + ["--effect", "payload_mass"],
         names=["--effect", "payload_mass"])
    case("synth-effect", "empty-name", SYN + ["--effect", "=1"], names=["--effect"])
    case("synth-effect", "unknown-name", SYN + ["--effect", "gravity=1"], names=["gravity"])
    case("synth-effect", "miscased-name", SYN + ["--effect", "Payload_Mass=1"],
         names=["Payload_Mass", "payload_mass"])
    case("synth-effect", "given-twice", SYN + ["--effect", "payload_mass=1", "--effect",
                                               "payload_mass=2"], names=["payload_mass", "twice"])
    for name, v in (("friction_coulomb", "inf"), ("friction_coulomb", "abc"),
                    ("force_law_scale", "-1"), ("force_law_scale", "nan"),
                    ("payload_mass", "1"), ("hysteresis_delta", "1,2,3")):
        case("synth-effect", f"actuator-{name}={v}", SYN_A + ["--effect", f"{name}={v}"],
             names=[name])
    # ---- synthesize options --------------------------------------------------------------
    for v in ("0", "-1", "1e9", "1e-9", "nan", "inf", "1e5"):
        case("synth-option", f"duration-{v}", ["synthesize", "--out", "x.csv", "--duration", v],
             names=["--duration", "duration"])
    for v in ("-1", "1.5", "abc", str(2 ** 64), "1e9"):
        case("synth-option", f"seed-{v}", SYN + ["--seed", v], names=["--seed", "seed"])
    case("synth-option", "noise-miscased", SYN + ["--noise", "Table-3.2"], names=["--noise"])
    for v in ("xyz", "pid", "", "PSMC joint Ki=3 λ=0.4"):
        case("synth-option", f"controller-{v or 'empty'}", SYN + ["--experiment", "closed-loop",
                                                                  "--controller", v],
             names=["--controller", "controller"])
    case("synth-option", "experiment-tensile-arm", SYN + ["--experiment", "tensile"],
         names=["--experiment", "experiment", "tensile"])
    case("synth-option", "experiment-closed-actuator", SYN_A + ["--experiment", "closed-loop"],
         names=["--experiment", "experiment", "closed-loop"])
    case("synth-option", "actuator-with-duration", SYN_A + ["--duration", "2"],
         names=["--duration"])
    case("synth-option", "arm-with-cycles", SYN + ["--cycles", "2"], names=["--cycles"])
    for opt, vals in (("--cycles", ("0", "-1", "1e9", "1000000000", "abc")),
                      ("--period", ("0", "-1", "1e9", "1e-9", "nan")),
                      ("--sample-rate", ("0", "1e9", "1e-9", "inf")),
                      ("--jitter", ("-1", "5", "nan", "1e300")),
                      ("--pressures", ("", "a", "-2e5", "1e9", "nan", "1e5,,2e5", ",",
                                       "0")),
                      ("--force-law", ("1,2", "1,1,1,1,1", "nan,0,0,0,0", "0,0,0,0,0",
                                       "a,b,c,d,e", "-1,0.003,0,0,0"))):
        for v in vals:
            case("synth-option", f"actuator{opt}-{v or 'empty'}", SYN_A + [opt, v],
                 names=[opt, opt[2:].replace("-", "_")])
    # ---- synthesize output file ------------------------------------------------------------
    for nm, out, setup, nms in (
            ("empty", "", None, ["--out"]),
            ("existing", "x.csv", files(**{"x.csv": "mine\n"}), ["x.csv", "--out", "exists"]),
            ("folder", "dir", files(dir=None), ["dir", "--out", "folder"]),
            ("missing-parent", "no/such/x.csv", None, ["no/such", "--out"]),
            ("under-a-file", "f.txt/x.csv", files(**{"f.txt": "mine\n"}), ["f.txt", "--out"]),
            ("txt-extension", "x.txt", None, ["x.txt", ".txt", "--out"]),
            ("no-extension", "x", None, ["'x'", "--out", "extension", ".csv"]),
            ("parquet-no-pyarrow", "x.parquet", None, ["pyarrow", "parquet"]),
            ("sidecar-exists", "x.parquet", files(**{"x.toml": "mine\n"}), ["x.toml", "pyarrow"]),
            ("readonly", "ro/x.csv", readonly_folder("ro"), ["--out", "'ro", "permission",
                                                            "read-only"])):
        case("output-file", f"synth-out-{nm}", ["synthesize", "--duration", "1", "--out", out],
             setup=setup, names=nms)
    case("output-file", "history-fifo-overwrite", IMPACT + ["--history", "h.csv", "--overwrite"],
         setup=lambda d: os.mkfifo(d / "h.csv"), names=["--history", "h.csv", "regular file"])
    case("output-file", "history-name-too-long", IMPACT + ["--history", "x" * 300 + ".csv"],
         names=["--history", "too long", "xxxx"])
    case("output-file", "synth-out-symlink-loop", ["synthesize", "--duration", "1", "--out",
                                                   "loop/x.csv"],
         setup=lambda d: os.symlink("loop", d / "loop"), names=["--out", "loop"])
    case("output-folder", "diagnose-out-is-the-data", ["diagnose", "data.csv", "--out",
                                                       "data.csv"],
         setup=ol, names=["--out", "data.csv", "not a folder"])
    case("output-folder", "diagnose-out-dot", ["diagnose", "data.csv", "--out", "."],
         setup=chain(ol, files(**{"notes.txt": "mine\n"})), names=["--out", "'.'", "notes.txt"])
    case("output-folder", "sweep-out-symlink-loop", SWEEP[:2] + ["--out", "loop"],
         setup=chain(copy_base("study.toml", "s.toml"), lambda d: os.symlink("loop", d / "loop")),
         names=["--out", "loop"])
    case("synth-option", "reference-with-open-loop", SYN + ["--reference", "step"],
         names=["--reference", "closed-loop"])
    case("synth-option", "controller-with-sawtooth", SYN + ["--experiment", "static-sawtooth",
                                                            "--controller", "PID"],
         names=["--controller", "closed-loop"])
    case("synth-option", "actuator-huge-record", SYN_A + ["--cycles", "100", "--period", "3600",
                                                          "--sample-rate", "10000"],
         names=["--sample-rate", "--cycles", "GB"])
    case("identify-option", "drop-more-than-record", IDENT_D + ["--drop", "100000"], setup=ol,
         names=["--drop", "drop"])
    case("impact-domain", "q-in-radians", ["impact", "--q", "0.5", "-1.4", "--qd", "1", "0"],
         names=["q", "working area"], expect="warn")
    case("output-file", "synth-overwrite-folder", ["synthesize", "--duration", "1", "--out",
                                                   "dir", "--overwrite"],
         setup=files(dir=None), names=["dir", "folder"])
    case("output-file", "synth-overwrite-marked-folder-file",
         ["synthesize", "--duration", "1", "--out", "o/result.csv", "--overwrite"],
         setup=marked_folder("o", "sweep"), names=["o/result.csv", "ppamsafety", "sweep"])

    # ---- sweep options ---------------------------------------------------------------------
    st = copy_base("study.toml", "s.toml")
    for opt, vals in (("--max-cases", ("0", "-1", "abc", "1e9", "1.5")),
                      ("--processes", ("0", "-1", "abc", "1e9"))):
        for v in vals:
            case("sweep-option", f"{opt[2:]}-{v}", SWEEP + [opt, v], setup=st, names=[opt])
    case("sweep-option", "backend-miscased", SWEEP + ["--backend", "Local"], setup=st,
         names=["--backend"])
    case("sweep-option", "scheduler-without-dask", SWEEP + ["--scheduler", "tcp://x:1"],
         setup=st, names=["--scheduler", "--backend"])
    case("sweep-option", "study-missing", ["sweep", "nope.toml", "--out", "o"],
         names=["nope.toml"])
    case("sweep-option", "study-folder", ["sweep", "dir", "--out", "o"], setup=files(dir=None),
         names=["dir"])
    case("sweep-option", "study-empty-path", ["sweep", "", "--out", "o"],
         names=["study", "''", "STUDY"])
    case("sweep-option", "resume-and-overwrite", SWEEP + ["--resume", "--overwrite"],
         setup=chain(st, marked_folder("o", "sweep")), names=["--resume", "--overwrite"])


# ---- measured-data files -------------------------------------------------------------------

def _data_cases():
    def both(name, setup, names, *, cls="data-file", expect="error", ident=IDENT_D):
        case(cls, f"{name}-diagnose", DIAG, setup=setup, names=names, expect=expect)
        case(cls, f"{name}-identify", ident, setup=setup, names=names, expect=expect)

    both("missing-file", None, ["data.csv", "does not exist"])
    both("folder", files(**{"data.csv": None}), ["data.csv", "not a file"])
    both("empty-file", files(**{"data.csv": ""}), ["data.csv", "metadata", "empty"])
    both("whitespace-file", files(**{"data.csv": "\n  \n\n"}), ["data.csv", "metadata", "empty"])
    both("binary-file", files(**{"data.csv": bytes(range(256)) * 40}), ["data.csv"])
    both("latin1-file", files(**{"data.csv": "# kind = \"arm\"\n# description = \"\xb5\"\n"
                                 .encode("latin-1") + b"t,q1\n0,1\n"}), ["data.csv", "UTF-8"])
    both("no-metadata", record("ol", header_text=""), ["metadata"])
    both("bad-toml", record("ol", header_text='kind = "arm\nexperiment = "open-loop"'),
         ["TOML", "metadata"])
    both("txt-extension", chain(record("ol"), lambda d: (d / "data.csv").rename(d / "data.txt")),
         ["data.txt", ".txt", "CSV"])
    case("data-file", "xlsx-extension", ["diagnose", "data.xlsx", "--out", "o"],
         setup=files(**{"data.xlsx": b"PK\x03\x04junk"}), names=["data.xlsx", ".xlsx"])
    case("data-file", "parquet-no-pyarrow", ["diagnose", "data.parquet", "--out", "o"],
         setup=files(**{"data.parquet": b"PAR1junk"}), names=["pyarrow", "parquet"])
    case("data-file", "fifo", ["diagnose", "data.csv", "--out", "o"],
         setup=lambda d: os.mkfifo(d / "data.csv"), names=["data.csv", "not a file"])
    case("data-file", "dev-zero-link", ["diagnose", "data.csv", "--out", "o"],
         setup=lambda d: os.symlink("/dev/zero", d / "data.csv"), names=["data.csv", "not a file"])
    case("data-file", "empty-path", ["diagnose", "", "--out", "o"], names=["DATA", "''", "data"])
    both("sidecar-and-header", chain(record("ol"), files(**{
        "data.toml": 'kind = "arm"\nexperiment = "open-loop"\n'})), ["twice", "data.toml"])
    both("sidecar-bad-toml", chain(record("ol", header_text=""), files(**{
        "data.toml": 'kind = \n'})), ["data.toml", "TOML"])
    # metadata values
    for nm, kv, nms in (
            ("kind-missing", {"kind": _DEL}, ["kind"]),
            ("kind-miscased", {"kind": "Arm"}, ["kind", "'Arm'"]),
            ("kind-unknown", {"kind": "robot"}, ["kind", "robot"]),
            ("kind-number", {"kind": 1}, ["kind"]),
            ("kind-list", {"kind": ["arm"]}, ["kind"]),
            ("experiment-miscased", {"experiment": "Open-Loop"}, ["experiment"]),
            ("experiment-unknown", {"experiment": "fourier"}, ["experiment"]),
            ("experiment-not-for-kind", {"experiment": "tensile"}, ["experiment", "tensile"]),
            ("format-version-2", {"format_version": 2}, ["format_version"]),
            ("format-version-str", {"format_version": "1"}, ["format_version"]),
            ("sample-rate-negative", {"sample_rate": -1000.0}, ["sample_rate"]),
            ("sample-rate-zero", {"sample_rate": 0}, ["sample_rate"]),
            ("sample-rate-str", {"sample_rate": "1kHz"}, ["sample_rate"]),
            ("sample-rate-mismatch", {"sample_rate": 500.0}, ["sample_rate"]),
            ("sample-rate-huge", {"sample_rate": 1e300}, ["sample_rate"]),
            ("sample-rate-bool", {"sample_rate": True}, ["sample_rate"]),
            ("sample-rate-tiny", {"sample_rate": 1e-300}, ["sample_rate"]),
            ("units-deg", {"units": {"q1": "deg"}}, ["q1", "deg"]),
            ("units-bar", {"units": {"p1": "bar"}}, ["p1", "bar"]),
            ("units-not-table", {"units": "SI"}, ["units"]),
            ("units-number", {"units": {"q1": 1}}, ["units.q1", "q1"]),
            ("description-number", {"description": 5}, ["description"]),
            ("source-list", {"source": ["a"]}, ["source"])):
        both(f"meta-{nm}", record("ol", meta=_meta_set(**kv)), nms)
    # columns
    for nm, fr, nms in (
            ("missing-q1", lambda df: df.drop(columns=["q1"]), ["q1"]),
            ("missing-p3", lambda df: df.drop(columns=["p3"]), ["p3"]),
            ("missing-t", lambda df: df.drop(columns=["t"]), ["'t'", "time"]),
            ("only-t", lambda df: df[["t"]], ["q1", "required", "needs"]),
            ("renamed-Q1", lambda df: df.rename(columns={"q1": "Q1"}), ["q1", "Q1"]),
            ("non-numeric", _set("q1", lambda s: s.astype(object).where(s.index != 5, "oops")),
             ["q1", "oops"]),
            ("bool-column", _set("q2", lambda s: s.index % 2 == 0), ["q2"]),
            ("nan-cell", _set("p2", lambda s: s.where(s.index != 7, np.nan)), ["p2"]),
            ("inf-cell", _set("qd1", lambda s: s.where(s.index != 7, np.inf)), ["qd1"]),
            ("all-nan-column", _set("p4", np.nan), ["p4"]),
            ("huge-value", _set("p1", lambda s: s.where(s.index != 3, 1e300)), ["p1"]),
            ("t-decreasing", _set("t", lambda s: s[::-1].to_numpy()), ["'t'"]),
            ("t-constant", _set("t", 0.0), ["'t'"]),
            ("t-duplicate", _set("t", lambda s: s.where(s.index != 4, s.shift(1))), ["'t'"]),
            ("t-nonuniform", _set("t", lambda s: s + 3e-4 * np.sin(np.arange(len(s)))),
             ["'t'", "uniform"]),
            ("t-gap", _set("t", lambda s: s + (s.index >= 500) * 0.5), ["gap", "'t'"]),
            ("t-in-ms", _set("t", lambda s: s * 1e3), ["'t'", "sample_rate", "ms"]),
            ("t-strings", _set("t", lambda s: "2024-01-01 00:00:0" + (s.index % 10).astype(str)),
             ["'t'"]),
            ("t-nan", _set("t", lambda s: s.where(s.index != 9, np.nan)), ["'t'", " t"]),
            ("t-1e300", _set("t", lambda s: s + 1e300), ["'t'"]),
            ("header-repeated", lambda df: pd.concat([
                df.iloc[:5].astype(object), pd.DataFrame([df.columns], columns=df.columns),
                df.iloc[5:].astype(object)]),
             ["'t'", "not a number"]),
            ("too-few-rows", lambda df: df.iloc[:5], ["short", "rows"]),
            ("no-rows", lambda df: df.iloc[:0], ["short", "rows", "no data"]),
            ("duplicate-column", lambda df: df.rename(columns={"qd2": "qd1"}), ["qd1",
                                                                               "duplicate"]),
            ("p-bar", _set("p1", lambda s: s / 1e5), ["p1", "bar"]),
            ("p-kpa", lambda df: df.assign(**{c: df[c] / 1e3 for c in df.columns
                                              if c[0] in "pu"}), ["kPa"]),
            ("p-below-vacuum", _set("p2", lambda s: s - 4e5), ["p2", "vacuum", "-1"]),
            ("p-1e9", _set("p3", lambda s: s * 1e4), ["p3"]),
            ("p-100bar", _set("p3", lambda s: s * 40), ["p3"]),
            ("u-below-vacuum", _set("u1", lambda s: s - 4e5), ["u1"]),
            ("u-huge", _set("u2", 1e12), ["u2"]),
            ("q-degrees", _set("q1", lambda s: s * 180 / math.pi), ["q1", "degrees"]),

            ("q-outside-turn", _set("q1", 7.0), ["q1"]),
            ("qd-deg-per-s", _set("qd1", lambda s: s * 180 / math.pi * 40), ["qd1", "deg/s"]),
            ("qd-huge", _set("qd2", 1e6), ["qd2"])):
        both(f"col-{nm}", record("ol", frame=fr), nms)
    both("semicolon-separator", record("ol", frame=None,
                                       body="t;q1;q2;qd1;qd2;p1;p2;p3;p4\n" +
                                       "".join(f"{i * 1e-3};0.7;-1.4;0;0;1e5;1e5;1e5;1e5\n"
                                               for i in range(50))),
         ["';'", "separator", "semicolon"])
    both("decimal-comma", record("ol", body="t;q1;q2;qd1;qd2;p1;p2;p3;p4\n" +
                                 "".join(f"0,{i:03d};0,7;-1,4;0;0;100000;100000;100000;100000\n"
                                         for i in range(50))),
         ["';'", "separator", "decimal", "comma"])
    both("tab-separator", record("ol", body="t\tq1\tq2\tqd1\tqd2\tp1\tp2\tp3\tp4\n" +
                                 "".join(f"{i * 1e-3}\t0.7\t-1.4\t0\t0\t1e5\t1e5\t1e5\t1e5\n"
                                         for i in range(50))),
         ["tab", "separator", "\\t"])
    both("ragged-rows", record("ol", body="t,q1,q2,qd1,qd2,p1,p2,p3,p4\n0,1,2\n" +
                               "0.001,0.7,-1.4,0,0,1e5,1e5,1e5,1e5,9,9\n"), ["CSV", "fields",
                                                                              "line"])
    both("header-only", record("ol", body="t,q1,q2,qd1,qd2,p1,p2,p3,p4\n"), ["short", "rows"])
    # valid but odd: must work
    case("data-file-valid", "crlf-line-ends", ["identify", "data.csv", "--kind", "dynamic",
                                               "--out", "o"],
         setup=chain(record("ol"), lambda d: (d / "data.csv").write_bytes(
             (d / "data.csv").read_bytes().replace(b"\n", b"\r\n"))), expect="ok")
    case("data-file-valid", "utf8-bom", ["identify", "data.csv", "--kind", "dynamic", "--out",
                                         "o"],
         setup=chain(record("ol"), lambda d: (d / "data.csv").write_bytes(
             b"\xef\xbb\xbf" + (d / "data.csv").read_bytes())), expect="ok")
    # closed loop metadata
    for nm, kv, nms in (
            ("controller-missing", {"controller": _DEL}, ["controller"]),
            ("variant-unknown", {"controller": {"variant": "LQR"}}, ["variant", "LQR"]),
            ("variant-miscased", {"controller": {"variant": "pid"}}, ["variant", "pid"]),
            ("reference-unknown", {"reference": "circle7"}, ["reference", "circle7"]),
            ("reference-number", {"reference": 3}, ["reference"]),
            ("family-unknown", {"controller": {"family": "LQR", "gains": {"kp": 1}}},
             ["family", "LQR"]),
            ("gains-string", {"controller": {"family": "PID", "gains": {"kp": "high"}}},
             ["gains", "kp"]),
            ("gains-empty", {"controller": {"family": "PID", "gains": {}}}, ["gains"])):
        case("data-file", f"closed-{nm}", DIAG, setup=record("cl", meta=_meta_set(**kv)),
             names=nms)
    case("data-file", "closed-q-degrees", DIAG,
         setup=record("cl", frame=_set("q2", lambda s: s * 180 / math.pi)), names=["q2"])
    # static records
    for nm, fr, nms in (("F-negative", _set("F1", lambda s: -s), ["F1"]),
                        ("F-huge", _set("F2", 1e9), ["F2"]),
                        ("two-rows", lambda df: df.iloc[:2], ["short", "rows"])):
        case("data-file", f"static-{nm}", IDENT_S, setup=record("st", frame=fr), names=nms)
    # actuator records
    for nm, fr, kv, nms in (
            ("contraction-percent", _set("contraction", lambda s: s * 100), {},
             ["contraction", "percent"]),
            ("contraction-negative", _set("contraction", lambda s: s - 2.0), {}, ["contraction"]),
            ("contraction-one", _set("contraction", 1.0), {}, ["contraction"]),
            ("pressure-below-vacuum", _set("pressure", lambda s: s - 5e5), {}, ["pressure"]),
            ("pressure-1e9", _set("pressure", lambda s: s * 1e4), {}, ["pressure"]),
            ("pressure-bar", _set("pressure", lambda s: s / 1e5), {}, ["pressure", "bar"]),
            ("force-huge", _set("force", 1e12), {}, ["force"]),
            ("force-law-4", None, {"force_law": {"a": [1e-5, 3e-3, 0, 0]}}, ["force_law"]),
            ("force-law-bar", None, {"force_law": {"a": [8.2, 295, -1587, 3623, -5729]}},
             ["force_law", "N/bar"]),
            ("force-law-missing", None, {"force_law": _DEL}, ["force_law"]),
            ("force-law-a0-negative", None, {"force_law": {"a": [-1e-5, 3e-3, 0, 0, 0]}},
             ["force_law"]),
            ("force-law-l0-mm", None, {"force_law": {"a": [8e-5, 3e-3, 0, 0, 0], "l0": 60}},
             ["l0"]),
            ("position-without-l0", lambda df: df.rename(columns={"contraction": "position"}),
             {}, ["position", "l0"]),
            ("position-negative", lambda df: df.rename(columns={"contraction": "position"})
             .assign(position=-0.05), {"force_law": {"a": [8e-5, 3e-3, 0, 0, 0], "l0": 0.06}},
             ["position"])):
        case("data-file", f"actuator-{nm}", DIAG,
             setup=record("ten", meta=_meta_set(**kv) if kv else None, frame=fr), names=nms)
        case("data-file", f"actuator-{nm}-identify", IDENT_S,
             setup=record("ten", meta=_meta_set(**kv) if kv else None, frame=fr), names=nms)
    # loose units: the impossible is still refused, the unit hints become one-line warnings
    case("data-file", "loose-p-below-vacuum", DIAG + ["--loose-units"],
         setup=record("ol", frame=_set("p2", lambda s: s - 4e5)), names=["p2"])
    case("data-file", "loose-q-degrees", DIAG + ["--loose-units"],
         setup=record("ol", frame=_set("q1", lambda s: s * 180 / math.pi)), names=["q1"])
    # suspicious but possible: a one-line warning naming the column
    for nm, fr, nms in (("p1-kpa-only", _set("p1", lambda s: s / 1e3), ["p1", "kPa"]),
                        ("q-degrees-small", _set("q2", lambda s: s * 180 / math.pi / 20),
                         ["q2", "working area"]),
                        ("p-6bar", _set("p1", lambda s: s * 2.5), ["p1", "plausible"])):
        case("data-file", f"warn-{nm}", DIAG, setup=record("ol", frame=fr), names=nms,
             expect="warn")
    case("data-file", "loose-allow-gaps-all-nan", DIAG + ["--allow-gaps"],
         setup=record("ol", frame=_set("p1", np.nan)), names=["p1", "short", "rows"])


# ---- study files ---------------------------------------------------------------------------

def _study_cases():
    def study(name, text, names, *, extra=(), expect="error", setup=None, timeout=TIMEOUT):
        body = text
        case("study-file", name, SWEEP + list(extra),
             setup=chain(files(**{"s.toml": body}), setup), names=names, expect=expect,
             timeout=timeout)

    B = '[case]\nexperiment = "step"\n'
    study("empty-file", "", ["s.toml", "case", "empty", "no case"])
    study("only-comments", "# nothing\n", ["s.toml", "case", "empty", "no case"])
    study("only-study-table", '[study]\nname = "x"\n', ["case", "no case", "grid"])
    study("binary", bytes(range(256)) * 4, ["s.toml", "UTF-8", "TOML"])
    study("bad-toml", "[case\nexperiment = step\n", ["s.toml", "TOML"])
    study("unknown-table", "[cases]\nexperiment = 'step'\n", ["cases"])
    study("unknown-key", B + "lamda = 0.4\n", ["lamda"])
    study("miscased-key", '[case]\nExperiment = "step"\n', ["Experiment"])
    study("top-level-key", 'experiment = "step"\n', ["experiment"])
    for k, v, nms in (
            ("experiment", '"Step"', ["experiment", "Step"]),
            ("experiment", "1", ["experiment"]),
            ("controller", '"pid"', ["controller", "pid"]),
            ("lam", '"fast"', ["lam"]), ("lam", "-1.0", ["lam"]), ("lam", "nan", ["lam"]),
            ("lam", "inf", ["lam"]), ("lam", "1e300", ["lam"]), ("lam", "-0.5", ["lam"]),
            ("lam", "[1.0, 2.0, 3.0]", ["lam"]),
            ("kp_bar", "1e9", ["kp_bar"]), ("ki_bar", "-1", ["ki_bar"]),
            ("kd_bar", "1e300", ["kd_bar"]), ("kp_bar", "true", ["kp_bar"]),
            ("task_kp", "1e12", ["task_kp"]),
            ("stiffness", "-1.0", ["stiffness"]), ("stiffness", "1e300", ["stiffness"]),
            ("stiffness", "[1.0]", ["stiffness"]), ("stiffness", '"stiff"', ["stiffness"]),
            ("head", '"Thesis-Frontal"', ["head"]), ("head", '"dummy"', ["head"]),
            ("instants", '"worst"', ["instants"]), ("every", "0", ["every"]),
            ("noise_seed", "-1", ["noise_seed"]), ("noise_seed", "1.5", ["noise_seed"]),
            ("duration", "0.0", ["duration"]), ("duration", "-1.0", ["duration"]),
            ("duration", "1e9", ["duration"]), ("duration", "1.0", ["duration", "step"]),
            ("duration", "nan", ["duration"]), ("effects", "{ payload_mass = 9 }",
                                                 ["effects", "payload_mass"])):
        ctrl = ('controller = "PSMC joint"\n' if k in ("lam", "kp_bar", "ki_bar", "kd_bar")
                else 'controller = "PSMC task"\n' if k == "task_kp" else "")
        exp = "" if k == "experiment" else 'experiment = "step"\n'
        every = 'instants = "all"\n' if k == "every" else ""
        study(f"case-{k}-{v}", f"[case]\n{exp}{ctrl}{every}{k} = {v}\n", nms)
    study("every-without-all", B + "every = 5\n", ["every", "instants"])
    study("pid-with-lam", B + 'controller = "PID"\nlam = 0.4\n', ["lam", "PID"])
    study("circle-1ms", '[case]\nexperiment = "circle10"\nduration = 0.001\n',
          ["duration", "failed"], timeout=180)
    study("grid-mixed-types", B + '[grid]\nduration = [3.0, "long"]\n', ["grid.duration[1]"])
    study("variants-nested", '[[variants]]\ncontroller = { family = "PID" }\n',
          ["variants[0].controller"])
    study("output-csv-uppercase", B + '[output]\ncsv = "R.CSV"\n', ["output.csv"])
    study("noise-seed-huge", B + "noise_seed = 99999999999999999999\n", ["noise_seed"])
    study("switch-too-short", '[case]\nexperiment = "switch"\nduration = 5.0\n',
          ["duration", "switch"])
    study("circle-huge", '[case]\nexperiment = "circle10"\nduration = 1e5\n', ["duration"])
    # valid: plant effects of every case (README), a payload within its range
    case("study-file-valid", "case-effects-payload-1kg", SWEEP + ["--no-progress"],
         setup=files(**{"s.toml": B + "effects = { payload_mass = 1 }\n"}), expect="ok")
    # grids
    study("grid-empty-list", B + "[grid]\nlam = []\n", ["grid.lam"])
    study("grid-not-list", B + "[grid]\nlam = 0.4\n", ["grid.lam"])
    study("grid-string", B + '[grid]\nlam = "0.4"\n', ["grid.lam"])
    study("grid-geomspace-zero", B + "[grid]\nstiffness = { geomspace = [0, 1, 3] }\n",
          ["grid.stiffness"])
    study("grid-geomspace-num-0", B + "[grid]\nstiffness = { geomspace = [1, 10, 0] }\n",
          ["grid.stiffness"])
    study("grid-geomspace-num-float", B + "[grid]\nstiffness = { geomspace = [1, 10, 3.5] }\n",
          ["grid.stiffness"])
    study("grid-linspace-arity", B + "[grid]\nstiffness = { linspace = [1, 10] }\n",
          ["grid.stiffness"])
    study("grid-logspace", B + "[grid]\nstiffness = { logspace = [0, 1, 3] }\n",
          ["grid.stiffness"])
    study("grid-1e9-points", B + "[grid]\nstiffness = { geomspace = [1, 10, 1000000000] }\n",
          ["grid", "cases", "--max-cases"])
    P = '[case]\nexperiment = "step"\ncontroller = "PSMC joint"\n'
    study("grid-1e6-cases", P + "[grid]\nstiffness = { geomspace = [1, 10, 1000] }\n"
          "lam = { geomspace = [0.1, 1, 1000] }\n", ["cases", "--max-cases"])
    study("grid-1e8-cases", B + "[grid]\nstiffness = { geomspace = [1, 10, 10000] }\n"
          "duration = { linspace = [3, 12, 10000] }\n", ["cases", "--max-cases"])
    study("grid-1e12-cases", B + "[grid]\nstiffness = { geomspace = [1, 10, 1000000] }\n"
          "duration = { linspace = [3, 12, 1000000] }\n", ["cases", "--max-cases"])
    study("grid-1e6-max-cases", P + "[grid]\nstiffness = { geomspace = [1, 10, 1000] }\n"
          "lam = { geomspace = [0.1, 1, 1000] }\n", ["cases", "--max-cases", "--yes"],
          extra=["--max-cases", "2000000"])
    study("grid-1e6-histories", P + "[grid]\nstiffness = { geomspace = [1, 10, 1000] }\n"
          "lam = { geomspace = [0.1, 1, 1000] }\n[output]\nhistories = true\n",
          ["cases", "--max-cases", "GB"])
    study("grid-also-in-case", B + '[grid]\nexperiment = ["step"]\n', ["grid.experiment"])
    study("grid-noise-seed-float", B + "[grid]\nnoise_seed = { linspace = [0, 1, 3] }\n",
          ["noise_seed"])
    study("grid-duration-short", B + "[grid]\nduration = [1.0, 3.0]\n", ["duration", "grid"])
    study("grid-gain-huge", B + 'controller = "PSMC joint"\n[grid]\nki_bar = [2, 1e9]\n',
          ["ki_bar"])
    # variants
    study("variants-not-array", "variants = 1\n", ["variants"])
    study("variants-empty", "variants = []\n", ["variants"])
    study("variants-conflict", B + '[[variants]]\nexperiment = "switch"\n',
          ["variants[0].experiment", "experiment"])
    study("variants-task-with-ki", '[[variants]]\ncontroller = "PSMC task"\nki_bar = 2\n',
          ["ki_bar"])
    # output / study tables
    for k, v, nms in (("csv", '"../x.csv"', ["output.csv"]), ("csv", '"x.txt"', ["output.csv"]),
                      ("csv", '""', ["output.csv"]), ("csv", "5", ["output.csv"]),
                      ("csv", '"study.toml"', ["output.csv"]),
                      ("histories", '"yes"', ["output.histories"]),
                      ("format", '"csv"', ["output.format"])):
        study(f"output-{k}-{v}", B + f"[output]\n{k} = {v}\n", nms)
    study("study-name-empty", B + '[study]\nname = ""\n', ["study.name"])
    study("study-name-number", B + "[study]\nname = 5\n", ["study.name"])
    study("study-not-table", B + "study = 5\n", ["study"])
    # run-time failure of every case: a non-zero exit with a summary
    study("all-cases-fail", B + 'instants = "all"\nevery = 1000000\n',
          ["failed", "case", "every"], timeout=180)


# ---- Python entry points -------------------------------------------------------------------

def _api_cases():
    def hic(*a, **k):
        from ppamsafety.impact.hic import hic as f
        return f(*a, **k)

    a = np.abs(np.sin(np.linspace(0, np.pi, 200))) * 50
    api("api-hic", "masked-array", lambda: hic(np.ma.masked_array(a, mask=a > 40), 1e-4),
        names=["a", "mask"])
    api("api-hic", "dt-1e-300", lambda: hic(a, 1e-300), names=["dt"])
    api("api-hic", "dt-0d-array", lambda: hic(a, np.array(1e-4)), names=["dt"], expect="ok")
    api("api-hic", "empty-batch", lambda: hic(np.zeros((0, 200)), 1e-4), names=["a"])
    api("api-hic", "empty-record", lambda: hic(np.zeros(0), 1e-4), names=["a"])
    # a window longer than the record covers the record (the unlimited HIC; documented)
    api("api-hic", "window-huge-valid", lambda: hic(a, 1e-4, window=1e300), expect="ok")
    api("api-hic", "window-nan", lambda: hic(a, 1e-4, window=math.nan), names=["window"])
    api("api-hic", "window-inf", lambda: hic(a, 1e-4, window=math.inf), names=["window"])
    api("api-hic", "window-0", lambda: hic(a, 1e-4, window=0), names=["window"])
    api("api-hic", "negative-accel", lambda: hic(-a, 1e-4), names=["a", "non-negative"])
    api("api-hic", "list-of-str", lambda: hic(["1", "2"], 1e-4), names=["a"])
    api("api-hic", "object-array", lambda: hic(np.array([1, None, 3], dtype=object), 1e-4),
        names=["a"])
    api("api-hic", "3d", lambda: hic(np.zeros((2, 2, 10)), 1e-4), names=["a"])
    api("api-hic", "huge-record", lambda: hic(np.ones(10 ** 9 // 8), 1e-4), names=["a"],
        expect="ok")

    def sweep_(*a, **k):
        from ppamsafety.sweep import run_sweep
        return run_sweep(*a, **k).table

    api("api-sweep", "cache-dir-empty", lambda: sweep_(_square, [{"x": 1}], cache_dir=""),
        names=["cache_dir"])
    api("api-sweep", "result-column-clash", lambda: sweep_(_clash, [{"x": 1}], progress=False),
        names=["x", "column"])
    api("api-sweep", "result-column-clash-raise",
        lambda: sweep_(_clash, [{"x": 1}], progress=False, on_error="raise"), names=["x"])
    api("api-sweep", "huge-grid", lambda: sweep_(_square, grid={"x": list(range(10 ** 4)),
                                                                 "y": list(range(10 ** 4))},
                                                 progress=False),
        names=["cases", "max_cases"])
    api("api-sweep", "grid-generator", lambda: sweep_(_square, grid={"x": (i for i in range(3))},
                                                      progress=False), names=["grid"])
    api("api-sweep", "processes-0d", lambda: sweep_(_square, [{"x": 1}], processes=np.array(1),
                                                    progress=False), names=["processes"],
        expect="ok")
    api("api-sweep", "on-error-miscased", lambda: sweep_(_square, [{"x": 1}], on_error="Raise"),
        names=["on_error"])
    api("api-sweep", "all-fail", lambda: sweep_(_fail, [{"x": 1}, {"x": 2}], progress=False),
        names=["failed", "case"], expect="warn")

    def traj(f, **k):
        from ppamsafety.experiments import trajectories as tr
        from ppamsafety.params import thesis_arm
        return getattr(tr, f)(thesis_arm(), **k)

    def thesis_ref(name, **k):
        from ppamsafety.experiments.catalog import thesis_reference
        from ppamsafety.params import thesis_arm
        return thesis_reference(thesis_arm(), name, **k)

    api("api-experiment", "step-duration-1", lambda: traj("step", duration=1.0),
        names=["duration"])
    api("api-experiment", "step-duration-0d", lambda: traj("step", duration=np.array(12.0)),
        names=["duration"], expect="ok")
    api("api-experiment", "circle-1e5s", lambda: traj("circle", period=10.0, duration=1e5),
        names=["duration", "GB", "samples"])
    api("api-experiment", "thesis-circle-1e5s", lambda: thesis_ref("circle10", duration=1e5),
        names=["duration", "GB", "samples"])
    api("api-experiment", "thesis-step-miscased", lambda: thesis_ref("Step"), names=["name",
                                                                                    "Step"])
    api("api-experiment", "run-bad-reference", _run_bad_reference, names=["reference"])
    api("api-experiment", "run-unholdable-reference", _run_unholdable_reference,
        names=["reference", "q_d"])
    api("api-experiment", "run-duration-1e9", _run_duration_huge, names=["duration"])

    def impacts(**k):
        from ppamsafety.impact.model import simulate_impacts
        from ppamsafety.params import thesis_arm
        kw = dict(q=np.radians([30, -80]), qd=[1.0, 0.0], stiffness=[43.0, 27.0])
        kw.update(k)
        return simulate_impacts(thesis_arm(), kw.pop("q"), kw.pop("qd"), kw.pop("stiffness"),
                                **kw)

    api("api-impact", "qd-392", lambda: impacts(qd=[500.0, 0.0]), names=["qd", "tool speed"])
    api("api-impact", "head-miscased", lambda: impacts(head="Thesis-Frontal"), names=["head"])
    api("api-impact", "qd-0d", lambda: impacts(qd=np.array([1.0, 0.0])[0:2]), expect="ok")
    api("api-impact", "dt-0d", lambda: impacts(dt=np.array(2e-5)), expect="ok")
    api("api-impact", "dt-masked", lambda: impacts(qd=np.ma.masked_array([1.0, 0.0],
                                                                         mask=[1, 0])),
        names=["qd", "mask"])

    def maxload(**k):
        from ppamsafety.design import max_load_map
        from ppamsafety.params import thesis_arm
        return max_load_map(thesis_arm(), n1=5, n2=5, **k)

    api("api-design", "p-max-1e300", lambda: maxload(p_max=1e300), names=["p_max"])
    api("api-design", "p-max-0d", lambda: maxload(p_max=np.array(3e5)), expect="ok")
    api("api-design", "p-max-negative", lambda: maxload(p_max=-1.0), names=["p_max"])

    def synth(*a, **k):
        from ppamsafety.diagnose import synthesize
        return synthesize(*a, **k)

    for v in (math.inf, math.nan, "abc", "", "1,2,3", [1.0, 2.0, 3.0], None, {}, True):
        api("api-synthesize", f"payload_mass-{v!r}", lambda v=v: synth(
            "open-loop", {"payload_mass": v}, duration=0.5), names=["payload_mass"])
    for v in ("1,2,3", [1, 2, 3], math.inf, "abc"):
        api("api-synthesize", f"valve_dead_time-{v!r}", lambda v=v: synth(
            "open-loop", {"valve_dead_time": v}, duration=0.5), names=["valve_dead_time"])
    api("api-synthesize", "noise-miscased", lambda: synth("open-loop", noise="None"),
        names=["noise"])
    api("api-synthesize", "experiment-miscased", lambda: synth("Open-Loop"),
        names=["experiment"])
    api("api-synthesize", "seed-0d", lambda: synth("open-loop", seed=np.array(3), duration=0.5),
        expect="ok")

    def check_case(**k):
        from ppamsafety.sweep_cases import check_case as f
        return f(**k)

    api("api-case", "lam-0d", lambda: check_case(controller="PSMC joint", lam=np.array(0.4)),
        expect="ok")
    api("api-case", "lam-1e300", lambda: check_case(controller="PSMC joint", lam=1e300),
        names=["lam"])
    api("api-case", "controller-miscased", lambda: check_case(controller="pid"),
        names=["controller"])
    api("api-case", "duration-short", lambda: check_case(experiment="step", duration=1.0),
        names=["duration"])


# ---- found in the second pass of issue 22 (classes the first battery did not hold) ---------

DATASET = ROOT / "ppamsafety" / "data" / "datasets" / "zillen2021"
MANIFEST = ('profile = "profile.toml"\nexperiment = "tensile"\n[actuator]\ntype = "cylinder"\n'
            'bore = "25.7 mm"\n')
RECORD = '[[records]]\nfile = "r1.csv.xz"\npressure_nominal = "1 bar"\n'


def campaign(manifest=MANIFEST + RECORD, *, record=True, profile=True, **extra):
    """A setup writing a campaign manifest ``m.toml`` beside a real record and profile."""
    def setup(d: Path):
        if profile:
            shutil.copy(DATASET / "profile.toml", d / "profile.toml")
        if record:
            shutil.copy(DATASET / "O-ring257_1bar.csv.xz", d / "r1.csv.xz")
        (d / "m.toml").write_bytes(manifest if isinstance(manifest, bytes)
                                   else manifest.encode("utf-8"))
        files(**extra)(d)
    return setup


def thesis_arm_file(d: Path, crlf=False, bom=False):
    from ppamsafety.params import thesis_arm
    from ppamsafety.params.arm_file import arm_to_toml
    t = arm_to_toml(thesis_arm()).encode()
    if crlf:
        t = t.replace(b"\n", b"\r\n")
    (d / "a.toml").write_bytes((b"\xef\xbb\xbf" if bom else b"") + t)


def _xz_bomb(d: Path):
    """A small .xz record that decompresses to 300 MB."""
    import lzma
    with lzma.open(d / "r1.csv.xz", "wb", preset=0) as fh:
        block = b"0.0\t0.0\t0.0\t0.0\t0.0\t0.0\t0.0\n" * 10000
        for _ in range(300 * 2 ** 20 // len(block) + 1):
            fh.write(block)


def _sparse(name, size):
    def setup(d: Path):
        with open(d / name, "wb") as fh:
            fh.truncate(size)
    return setup


def _more_cases():
    DIAG_M = ["diagnose", "m.toml", "--out", "o"]
    # ---- campaign manifests (diagnose MANIFEST.toml) -----------------------------------------
    for nm, man, kw, nms in (
            ("empty", "", {}, ["m.toml", "records"]),
            ("binary", bytes(range(256)) * 8, {}, ["m.toml", "binary", "UTF-8"]),
            ("latin1", MANIFEST.encode() + "# \xb5\n".encode("latin-1") + RECORD.encode(), {},
             ["m.toml", "UTF-8"]),
            ("bad-toml", "records = [\n", {}, ["m.toml", "TOML"]),
            ("unknown-key", MANIFEST + "pressure = 1\n" + RECORD, {}, ["pressure"]),
            ("records-not-array", MANIFEST + "records = 5\n", {}, ["records"]),
            ("records-empty", MANIFEST + "records = []\n", {}, ["records"]),
            ("records-strings", MANIFEST + 'records = ["r1.csv.xz"]\n', {}, ["records"]),
            ("record-no-file", MANIFEST + '[[records]]\nlabel = "a"\n', {}, ["records[0]", "file"]),
            ("record-file-number", MANIFEST + "[[records]]\nfile = 5\n", {}, ["records[0].file"]),
            ("record-file-empty", MANIFEST + '[[records]]\nfile = ""\n', {}, ["records[0].file"]),
            ("record-file-missing", MANIFEST + '[[records]]\nfile = "nope.csv"\n', {},
             ["records[0]", "nope.csv"]),
            ("record-file-folder", MANIFEST + '[[records]]\nfile = "dir"\n', {"dir": None},
             ["records[0]", "dir", "folder"]),
            ("record-file-binary", MANIFEST + '[[records]]\nfile = "b.csv"\n',
             {"b.csv": bytes(range(256)) * 8}, ["records[0]", "b.csv"]),
            ("record-unknown-key", MANIFEST + RECORD + "bore = 1\n", {}, ["records[0]", "bore"]),
            ("record-format-miscased", MANIFEST + RECORD + 'format = "Raw"\n', {},
             ["records[0].format", "raw"]),
            ("record-label-number", MANIFEST + RECORD + "label = 5\n", {}, ["records[0].label"]),
            ("record-run-float", MANIFEST + RECORD + "run = 1.5\n", {}, ["records[0].run"]),
            ("record-pressure-nonsense", MANIFEST + '[[records]]\nfile = "r1.csv.xz"\n'
             'pressure_nominal = "3 parsecs"\n', {}, ["pressure_nominal"]),
            ("profile-missing", MANIFEST.replace("profile.toml", "nope.toml") + RECORD, {},
             ["profile", "nope.toml"]),
            ("profile-number", MANIFEST.replace('"profile.toml"', "5") + RECORD, {}, ["profile"]),
            ("profile-folder", MANIFEST.replace("profile.toml", "dir") + RECORD, {"dir": None},
             ["profile", "dir"]),
            ("actuator-string", MANIFEST.split("[actuator]")[0] + 'actuator = "cylinder"\n'
             + RECORD, {}, ["actuator"]),
            ("actuator-bore-negative", MANIFEST.replace("25.7 mm", "-25.7 mm") + RECORD, {},
             ["bore", "actuator"]),
            ("name-number", "name = 5\n" + MANIFEST + RECORD, {}, ["name"]),
            ("raw-without-profile", MANIFEST.replace('profile = "profile.toml"\n', "") + RECORD,
             {}, ["profile", "records[0]"])):
        case("campaign-file", nm, DIAG_M, setup=campaign(man, **kw), names=nms)
    for opt, v in (("--bootstrap", "0"), ("--seed", "3"), ("--block", "0.1"),
                   ("--allow-gaps", None), ("--loose-units", None),
                   ("--experiment", "open-loop"), ("--arm", "a.toml")):
        case("campaign-file", f"arm-option{opt}", DIAG_M + [opt] + ([v] if v else []),
             setup=chain(campaign(), lambda d: thesis_arm_file(d)), names=[opt])
    for opt, v in (("--drop", "5"), ("--no-friction", None), ("--sign-velocity", "0.1")):
        case("identify-option", f"static-with{opt}", IDENT_S + [opt] + ([v] if v else []),
             setup=copy_base("st.csv", "data.csv"), names=[opt, "dynamic"])
    case("identify-option", "sign-velocity-without-friction",
         IDENT_D + ["--no-friction", "--sign-velocity", "0.1"], setup=copy_base("ol.csv",
                                                                               "data.csv"),
         names=["--sign-velocity", "friction"])
    case("campaign-file", "folder", ["diagnose", "m.toml", "--out", "o"],
         setup=files(**{"m.toml": None}), names=["m.toml", "folder"])
    case("campaign-file", "missing", ["diagnose", "m.toml", "--out", "o"],
         names=["m.toml", "does not exist"])
    case("campaign-file", "xz-bomb", DIAG_M, setup=chain(campaign(record=False), _xz_bomb),
         names=["r1.csv.xz", "decompresses", "MB"], timeout=120)
    case("campaign-file", "huge-record", DIAG_M.copy(),
         setup=chain(campaign(MANIFEST + '[[records]]\nfile = "big.csv"\n', record=False),
                     _sparse("big.csv", 2 ** 30)), names=["big.csv", "MB"])
    case("campaign-file", "bom-crlf-valid", DIAG_M,
         setup=campaign(b"\xef\xbb\xbf" + (MANIFEST + RECORD).replace("\n", "\r\n").encode()),
         expect="ok", timeout=180)

    # ---- input text files: arm, head and study files share one reader ----------------------
    for opt, argv, valid in (
            ("--arm", IMPACT + ["--arm", "a.toml"], "arm"),
            ("--head", IMPACT + ["--head", "a.toml"], "head"),
            ("study", ["sweep", "a.toml", "--out", "o"], "study"),
            ("arm-check", ["arm", "check", "a.toml"], "arm")):
        for nm, setup, nms in (
                ("binary", files(**{"a.toml": bytes(range(256)) * 4}), ["a.toml", "binary"]),
                ("latin1", files(**{"a.toml": b'name = "\xb5"\n'}), ["a.toml", "UTF-8"]),
                ("folder", files(**{"a.toml": None}), ["a.toml", "folder"]),
                ("fifo", lambda d: os.mkfifo(d / "a.toml"), ["a.toml", "regular file"]),
                ("dev-zero-link", lambda d: os.symlink("/dev/zero", d / "a.toml"),
                 ["a.toml", "regular file"]),
                ("dangling-link", lambda d: os.symlink("nowhere.toml", d / "a.toml"),
                 ["a.toml", "does not exist"]),
                ("huge", _sparse("a.toml", 200 * 2 ** 20), ["a.toml", "MB"]),
                ("under-a-file", files(**{"f.txt": "x\n"}), ["f.txt", "does not exist"])):
            a = [x.replace("a.toml", "f.txt/a.toml") for x in argv] if nm == "under-a-file" \
                else argv
            case("input-file", f"{opt.strip('-')}-{nm}", a, setup=setup, names=nms)
    for opt, argv in (("--arm", IMPACT + ["--arm", ""]), ("--head", IMPACT + ["--head", ""]),
                      ("arm-check", ["arm", "check", ""]),
                      ("--arm-export", ["arm", "export", "--out", "x.toml", "--arm", ""])):
        case("input-file", f"{opt.strip('-')}-empty-path", argv,
             names=["--arm", "--head", "FILE", "empty"])

    case("input-file-valid", "arm-bom-crlf", ["arm", "check", "a.toml"],
         setup=lambda d: thesis_arm_file(d, crlf=True, bom=True), expect="ok")
    case("input-file-valid", "study-bom-crlf", ["sweep", "s.toml", "--out", "o", "--no-progress"],
         setup=files(**{"s.toml": b'\xef\xbb\xbf[case]\r\nexperiment = "step"\r\n'}), expect="ok")

    # ---- a single-valued option given twice -----------------------------------------------------
    ol = copy_base("ol.csv", "data.csv")
    for nm, argv, setup in (
            ("impact-q", IMPACT + ["--q", "40", "-80"], None),
            ("impact-dt", IMPACT + ["--dt", "1e-5", "--dt", "2e-5"], None),
            ("impact-head", IMPACT + ["--head", "thesis-frontal", "--head", "child-frontal"], None),
            ("synth-seed", SYN + ["--seed", "1", "--seed", "2"], None),
            ("synth-out", SYN + ["--out", "y.csv"], None),
            ("synth-noise", SYN + ["--noise", "none", "--noise", "table-3.2"], None),
            ("diagnose-seed", DIAG + ["--seed", "1", "--seed", "2"], ol),
            ("diagnose-out", DIAG + ["--out", "p"], ol),
            ("identify-kind", IDENT_D + ["--kind", "static"], ol),
            ("sweep-processes", SWEEP + ["--processes", "1", "--processes", "2"],
             copy_base("study.toml", "s.toml")),
            ("report-outdir", ["report", "--outdir", "a", "--outdir", "b"], None),
            ("arm-check-q", ["arm", "check", "a.toml", "--q", "50", "-80", "--q", "60", "-80"],
             None),
            ("arm-twice", IMPACT + ["--arm", "a.toml", "--arm", "b.toml"], None)):
        opt = next(a for a in argv[::-1] if a.startswith("--"))
        case("cli-duplicate", nm, argv, setup=setup, names=[opt, "twice"])
    case("cli-duplicate", "report-only-name-twice", ["report", "--only", "design,design"],
         names=["--only", "design", "more than once"])
    case("cli-duplicate", "report-only-empty-part", ["report", "--only", "design,,safety"],
         names=["--only", "empty"])

    # ---- single output files that name a folder -------------------------------------------------
    for nm, argv in (("history-slash", IMPACT + ["--history", "h/"]),
                     ("history-dot", IMPACT + ["--history", "."]),
                     ("synth-slash", ["synthesize", "--duration", "1", "--out", "x.csv/"]),
                     ("synth-dotdot", ["synthesize", "--duration", "1", "--out", ".."]),
                     ("arm-export-slash", ["arm", "export", "--out", "a/"]),
                     ("arm-export-csv", ["arm", "export", "--out", "a.csv"])):
        case("output-file", nm, argv, names=["--out", "--history", "folder", ".toml"])
    case("output-file", "arm-export-fifo", ["arm", "export", "--out", "a.toml", "--overwrite"],
         setup=lambda d: os.mkfifo(d / "a.toml"), names=["--out", "a.toml", "regular file"])

    # ---- study files: [envelope] ranges and keys ------------------------------------------------
    E = '[envelope]\nparameter = "{p}"\nrange = [{a}, {b}]\n'
    for nm, text, nms in (
            ("speed-high-end", E.format(p="speed", a=0.1, b=1e9), ["envelope.range", "speed"]),
            ("speed-zero", E.format(p="speed", a=0, b=1), ["envelope.range", "speed"]),
            ("lam-high-end", E.format(p="lam", a=0.1, b=1e300) +
             '[case]\ncontroller = "PSMC joint"\n', ["envelope.range", "lam"]),
            ("duration-high-end", E.format(p="duration", a=3, b=1e6), ["envelope.range",
                                                                       "duration"]),
            ("pressure-high-end", E.format(p="arm.pneumatics.mean_pressure", a=1e5, b=1e7),
             ["envelope.range", "mean_pressure"]),
            ("reversed", E.format(p="speed", a=1, b=0.1), ["envelope.range"]),
            ("range-strings", '[envelope]\nparameter = "speed"\nrange = ["0.1", "1"]\n',
             ["envelope.range"]),
            ("limit-miscased", E.format(p="speed", a=0.1, b=1) + 'limit = "f_max"\n',
             ["envelope.limit", "F_max"]),
            ("tolerance-zero", E.format(p="speed", a=0.1, b=1) + "tolerance = 0\n",
             ["envelope.tolerance"]),
            ("pose-outside", E.format(p="speed", a=0.1, b=1) + "pose = [400.0, 0.0]\n",
             ["q1_deg", "pose", "working area"]),
            ("with-grid", E.format(p="speed", a=0.1, b=1) + "[grid]\nlam = [0.4]\n",
             ["grid", "envelope"]),
            ("unknown-parameter", E.format(p="lamda", a=0.1, b=1), ["lamda"])):
        case("study-envelope", nm, SWEEP, setup=files(**{"s.toml": text}), names=nms)

    # ---- Ctrl-C: exit 130 at once, one line, nothing lost ---------------------------------------
    # about 2 min of work on 2 cores (about 0.1 s a case), so that the Ctrl-C comes while cases
    # run, also on a machine several times faster
    long_sweep = files(**{"s.toml": '[case]\nexperiment = "circle10"\n[grid]\n'
                                    'duration = { linspace = [60.0, 90.0, 1200] }\n'})
    case("interrupt", "sweep-early", SWEEP + ["--processes", "2", "--no-progress"],
         setup=long_sweep, interrupt=3.0, expect="interrupt")
    case("interrupt", "sweep-running", SWEEP + ["--processes", "2", "--no-progress"],
         setup=long_sweep, interrupt=12.0, expect="interrupt")
    case("interrupt", "sweep-resume-after", SWEEP + ["--resume", "--processes", "2",
                                                      "--no-progress"],
         setup=chain(long_sweep, marked_folder("o", "sweep", ())), interrupt=8.0,
         expect="interrupt")
    case("interrupt", "report", ["report", "--quick", "--outdir", "r", "--processes", "2"],
         interrupt=10.0, expect="interrupt")
    case("interrupt", "diagnose", DIAG + ["--bootstrap", "200"],
         setup=copy_base("ol_long.csv", "data.csv"), interrupt_on="interrupt_marker",
         expect="interrupt")
    case("interrupt", "synthesize", ["synthesize", "--out", "x.csv", "--duration", "600"],
         interrupt=3.0, expect="interrupt")


def _more_api_cases():
    def arm():
        from ppamsafety.params import thesis_arm
        return thesis_arm()

    # ---- sizes estimated before allocating ------------------------------------------------------
    def impacts_n(n):
        from ppamsafety.impact import simulate_impacts
        q = np.broadcast_to(np.radians([50.0, -80.0]), (n, 2))
        return simulate_impacts(arm(), q, np.broadcast_to([1.0, 0.0], (n, 2)), [43.0, 27.0])

    api("api-size", "impacts-1e7-cases", lambda: impacts_n(10 ** 7), names=["cases", "GB"])
    api("api-size", "impacts-1e8-cases", lambda: impacts_n(10 ** 8), names=["cases", "GB"])

    def synexc(**k):
        from ppamsafety.data import synthetic_excitation
        return synthetic_excitation(arm(), **k)

    api("api-size", "synthetic-excitation-dt-1e-9", lambda: synexc(dt=1e-9), names=["dt"])
    api("api-size", "synthetic-excitation-1000-periods-1us", lambda: synexc(periods=1000,
                                                                           dt=1e-6),
        names=["periods", "GB"])

    def simexc(**k):
        from ppamsafety.data.synthetic import default_excitation
        from ppamsafety.identify.excitation import simulate_excitation
        a = arm()
        return simulate_excitation(a, default_excitation(a), **k)

    api("api-size", "simulate-excitation-dt-1e-9", lambda: simexc(dt=1e-9), names=["dt"])
    api("api-size", "simulate-excitation-1e4-periods", lambda: simexc(periods=1e4, dt=1e-5),
        names=["periods", "GB"])

    def plant(n, rows=1):
        from ppamsafety.plant.model import simulate
        U = np.broadcast_to(np.full(4, 1e5), (rows, n, 4) if rows > 1 else (n, 4))
        return simulate(arm(), np.array([0.8, -1.4, 0, 0, 1e5, 1e5, 1e5, 1e5]), U)

    api("api-size", "plant-simulate-1e9-samples", lambda: plant(10 ** 9),
        names=["samples", "GB"])
    api("api-size", "plant-simulate-1e4-rows", lambda: plant(10 ** 5, 10 ** 4),
        names=["rows", "GB"])

    def directions(n):
        from ppamsafety.impact.directions import direction_sweep
        return direction_sweep(arm(), np.radians([50.0, -80.0]), [1.0, 0.0], [43.0, 27.0],
                               angles=np.broadcast_to(0.1, (n,)))

    api("api-size", "direction-sweep-1e8-angles", lambda: directions(10 ** 8),
        names=["angles", "GB"])

    def hic_bf(n, w):
        from ppamsafety.impact.hic import hic_bruteforce
        return hic_bruteforce(np.broadcast_to(1.0, (n,)), 1e-6, window=w)

    api("api-size", "hic-bruteforce-1e6-samples-1s", lambda: hic_bf(10 ** 6, 1.0),
        names=["windows", "hic()"])
    api("api-size", "hic-long-window-valid", lambda: _hic(np.abs(np.sin(np.arange(10 ** 6)
                                                                        * 1e-3)), 1e-6,
                                                           window=1.0), expect="ok")

    # ---- paths given to the public readers and writers ------------------------------------------
    def call(mod, fn, *a, **k):
        import importlib
        return getattr(importlib.import_module(mod), fn)(*a, **k)

    for fn, mod in (("load_arm", "ppamsafety.design"), ("load_head", "ppamsafety.impact.head"),
                    ("load_study", "ppamsafety.study_files"),
                    ("load_campaign", "ppamsafety.data.campaign"),
                    ("load_measured", "ppamsafety.data")):
        for nm, v in (("None", None), ("empty", ""), ("bytes", b"x.toml"), ("int", 3),
                      ("folder", "."), ("missing", "nope.toml"), ("list", ["a.toml"])):
            api("api-path", f"{fn}-{nm}", lambda mod=mod, fn=fn, v=v: call(mod, fn, v),
                names=["path", "file", "''", "nope.toml", "folder"])
    api("api-path", "run_study_file-outdir-empty", lambda: call(
        "ppamsafety.study_files", "run_study_file", BASE / "study.toml", ""),
        names=["outdir", "empty"])
    api("api-path", "run_study_file-study-None", lambda: call(
        "ppamsafety.study_files", "run_study_file", None, "o"), names=["study"])
    api("api-path", "parse_study-None", lambda: call("ppamsafety.study_files", "parse_study",
                                                     None), names=["text"])
    api("api-path", "parse_study-bytes", lambda: call("ppamsafety.study_files", "parse_study",
                                                      b"[case]\n"), names=["text"])
    api("api-path", "import_bench-missing", lambda: call(
        "ppamsafety.data.bench_import", "import_bench", "nope.csv", {},
        actuator={"type": "cylinder", "bore": 0.0257}), names=["nope.csv"])

    # ---- seeds: integers in [0, 2^63 - 1] everywhere --------------------------------------------
    def syn(**k):
        from ppamsafety.diagnose import synthesize
        return synthesize("open-loop", duration=0.5, **k)

    for nm, f in (("synthesize-2**64", lambda: syn(seed=2 ** 64)),
                  ("synthesize-actuator-2**64", lambda: call(
                      "ppamsafety.diagnose", "synthesize", kind="actuator", seed=2 ** 64)),
                  ("synthetic-static-neg", lambda: call("ppamsafety.data", "synthetic_static",
                                                        seed=-1)),
                  ("equilibria-float", lambda: call("ppamsafety.identify.static",
                                                    "equilibrium_configurations", arm(),
                                                    seed=1.5)),
                  ("static-experiment-str", lambda: call(
                      "ppamsafety.identify.static", "static_experiment", arm(),
                      np.radians([[50.0, -80.0]]), seed="1")),
                  ("design-excitation-neg", lambda: call(
                      "ppamsafety.identify.excitation", "design_excitation", arm(), seed=-1)),
                  ("default-excitation-2**64", lambda: call(
                      "ppamsafety.data.synthetic", "default_excitation", arm(), seed=2 ** 64))):
        api("api-seed", nm, f, names=["seed"])
    api("api-seed", "synthesize-0d-valid", lambda: syn(seed=np.array(2 ** 62)), expect="ok")

    # ---- envelopes: both ends of the range are checked before anything runs ---------------------
    def env(p, b, **k):
        from ppamsafety.envelope import safety_envelope
        return safety_envelope(p, b, **k)

    api("api-envelope", "speed-1e3", lambda: env("speed", (0.1, 1e3)), names=["bounds[1]",
                                                                             "speed"])
    api("api-envelope", "lam-1e300", lambda: env("lam", (0.1, 1e300),
                                                 case={"controller": "PSMC joint"}),
        names=["bounds[1]", "lam"])
    api("api-envelope", "duration-1e6", lambda: env("duration", (3.0, 1e6)),
        names=["bounds[1]", "duration"])
    api("api-envelope", "lam-pid", lambda: env("lam", (0.1, 1.0)), names=["lam", "PID"])
    api("api-envelope", "pressure-negative", lambda: env("arm.pneumatics.mean_pressure",
                                                         (-1e5, 2e5)),
        names=["bounds[0]", "mean_pressure"])
    api("api-envelope", "parameter-miscased", lambda: env("Speed", (0.1, 1.0)),
        names=["parameter", "Speed"])

    # ---- the README's entry points with loose types ---------------------------------------------
    def cc(**k):
        from ppamsafety.sweep_cases import check_case
        return check_case(**k)

    api("api-case", "stiffness-array-pair", lambda: cc(stiffness=np.array([40.0, 20.0])),
        expect="ok")
    api("api-case", "kp-array-pair", lambda: cc(kp_bar=np.array([1.0, 2.0])), expect="ok")
    api("api-case", "stiffness-2d", lambda: cc(stiffness=np.ones((2, 2))), names=["stiffness"])
    api("api-case", "lam-nan", lambda: cc(controller="PSMC joint", lam=math.nan),
        names=["lam"])
    api("api-case", "experiment-miscased-did-you-mean", lambda: cc(experiment="Step"),
        names=["did you mean 'step'"])
    api("api-case", "instants-miscased", lambda: cc(instants="Heuristic"),
        names=["did you mean 'heuristic'"])

    def sw(**k):
        from ppamsafety.sweep import run_sweep
        return run_sweep(_square, progress=False, **k).table

    api("api-sweep", "grid-empty-dict", lambda: sw(grid={}), names=["grid"])
    api("api-sweep", "grid-list-of-lists", lambda: sw(grid=[["x", [1, 2]]]), names=["grid"])
    api("api-sweep", "max-cases-0d-valid", lambda: call(
        "ppamsafety.study_files", "run_study_file", BASE / "study.toml", "o",
        max_cases=np.int64(1), progress=False), expect="ok", timeout=180)

    def impacts(**k):
        from ppamsafety.impact import simulate_impacts
        kw = dict(q=np.radians([50.0, -80.0]), qd=[1.0, 0.0], stiffness=[43.0, 27.0])
        kw.update(k)
        return simulate_impacts(arm(), kw.pop("q"), kw.pop("qd"), kw.pop("stiffness"), **kw)

    api("api-impact", "head-miscased-did-you-mean", lambda: impacts(head="Thesis-Frontal"),
        names=["did you mean 'thesis-frontal'"])
    api("api-impact", "bounds-head-name", lambda: call(
        "ppamsafety.impact.bounds", "impact_bounds", arm(), np.radians([50.0, -80.0]),
        [1.0, 0.0], head="thesis-frontal"), expect="ok")
    api("api-impact", "bounds-duration-huge", lambda: call(
        "ppamsafety.impact.bounds", "impact_bounds", arm(), np.radians([50.0, -80.0]),
        [1.0, 0.0], head="thesis-frontal", duration=1e9), names=["duration"])
    api("api-impact", "bounds-duration-str", lambda: call(
        "ppamsafety.impact.bounds", "impact_bounds", arm(), np.radians([50.0, -80.0]),
        [1.0, 0.0], head="thesis-frontal", duration="0.05"), names=["duration"])
    api("api-impact", "acceleration-dt-1e-300", lambda: call(
        "ppamsafety.identify.dynamic", "estimate_acceleration", np.zeros((100, 2)), 1e-300),
        names=["dt"])
    api("api-impact", "filter-dt-1e-300", lambda: call(
        "ppamsafety.identify.dynamic", "filter_signal", np.zeros(100), 1e-300), names=["dt"])
    api("api-impact", "chattering-dt-1e-300", lambda: call(
        "ppamsafety.experiments.metrics", "chattering_index", np.zeros((100, 2)), 1e-300),
        names=["dt"])
    api("api-report", "only-twice", lambda: call("ppamsafety.report.build", "build_report",
                                                 "r", only=["design", "design"]),
        names=["only", "design"])
    api("api-report", "only-miscased", lambda: call("ppamsafety.report.build", "build_report",
                                                    "r", only=["Design"]),
        names=["did you mean 'design'"])


def _section(name, **k):
    import importlib
    return importlib.import_module(f"ppamsafety.sections.{name}").compute(**k)


def _more_api_cases_2():
    # ---- the sections' compute(): common arguments checked even where unused ---------------------
    for name in ("responses", "design", "tracking", "safety", "effects", "cylinder_friction"):
        api("api-section", f"{name}-quick-str", lambda n=name: _section(n, quick="yes"),
            names=["quick"])
        api("api-section", f"{name}-arm-str", lambda n=name: _section(n, arm="thesis"),
            names=["arm"])
    for name in ("responses", "design", "safety", "effects"):
        api("api-section", f"{name}-head-unknown", lambda n=name: _section(n, head="nope"),
            names=["head", "nope"])

    # ---- names of result signals: a KeyError that is also a ValueError, with the spelling -------
    def ref_signal(name):
        from ppamsafety.experiments import step
        from ppamsafety.params import thesis_arm
        return step(thesis_arm()).signal(name)

    for v in ("X_d", "q1", 3, None):
        api("api-experiment", f"reference-signal-{v!r}", lambda v=v: ref_signal(v),
            names=["signal", repr(v)])

    def circle(**k):
        from ppamsafety.experiments.trajectories import circle as c
        from ppamsafety.params import thesis_arm
        return c(thesis_arm(), **k)

    api("api-experiment", "circle-period-1ms", lambda: circle(period=1e-3, duration=10.0),
        names=["period", "m/s"])
    api("api-experiment", "circle-period-10ms", lambda: circle(period=1e-2, duration=10.0),
        names=["period", "m/s"])
    api("api-experiment", "circle-partial-valid", lambda: circle(period=10.0, duration=4.0),
        expect="ok")

    # ---- identify_measured: an option that changes nothing is refused --------------------------------
    def ident(kind, **k):
        from ppamsafety.data import identify_measured, load_measured
        return identify_measured(load_measured(BASE / ("st.csv" if kind == "static" else
                                                       "ol.csv")), kind, **k)

    api("api-identify", "static-sign-velocity", lambda: ident("static", sign_velocity=0.1),
        names=["sign_velocity"])
    api("api-identify", "no-friction-sign-velocity", lambda: ident("dynamic", friction=False,
                                                                   sign_velocity=0.1),
        names=["sign_velocity", "friction"])
    api("api-identify", "sign-velocity-negative", lambda: ident("dynamic", sign_velocity=-1.0),
        names=["sign_velocity"])

    def diag(**k):
        from ppamsafety.data import load_measured
        from ppamsafety.diagnose import diagnose
        return diagnose(load_measured(BASE / "ten.csv"), **k)

    api("api-diagnose", "actuator-with-arm", lambda: diag(arm=_thesis()), names=["arm"])
    api("api-diagnose", "actuator-experiment-mismatch", lambda: diag(experiment="open-loop"),
        names=["experiment", "tensile"])


def _thesis():
    from ppamsafety.params import thesis_arm
    return thesis_arm()


def _more_cli_cases_2():
    st = copy_base("study.toml", "s.toml")
    case("sweep-option", "scheduler-not-an-address", SWEEP + ["--backend", "dask", "--scheduler",
                                                              "not an address"], setup=st,
         names=["--scheduler"])
    case("sweep-option", "scheduler-failed-leaves-nothing", SWEEP + ["--backend", "dask",
                                                                     "--scheduler", "x"],
         setup=st, names=["--scheduler"])
    ol = copy_base("ol.csv", "data.csv")
    ten = copy_base("ten.csv", "data.csv")
    for opt, v in (("--seed", "3"), ("--block", "0.1"), ("--bootstrap", "5")):
        case("diagnose-option", f"actuator-record{opt}", DIAG + [opt, v], setup=ten,
             names=[opt, "actuator"])
    case("diagnose-option", "experiment-mismatch-closed", DIAG + ["--experiment", "closed-loop"],
         setup=ol, names=["--experiment", "open-loop"])
    for nm, argv in (("synth-experiment-twice", SYN + ["--experiment", "open-loop",
                                                       "--experiment", "closed-loop"]),
                     ("identify-method-twice", IDENT_D + ["--method", "LS", "--method", "WLS"]),
                     ("history-twice", IMPACT + ["--history", "a.csv", "--history", "b.csv"])):
        opt = next(a for a in argv[::-1] if a.startswith("--"))
        case("cli-duplicate", nm, argv, setup=ol, names=[opt, "twice"])


def _hic(*a, **k):
    from ppamsafety.impact.hic import hic
    return hic(*a, **k)


def _square(x, y=0):
    return {"sq": x * x + y}


def _clash(x):
    return {"x": 99, "r": 1}


def _fail(x):
    raise ValueError("no")


def _run_bad_reference():
    from ppamsafety.control import PID
    from ppamsafety.experiments.case import ExperimentCase
    from ppamsafety.experiments.closed_loop import run_batch
    from ppamsafety.params import thesis_arm
    arm = thesis_arm()
    return run_batch([ExperimentCase(arm, PID(), "step")])


def _run_unholdable_reference():
    from ppamsafety.control import PID
    from ppamsafety.experiments import trajectories as tr
    from ppamsafety.experiments.case import ExperimentCase
    from ppamsafety.experiments.closed_loop import run_batch
    from ppamsafety.params import thesis_arm
    arm = thesis_arm()
    ref = tr.joint_steps(arm, q_levels=np.radians([[20.0, -130.0]]), t_changes=[],
                         duration=0.5)
    return run_batch([ExperimentCase(arm, PID(), ref)])


def _run_duration_huge():
    from ppamsafety.experiments.catalog import run_thesis_experiment, thesis_variants
    from ppamsafety.params import thesis_arm
    return run_thesis_experiment(thesis_arm(), "step", thesis_variants()[:1], duration=1e9)


_cli_cases()
_data_cases()
_study_cases()
_api_cases()
_more_cases()
_more_api_cases()
_more_api_cases_2()
_more_cli_cases_2()


# ------------------------------------------------------------------------------ running

@dataclass
class Result:
    """Outcome of one case."""

    case: str
    cls: str
    verdict: str
    rc: int | None
    seconds: float
    peak_mb: float
    message: str
    refused: bool = False
    expect: str = "error"
    detail: dict = field(default_factory=dict)


def _snapshot(d: Path) -> dict:
    out = {}
    for root, dirs, fs in os.walk(d):
        for f in fs:
            p = Path(root) / f
            try:
                if p.is_symlink() or not p.is_file():
                    continue
                out[str(p.relative_to(d))] = hashlib.sha1(p.read_bytes()).hexdigest()
            except OSError:
                continue
    return out


def _child_run(c: Case, d: Path, result_file: Path) -> int:
    """Run case ``c`` in this process (the child); return the exit status."""
    os.chdir(d)
    if c.api is not None:
        import warnings
        res = {}
        with warnings.catch_warnings(record=True) as w:
            warnings.simplefilter("always")
            try:
                out = c.api()
                res = {"ok": True, "result": repr(type(out).__name__)}
            except BaseException as exc:       # noqa: BLE001 - classify everything
                res = {"ok": False, "type": type(exc).__name__, "message": str(exc)[:2000],
                       "typeerror": isinstance(exc, TypeError),
                       "valueerror": isinstance(exc, ValueError),
                       "memoryerror": isinstance(exc, MemoryError)}
        res["warnings"] = [f"{type(x.message).__name__}: {x.message}"[:500] for x in w]
        result_file.write_text(json.dumps(res))
        return 0
    from ppamsafety.cli import main
    try:
        rc = main(c.argv)
    except SystemExit as exc:
        rc = exc.code if isinstance(exc.code, int) else 1
    except BaseException:                        # noqa: BLE001
        traceback.print_exc()
        rc = 1
    return rc


def _rss(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def _prepare(c: Case, d: Path) -> None:
    if d.exists():
        _rmtree(d)
    d.mkdir(parents=True)
    if c.setup is not None:
        c.setup(d)
    if c.unprivileged:
        os.chmod(d, 0o777)


def _rmtree(d: Path) -> None:
    if os.geteuid() == 0 and d.exists():
        subprocess.run(["chattr", "-R", "-i", str(d)], capture_output=True)
    for root, dirs, fs in os.walk(d):
        for x in dirs:
            try:
                os.chmod(os.path.join(root, x), 0o755)
            except OSError:
                pass
    shutil.rmtree(d, ignore_errors=True)


#: CPU seconds a command (its whole process group) may spend after Ctrl-C before it counts as
#: a hang: the work it does after being told to stop, whatever the machine's load (a wall-clock
#: grace would blame the command for a busy machine: a compiled 600 s simulation call, which
#: Ctrl-C cannot cut, ends 2-5 s of CPU after it on 2 cores).
INTERRUPT_GRACE = 10.0
#: Wall seconds after Ctrl-C at which a command that still runs (e.g. blocked) counts as a hang.
INTERRUPT_WALL = 120.0


def _group_cpu(pgid: int) -> float:
    """CPU seconds (user + system, with reaped children) of the live processes of a group."""
    total = 0
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open(f"/proc/{d}/stat") as fh:
                stat = fh.read()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2:].split()       # from field 3 (state) on
        if int(fields[2]) == pgid:                         # field 5: the process group
            total += sum(int(x) for x in fields[11:15])    # fields 14-17: utime .. cstime
    return total / os.sysconf("SC_CLK_TCK")


def _wait(pid: int, timeout: float, interrupt: float | None = None, interrupt_on=None,
          err_file: Path | None = None):
    """(status, rusage, verdict_override, peak, seconds from Ctrl-C to exit) of a child,
    killing it on timeout or memory; with ``interrupt``, SIGINT goes to its process group
    after that many seconds (what Ctrl-C in a terminal does); with ``interrupt_on``, as soon
    as ``err_file`` (its stderr) holds that text.  After Ctrl-C it is a hang once its process
    group has spent :data:`INTERRUPT_GRACE` s of CPU or :data:`INTERRUPT_WALL` s have passed."""
    t0 = time.monotonic()
    peak = 0
    t_int = cpu_int = None

    def kill(verdict):
        os.killpg(pid, signal.SIGKILL)
        _, status, ru = os.wait4(pid, 0)
        return status, ru, verdict, peak, None

    while True:
        wpid, status, ru = os.wait4(pid, os.WNOHANG)
        if wpid == pid:
            after = None if t_int is None else time.monotonic() - t_int
            return status, ru, None, max(peak, ru.ru_maxrss * 1024), after
        rss = _rss(pid)
        peak = max(peak, rss)
        now = time.monotonic()
        if rss > MEMORY_KILL:
            return kill("memory")
        due = (interrupt is not None and now - t0 > interrupt) or (
            interrupt_on is not None and err_file is not None and err_file.exists()
            and interrupt_on in err_file.read_text(errors="replace"))
        if t_int is None and due:
            try:
                os.killpg(pid, signal.SIGINT)
            except ProcessLookupError:
                pass
            t_int, cpu_int = now, _group_cpu(pid)
        if t_int is None:
            if now - t0 > timeout:
                return kill("hang")
        elif (now - t_int > INTERRUPT_WALL
              or _group_cpu(pid) - cpu_int > INTERRUPT_GRACE):
            return kill("hang")
        time.sleep(0.02)


def run_case(c: Case, workdir: Path, *, real: bool = False) -> Result:
    d = workdir / re.sub(r"[^A-Za-z0-9_.=-]", "_", f"{c.cls}-{c.name}")[:120]
    _prepare(c, d)
    before = _snapshot(d)
    out_f, err_f, res_f = d.parent / f".{d.name}.out", d.parent / f".{d.name}.err", \
        d.parent / f".{d.name}.json"
    for f in (out_f, err_f, res_f):
        f.unlink(missing_ok=True)
    t0 = time.monotonic()
    if real:
        if c.api is not None:
            cmd = [sys.executable, str(Path(__file__).resolve()), "--child",
                   f"{c.cls}:{c.name}", "--result", str(res_f)]
        else:
            cmd = [sys.executable, "-m", "ppamsafety.cli", *c.argv]
        with open(out_f, "wb") as o, open(err_f, "wb") as e:
            def pre():
                os.setpgid(0, 0)
                signal.signal(signal.SIGINT, signal.SIG_DFL)   # Ctrl-C as in a terminal
                if c.unprivileged:
                    os.setgid(NOBODY)
                    os.setuid(NOBODY)
            p = subprocess.Popen(cmd, cwd=d, stdout=o, stderr=e, preexec_fn=pre)
            status, ru, over, peak, t_exit = _wait(p.pid, c.timeout, c.interrupt, c.interrupt_on, err_f)
            p.returncode = os.waitstatus_to_exitcode(status)
    else:
        sys.stdout.flush()
        sys.stderr.flush()
        pid = os.fork()
        if pid == 0:                               # the child
            rc = 1
            try:
                os.setpgid(0, 0)
                # Ctrl-C raises KeyboardInterrupt, as in a terminal (a battery started in the
                # background inherits SIGINT ignored)
                signal.signal(signal.SIGINT, signal.default_int_handler)
                fo = os.open(out_f, os.O_WRONLY | os.O_CREAT, 0o666)
                fe = os.open(err_f, os.O_WRONLY | os.O_CREAT, 0o666)
                os.dup2(fo, 1)
                os.dup2(fe, 2)
                if c.unprivileged:
                    os.chmod(res_f.parent, 0o777)
                    os.setgid(NOBODY)
                    os.setuid(NOBODY)
                sys.stdout = io.TextIOWrapper(os.fdopen(1, "wb", 0), write_through=True)
                sys.stderr = io.TextIOWrapper(os.fdopen(2, "wb", 0), write_through=True)
                rc = _child_run(c, d, res_f)
            except BaseException:                  # noqa: BLE001
                traceback.print_exc()
            finally:
                try:
                    sys.stdout.flush()
                    sys.stderr.flush()
                finally:
                    os._exit(rc if isinstance(rc, int) and 0 <= rc < 256 else 1)
        status, ru, over, peak, t_exit = _wait(pid, c.timeout, c.interrupt, c.interrupt_on, err_f)
    secs = time.monotonic() - t0
    rc = os.waitstatus_to_exitcode(status) if over is None else None
    out = out_f.read_text(errors="replace") if out_f.exists() else ""
    err = err_f.read_text(errors="replace") if err_f.exists() else ""
    after = _snapshot(d)
    # a user file changed or deleted (the marker of a toolkit output folder is the toolkit's
    # own bookkeeping: a resumed sweep updates it)
    lost = [f for f, h in before.items() if after.get(f) != h
            and Path(f).name != ".ppamsafety-output"]
    peak_mb = peak / 2 ** 20
    if c.api is not None:
        res = json.loads(res_f.read_text()) if (over is None and res_f.exists()) else None
        verdict, msg = _classify_api(c, res, over, err)
    elif c.expect == "interrupt":
        verdict, msg = _classify_interrupt(rc, over, err, t_exit)
    else:
        verdict, msg = _classify_cli(c, rc, over, out, err)
    if lost:
        verdict, msg = "lost", f"user file(s) changed or deleted: {lost}; " + msg
    refused = verdict in ("clear", "vague") and c.expect == "error"
    r = Result(c.name, c.cls, verdict, rc, round(secs, 2), round(peak_mb, 1), msg[:600],
               refused=refused, expect=c.expect)
    for f in (out_f, err_f, res_f):
        f.unlink(missing_ok=True)
    _rmtree(d)
    return r


_RAW_WARNING = re.compile(r"^\S+\.py:\d+: \w*Warning: |^\s*warnings\.warn\(", re.M)


def _names(c: Case, text: str) -> bool:
    low = text.lower()
    return not c.names or any(n.lower() in low for n in c.names)


def _classify_cli(c: Case, rc, over, out: str, err: str):
    if over:
        return over, err[-300:]
    lines = [ln for ln in err.splitlines() if ln.strip()]
    errline = next((ln for ln in lines if "error:" in ln), "")
    if "Traceback (most recent call last)" in err:
        return "traceback", err[-600:]
    if _RAW_WARNING.search(err):
        raw = "noisy"
    else:
        raw = None
    if c.expect == "error":
        if rc == 2:
            if "internal failure" in errline:
                return "exit1", errline
            if raw:
                return raw, err
            return ("clear" if _names(c, errline or err) else "vague"), errline or err
        if rc == 0:
            return "accepted", (out[-300:] + err[-300:])
        if rc == 1:
            return "exit1", errline or err[-300:]
        return "other", f"rc={rc} {err[-300:]}"
    if rc != 0:
        return ("exit1" if rc == 1 else "refused-valid"), errline or err[-300:]
    if raw:
        return raw, err
    if c.expect == "warn":
        warn = [ln for ln in lines if ln.startswith("ppamsafety: warning:")]
        if warn and _names(c, " ".join(warn)):
            return "clear", warn[0]
        return "no-warning", err[-300:]
    return "clear", ""


def _classify_interrupt(rc, over, err, after):
    """Ctrl-C: exit 130 within :data:`INTERRUPT_GRACE` s of CPU with one line, no traceback."""
    if over:
        return over, (f"still running after Ctrl-C ({INTERRUPT_GRACE:g} s of CPU or "
                      f"{INTERRUPT_WALL:g} s); " + err[-300:])
    if "Traceback (most recent call last)" in err:
        return "traceback", err[-600:]
    if after is None:
        return "not-interrupted", f"rc={rc}: finished before Ctrl-C; " + err[-200:]
    if rc == 130 and "ppamsafety: interrupted" in err:
        return "clear", f"exit 130 {after:.1f} s after Ctrl-C"
    return "other", f"rc={rc} {after:.1f} s after Ctrl-C: {err[-300:]}"


def _classify_api(c: Case, res, over, err):
    if over:
        return over, err[-300:]
    if res is None:
        return "crash", err[-600:]
    if c.expect == "error":
        if res["ok"]:
            return "accepted", f"returned {res['result']}; warnings {res['warnings'][:2]}"
        if res.get("memoryerror"):
            return "memory", res["message"]
        if not (res["typeerror"] or res["valueerror"]):
            return "crash", f"{res['type']}: {res['message']}"
        return ("clear" if _names(c, res["message"]) else "vague"), \
            f"{res['type']}: {res['message']}"
    if not res["ok"]:
        return "refused-valid", f"{res['type']}: {res['message']}"
    if c.expect == "warn":
        return ("clear" if any(_names(c, w) for w in res["warnings"]) else "no-warning"), \
            "; ".join(res["warnings"])[:300]
    return "clear", ""


def select(only=None, names=None):
    cs = CASES
    if only:
        want = set(only)
        cs = [c for c in cs if c.cls in want]
    if names:
        cs = [c for c in cs if c.name in names or f"{c.cls}:{c.name}" in names]
    return cs


def run(cases, *, workdir: Path | None = None, real: bool = False, progress: bool = True):
    """Run ``cases``; return the list of :class:`Result`."""
    global BASE
    work = Path(workdir or tempfile.mkdtemp(prefix="ppam-battery-"))
    work.mkdir(parents=True, exist_ok=True)
    os.chmod(work, 0o755)
    BASE = work / "_base"
    make_base(BASE)
    os.environ["PPAMSAFETY_BATTERY_BASE"] = str(BASE)      # for --real children
    if not real:                 # import what the subcommands import, once, before forking
        import ppamsafety.cli  # noqa: F401
        import ppamsafety.data  # noqa: F401
        import ppamsafety.diagnose  # noqa: F401
        import ppamsafety.impact.model  # noqa: F401
        import ppamsafety.study_files  # noqa: F401
    results = []
    for i, c in enumerate(cases):
        r = run_case(c, work, real=real)
        results.append(r)
        if progress:
            flag = "" if r.verdict == "clear" else f"  <-- {r.message[:200]!r}"
            print(f"[{i + 1}/{len(cases)}] {c.cls}:{c.name}: {r.verdict} ({r.seconds:.1f} s, "
                  f"{r.peak_mb:.0f} MB){flag}", flush=True)
    return results


def summary(results) -> str:
    by = {}
    for r in results:
        by.setdefault(r.cls, []).append(r)
    lines = [f"{'class':22s} {'cases':>5s} {'clear':>5s} {'share':>7s}  failures"]
    for cls in sorted(by):
        rs = by[cls]
        ok = sum(r.verdict == "clear" for r in rs)
        bad = {}
        for r in rs:
            if r.verdict != "clear":
                bad[r.verdict] = bad.get(r.verdict, 0) + 1
        lines.append(f"{cls:22s} {len(rs):5d} {ok:5d} {100 * ok / len(rs):6.1f}%  "
                     f"{', '.join(f'{k} {v}' for k, v in sorted(bad.items()))}")
    n = len(results)
    ok = sum(r.verdict == "clear" for r in results)
    inval = [r for r in results if _case_of(r).expect == "error"]
    ok_inval = sum(r.verdict == "clear" for r in inval)
    lines.append(f"{'total':22s} {n:5d} {ok:5d} {100 * ok / max(n, 1):6.1f}%")
    lines.append(f"invalid-input cases: {len(inval)}, clear errors {ok_inval} "
                 f"({100 * ok_inval / max(len(inval), 1):.1f} %)")
    for v in ("hang", "exit1", "traceback", "lost", "memory", "accepted"):
        lines.append(f"  {v:10s} {sum(r.verdict == v for r in results)}")
    refused = [r for r in results if r.refused]
    if refused:
        top = max(refused, key=lambda r: r.peak_mb)
        lines.append(f"largest peak RSS of a refused request: {top.peak_mb:.0f} MB "
                     f"({top.cls}:{top.case})")
    lines.append(f"largest peak RSS of any case: "
                 f"{max(r.peak_mb for r in results):.0f} MB" if results else "")
    return "\n".join(lines)


def _case_of(r: Result) -> Case:
    return next(c for c in CASES if c.name == r.case and c.cls == r.cls)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--only", default=None, help="comma-separated classes")
    ap.add_argument("--names", default=None, help="comma-separated case names")
    ap.add_argument("--real", action="store_true", help="fresh processes (python -m ...)")
    ap.add_argument("--json", default=None, help="write the results here")
    ap.add_argument("--workdir", default=None)
    ap.add_argument("--list", action="store_true")
    ap.add_argument("--child", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--result", default=None, help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.child:
        global BASE
        BASE = Path(os.environ["PPAMSAFETY_BATTERY_BASE"])
        c = next(c for c in CASES if f"{c.cls}:{c.name}" == a.child)
        return _child_run(c, Path.cwd(), Path(a.result))
    cs = select(a.only.split(",") if a.only else None, a.names.split(",") if a.names else None)
    if a.list:
        for c in cs:
            print(f"{c.cls}:{c.name}  {' '.join(map(repr, c.argv)) if c.argv else 'api'}")
        print(len(cs), "cases")
        return 0
    res = run(cs, workdir=Path(a.workdir) if a.workdir else None, real=a.real)
    text = summary(res)
    print("\n" + text)
    bad = [r for r in res if r.verdict != "clear"]
    if bad:
        print("\nnot clear:")
        for r in bad:
            print(f"  {r.cls}:{r.case}: {r.verdict} rc={r.rc} {r.message[:300]!r}")
    if a.json:
        Path(a.json).write_text(json.dumps([r.__dict__ for r in res], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
