"""Command-line interface: ``ppamsafety report``, ``sweep``, ``impact``, ``arm``, ``info`` ...

Every command takes ``--arm FILE`` (an arm file, ``docs/arm_files.md``; default the
thesis arm) and ``--head NAME|FILE`` (a head model name or a head file; default
``thesis-frontal``).  ``ppamsafety arm export`` writes the thesis arm as a template,
``ppamsafety arm check FILE`` validates a file and prints the arm's key numbers.

Exit status
-----------
0
    Success.
2
    Bad usage or input: a wrong option or value, an output folder or file that
    cannot be written without losing user data, a missing file.  A one-line
    ``ppamsafety: error: ...`` message on stderr says what and why.
1
    A failure that is not the user's (a bug): a one-line message asking to
    report it.  Set ``PPAMSAFETY_DEBUG=1`` to see the Python traceback.
130
    Interrupted (Ctrl-C).

No user error ends in a Python traceback.  Output never overwrites a user's
file: see :mod:`ppamsafety.output` and the ``--overwrite`` options.

Negative numbers, also in scientific notation, are accepted as option values
(``--q -1e1 -80``, ``--q=-10 -80``).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import re
import sys
import warnings
from pathlib import Path

import numpy as np

from ._commandline import EXIT_FAILURE, EXIT_OK, EXIT_USAGE
from ._commandline import Parser as _Parser
from ._commandline import _split_multi_value, run_guarded  # noqa: F401  (tests use both)
from ._validation import SEED_MAX, did_you_mean
from ._version import __version__
from .output import atomic_write, check_new_file, inspect_output_folder
from .units import BAR, DEG

# Each subcommand imports the part of the library it runs inside its own function: importing
# all of it costs 3-9 s (numba, scipy, pandas), and `ppamsafety --help` or a usage error should
# answer at once.  These imports run downward (the CLI is the top layer); nothing else in the
# package imports inside a function except to defer a heavy dependency (docs/architecture.md).

_EPILOG = """\
exit status:
  0    success
  2    bad usage or input (message on stderr: "ppamsafety: error: ...")
  1    failure that is not the user's (please report it; PPAMSAFETY_DEBUG=1 shows the traceback)
  130  interrupted

output: a folder is created if missing; a non-empty folder is used only if it is a previous
ppamsafety output (marker file .ppamsafety-output) holding nothing but files ppamsafety wrote,
and is replaced only with --overwrite. An existing file is never overwritten without --overwrite.
"""

#: Defaults of ``synthesize --controller / --reference`` (as diagnose.arm.synthesize).
_SYN_CONTROLLER, _SYN_REFERENCE = "PSMC joint Ki=2 λ=0.4", "circle10"


def _finite(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return v


def _angle_deg(text: str) -> float:
    v = _finite(text)
    if abs(v) > 360.0:
        raise argparse.ArgumentTypeError(
            f"{v:g} deg is outside [-360, 360] deg (link angles are given in degrees)")
    return v


def _positive(text: str) -> float:
    v = _finite(text)
    if v <= 0.0:
        raise argparse.ArgumentTypeError(f"{v:g} is not positive (allowed: > 0)")
    return v


def _positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer (allowed: >= 1)") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"{v} is not positive (allowed: integers >= 1)")
    return v


#: ``impact --dt`` range [s]: :data:`ppamsafety.impact.model.DT_RANGE` (not imported here, so
#: that ``--help`` answers without loading the impact engine; a test keeps them equal).
_DT_RANGE = (1e-8, 1e-3)


def _impact_dt(text: str) -> float:
    v = _finite(text)
    if not _DT_RANGE[0] <= v <= _DT_RANGE[1]:
        raise argparse.ArgumentTypeError(f"{v:g} s is outside [{_DT_RANGE[0]:g}, "
                                         f"{_DT_RANGE[1]:g}] s (the integration step)")
    return v


def _nonnegative(text: str) -> float:
    v = _finite(text)
    if v < 0.0:
        raise argparse.ArgumentTypeError(f"{v:g} is negative (allowed: >= 0)")
    return v


def _seed(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer (a seed is an integer in "
                                         f"[0, 2^63 - 1])") from None
    if not 0 <= v <= SEED_MAX:
        raise argparse.ArgumentTypeError(f"{v} is outside [0, 2^63 - 1] (a seed is a "
                                         f"non-negative integer)")
    return v


def _count(lo: int, hi: int):
    """An argparse type: an integer in [lo, hi]."""
    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not an integer (allowed: {lo} to "
                                             f"{hi})") from None
        if not lo <= v <= hi:
            raise argparse.ArgumentTypeError(f"{v} is outside [{lo}, {hi}]")
        return v
    return parse


def _path(text: str) -> str:
    if not text.strip():
        raise argparse.ArgumentTypeError(f"{text!r} is an empty path")
    if "\0" in text:
        raise argparse.ArgumentTypeError(f"{text!r} holds a NUL character")
    return text


@contextlib.contextmanager
def _options(**names):
    """Errors of the library name its arguments; on the command line they name the options.

    ``with _options(block_seconds="--block"):`` rewrites ``block_seconds`` into ``--block``
    in a ``ValueError``/``TypeError`` raised inside the block, where it is the subject of
    the message (followed by ``=``, ``:``, ``[``, "must", "is", "applies", "has" or
    "gives", and not following another word: "the step experiment: ..." keeps its word),
    not where the same word is prose.
    """
    try:
        yield
    except (ValueError, TypeError, OSError) as exc:
        msg = str(exc)
        new = msg
        for lib, opt in names.items():
            # the argument as the subject of the message ("seed = -1 ...", "seed must ...",
            # "outdir: ..."), not the same word in prose ("the record's experiment")
            new = re.sub(rf"(?<![\w.\[-])(?<!\w ){re.escape(lib)}(?=\s*(=|:|\[|must\b|is\b|"
                         rf"applies\b|has\b|gives\b))", opt, new)
        if new == msg:
            raise
        raise type(exc)(new) if type(exc) in (ValueError, TypeError, OSError) else \
            ValueError(new) from None


@contextlib.contextmanager
def _named(option: str, value):
    """Errors about the file or name given to ``option`` start with the option's name."""
    try:
        yield
    except (ValueError, TypeError, OSError) as exc:
        msg = str(exc)
        if option in msg:
            raise
        raise ValueError(f"{option} {value}: {msg}") from None


def _section_names(text: str) -> list[str]:
    from .sections import REGISTRY

    names = [n.strip() for n in text.split(",")]
    if not any(names):
        raise argparse.ArgumentTypeError(
            f"{text!r} names no report section; give comma-separated names from "
            f"{', '.join(REGISTRY)} (omit --only to run them all)")
    if not all(names):
        raise argparse.ArgumentTypeError(f"{text!r} has an empty name between commas; give "
                                         f"comma-separated section names")
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise argparse.ArgumentTypeError(f"{text!r} names {', '.join(twice)} more than once; "
                                         f"name each section once")
    unknown = [n for n in names if n not in REGISTRY]
    if unknown:
        raise argparse.ArgumentTypeError(
            f"unknown report section(s) {', '.join(map(repr, unknown))}"
            f"{did_you_mean(unknown[0], list(REGISTRY))}; choose from {', '.join(REGISTRY)}")
    return names


def _arm_of(args):
    """The arm of ``--arm FILE`` (None: the thesis arm), loaded and checked; its notes
    (:func:`ppamsafety.design.arm_notes`) go to stderr."""
    if getattr(args, "arm", None) is None:
        return None
    from .design import load_arm

    with _named("--arm", args.arm):
        arm = load_arm(args.arm)
    _print_notes(arm, args.arm)
    return arm


def _print_notes(arm, where, notes=None) -> None:
    """Print the arm's notes (default :func:`ppamsafety.design.arm_notes`) as
    ``ppamsafety: note: <file>: ...`` lines on stderr."""
    from .design import arm_notes

    for note in arm_notes(arm) if notes is None else notes:
        print(f"ppamsafety: note: {where}: {note}", file=sys.stderr)


def _head_of(args):
    """The head model of ``--head NAME|FILE`` (None: not given)."""
    if getattr(args, "head", None) is None:
        return None
    from .impact.head import resolve_head

    with _named("--head", args.head):
        return resolve_head(args.head)


def _head_unused(args, command: str) -> None:
    """Validate a ``--head`` that ``command`` does not use, and say so."""
    if _head_of(args) is not None:
        print(f"ppamsafety: note: --head has no effect on {command} (it computes no impact)",
              file=sys.stderr)


def _cmd_report(args) -> int:
    from .report.build import build_report

    if args.only is not None and (args.include is not None or args.exclude is not None):
        raise ValueError("--only names every section to run; give --include/--exclude "
                         "without it")
    with _options(outdir="--outdir", processes="--processes", include="--include",
                  exclude="--exclude", replace_kind="--replace-other-kind"):
        index = build_report(args.outdir, quick=args.quick, only=args.only,
                             overwrite=args.overwrite, processes=args.processes,
                             replace_kind=args.replace_other_kind, arm=_arm_of(args),
                             head=_head_of(args), include=args.include, exclude=args.exclude)
    print(f"report written to {index}")
    return EXIT_OK


def _cmd_identify(args) -> int:

    from .data import MeasuredDataWarning, identify_measured, load_measured

    if args.kind == "static":
        given = [o for o, v in (("--drop", args.drop is not None), ("--no-friction",
                                                                    args.no_friction),
                                ("--sign-velocity", args.sign_velocity is not None)) if v]
        if given:
            raise ValueError(f"{', '.join(given)}: option(s) of --kind dynamic only (a static "
                             f"identification uses neither friction nor filtered samples)")
    with _options(outdir="--out"):
        inspect_output_folder(args.out, overwrite=args.overwrite, kind="identify",
                              replace_kind=args.replace_other_kind)   # fail before computing
    arm = _arm_of(args)
    _head_unused(args, "identify")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeasuredDataWarning)    # kept in data.notes
        data = load_measured(args.data, allow_gaps=args.allow_gaps,
                             strict_units=not args.loose_units)
    with _options(kind="--kind", method="--method", drop="--drop", confidence="--confidence",
                  sign_velocity="--sign-velocity"):
        ident = identify_measured(data, args.kind, method=args.method,
                                  friction=not args.no_friction,
                                  drop=300 if args.drop is None else args.drop,
                                  confidence=args.confidence, sign_velocity=args.sign_velocity,
                                  arm=arm)
    for note in ident.notes:
        print(f"ppamsafety: warning: {note}", file=sys.stderr)
    with _options(outdir="--out"):
        ident.write(args.out, overwrite=args.overwrite, replace_kind=args.replace_other_kind)
    for name in ident.results:
        r = ident.results[name]
        r = getattr(r, "lsq", r)
        print(f"{name:<8} {r.method}: residual RMS {r.residual_rms:.4g}, "
              f"condition number {r.condition_number:.4g}")
        for n, u, e, se in zip(r.names, r.units, r.estimates, r.std_errors):
            print(f"  {n:<18} {e: .6g} +- {se:.3g} {u}")
    print(f"identification written to {args.out}")
    return EXIT_OK


def _processes(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer (allowed: an integer "
                                         f">= 1)") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"{v} is not allowed (allowed: an integer >= 1)")
    return v


def _cmd_sweep(args) -> int:
    from .study_files import (check_run_size, describe_estimate, load_study,
                              run_study_file)

    if args.scheduler is not None and args.backend != "dask":
        raise ValueError(f"--scheduler {args.scheduler} needs --backend dask")
    if args.resume and args.overwrite:
        raise ValueError("--resume and --overwrite exclude each other: --resume continues the "
                         "sweep in --out, --overwrite recomputes it from scratch")
    arm = _arm_of(args)
    study = load_study(args.study, arm=arm, head=_head_of(args))   # checked first
    if arm is None and study.arm is not None:       # the study file's own [arm] file
        _print_notes(study.arm, f"{args.study} [arm]")
    n = len(study.cases) if args.max_cases is None else min(args.max_cases, len(study.cases))
    est = study.estimate(processes=args.processes, max_cases=n)
    with _options(max_cases="--max-cases", confirm="--yes"):           # refused before it runs
        check_run_size(study, est, confirm=args.yes or args.scheduler is not None)
    what = (f"envelope of {study.envelope['parameter']} ({study.envelope['limit']})"
            if study.envelope else describe_estimate(est))
    print(f"study {study.name!r}: {what}"
          f"{f' (first {n:,} of {len(study.cases):,})' if n < len(study.cases) else ''} on "
          f"{args.backend}{' (' + args.scheduler + ')' if args.scheduler else ''} -> {args.out}",
          flush=True)
    print(f"experiment reference: {study.references_text()}", flush=True)
    with _options(outdir="--out", max_cases="--max-cases", processes="--processes",
                  scheduler="--scheduler", confirm="--yes", replace_kind="--replace-other-kind"):
        df = run_study_file(study, args.out, backend=args.backend, scheduler=args.scheduler,
                            processes=args.processes, resume=args.resume,
                            overwrite=args.overwrite, max_cases=args.max_cases,
                            progress=not args.no_progress, confirm=args.yes,
                            replace_kind=args.replace_other_kind).table
    for line in df.attrs.get("envelope_lines", ()):
        print(line)
    failed = int((df["status"] == "failed").sum()) if "status" in df.columns else 0
    print(f"results written to {args.out}/{study.csv} ({len(df) - failed} ok, {failed} failed); "
          f"summary: {args.out}/summary.html")
    if failed and failed == len(df):
        errors = df["error"].astype(str).value_counts()
        top = "; ".join(f"{c} x {e}" for e, c in errors.head(3).items())
        more = f" (and {len(errors) - 3} other errors)" if len(errors) > 3 else ""
        print(f"ppamsafety: error: every case of the sweep failed ({failed} of {len(df)}): "
              f"{' '.join(top.split())}{more}; see the 'error' column of {args.out}/{study.csv}",
              file=sys.stderr)
        user = all(e.split(":", 1)[0] in ("ValueError", "TypeError", "StudyFileError",
                                          "OutputError") for e in errors.index)
        return EXIT_USAGE if user else EXIT_FAILURE
    if failed:
        print(f"ppamsafety: warning: {failed} of {len(df)} case(s) failed; their rows have "
              f"status='failed' and the error", file=sys.stderr)
    return EXIT_OK


def _cmd_diagnose(args) -> int:

    from .data import MeasuredDataWarning, load_campaign, load_measured
    from .diagnose import diagnose, other_arm

    with _options(outdir="--out"):
        inspect_output_folder(args.out, overwrite=args.overwrite, kind="diagnose",
                              replace_kind=args.replace_other_kind)   # fail before computing
    arm = _arm_of(args)
    _head_unused(args, "diagnose")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeasuredDataWarning)    # printed below, one line each
        if str(args.data).lower().endswith(".toml"):            # a bench campaign manifest
            given = [o for o, v in (("--allow-gaps", args.allow_gaps),
                                    ("--loose-units", args.loose_units)) if v]
            if given:
                raise ValueError(f"{', '.join(given)}: option(s) of a measured data file, not of "
                                 f"a campaign manifest ({args.data}): its import profile says "
                                 f"how the records are read")
            data = load_campaign(args.data)
        else:
            data = load_measured(args.data, allow_gaps=args.allow_gaps,
                                 strict_units=not args.loose_units)
    for note in getattr(data, "notes", ()):
        print(f"ppamsafety: warning: {note}", file=sys.stderr)
    if getattr(data, "kind", "actuator") == "actuator":       # a campaign or a bench record
        given = [o for o, v in (("--block", args.block), ("--seed", args.seed),
                                ("--bootstrap", args.bootstrap),
                                ("--stability", args.stability)) if v is not None]
        if given:
            raise ValueError(f"{', '.join(given)}: option(s) of an arm record; {args.data} is a "
                             f"test-bench (actuator) record, diagnosed against its nominal force "
                             f"law without them")
    if getattr(data, "kind", "") == "arm" and "arm" not in getattr(data, "meta", {"arm": 0}):
        from .diagnose import assumed_arm_note
        from .params import thesis_arm

        note = assumed_arm_note(thesis_arm() if arm is None else arm, given=arm is not None)
        print(f"ppamsafety: note: {args.data}: {note.removeprefix('arm: ')}", file=sys.stderr)
    mismatch = other_arm(data, arm)
    if mismatch is not None and not args.allow_other_arm:
        # refused before computing: a forgotten --arm would name every difference between
        # the two arms as a missing effect
        raise ValueError(f"{args.data}: {mismatch}; give the record's arm file with --arm FILE "
                         f"(the file whose fingerprint starts "
                         f"{data.meta['arm']['sha256'][:16]}: `ppamsafety arm check FILE` prints "
                         f"it), or --allow-other-arm to compare the two arms on purpose")
    if args.allow_other_arm and mismatch is None:
        raise ValueError(f"--allow-other-arm: {args.data} names no other arm than the one it is "
                         f"diagnosed against; leave it out")
    with _options(experiment="--experiment", alpha="--alpha", rho_max="--rho-max",
                  block_seconds="--block", seed="--seed", bootstrap="--bootstrap",
                  stability="--stability", arm="--arm"):
        dg = diagnose(data, experiment=args.experiment, alpha=args.alpha, rho_max=args.rho_max,
                      block_seconds=0.05 if args.block is None else args.block,
                      seed=0 if args.seed is None else args.seed, bootstrap=args.bootstrap,
                      stability=args.stability, arm=arm, allow_other_arm=args.allow_other_arm)
    for w in dg.warnings:
        print(f"ppamsafety: warning: {w}", file=sys.stderr)
    with _options(outdir="--out"):
        dg.write(args.out, overwrite=args.overwrite, replace_kind=args.replace_other_kind)
    for w in dg.warnings:
        print(f"WARNING: {w}")
    for e in dg.effects:
        ps = ", ".join(f"{n} = {p.value:.4g} [{p.ci_low:.4g}, {p.ci_high:.4g}] "
                       f"{p.unit} (declared {p.nominal:.4g})"
                       for n, p in e.parameters.items())
        print(f"effect {e.name} ({e.confidence_text()}): {ps}")
    if not dg.effects:
        print("no effect named")
    print(f"unexplained: {'yes (' + ', '.join(dg.unexplained_channels) + ')' if dg.unexplained else 'no'}")
    print(f"diagnosis written to {args.out} ({dg.timings['total']:.1f} s)")
    return EXIT_OK


def _float_list(text: str):
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected comma-separated numbers") from None
    return vals


def _effect_arg(text: str):
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"{text!r}: expected NAME=VALUE (e.g. "
                                         f"payload_mass=0.4, valve_gain_factor=0.8,0.8,1,1)")
    name, value = (x.strip() for x in text.split("=", 1))
    if not name:
        raise argparse.ArgumentTypeError(f"{text!r}: the effect NAME before '=' is empty")
    if not value:
        raise argparse.ArgumentTypeError(f"{text!r}: effect {name} has no VALUE after '=' "
                                         f"(a number, or comma-separated numbers)")
    return name, value


#: A ``--effect`` VALUE with a unit: numbers (comma-separated) and then the unit.
_VALUE_UNIT = re.compile(r"^\s*([-+0-9.eE]+(?:\s*,\s*[-+0-9.eE]+)*)\s*([^\s\d,.+-].*?)\s*$")


def _effect_value(kind: str, name: str, value: str) -> str:
    """``value`` of ``--effect NAME=VALUE`` in SI: a unit after the number(s) is converted by
    :func:`ppamsafety.units.si_factor` (``payload_mass=400g`` is 0.4 kg)."""
    from .units import si_factor

    m = _VALUE_UNIT.match(value)
    if m is None:
        return value
    from .diagnose import effect_unit

    numbers, unit = m.groups()
    si = effect_unit(kind, name)
    if si is None:
        return value                    # an unknown effect: refused by name below
    if si == "-":
        raise ValueError(f"--effect {name}={value}: {name} is a plain number (no unit); "
                         f"give e.g. {name}={numbers}")
    factor = si_factor(unit, si, name=f"--effect {name}={value}: the unit")
    return ",".join(repr(float(x) * factor) for x in numbers.split(","))


def _check_effect(kind: str, arm, name: str, value: str, written: str) -> None:
    """Refuse a bad ``--effect NAME=VALUE`` (``value`` in SI, ``written`` as given) naming
    ``--effect``, the value as written and the unit."""
    from .diagnose import check_effect, effect_unit

    try:
        check_effect(kind, name, value, arm=arm)
    except (TypeError, ValueError) as exc:
        si = effect_unit(kind, name)
        unit = ("" if si is None else f"; {name} is a plain number" if si == "-" else
                f"; {name} is a number in {si} (or with its unit after it, e.g. "
                f"{name}=1{si.replace(' ', '')})")
        raise ValueError(f"--effect {name}={written}: {exc}{unit}") from None


def _cmd_synthesize(args) -> int:
    from .data.measured import check_save_path
    from .diagnose import synthesize

    with _options(path="--out", **{"measured data file": "--out"}):
        check_save_path(args.out, overwrite=args.overwrite)      # fail before simulating
    arm = _arm_of(args)
    effects = {}
    kind = "actuator" if args.kind == "actuator" else "arm"
    for name, value in args.effect or []:       # values are parsed (and named) by synthesize
        if name in effects:
            raise ValueError(f"--effect {name} is given twice ({name}={effects[name]} and "
                             f"{name}={value}); give each effect once")
        effects[name] = _effect_value(kind, name, value)
        _check_effect(kind, arm, name, effects[name], value)
    tester = ("protocol", "pressures", "cycles", "period", "sample_rate", "force_law", "jitter")
    names = {"experiment": "--experiment", "noise": "--noise", "seed": "--seed",
             "duration": "--duration", "controller": "--controller", "reference": "--reference",
             **{k: f"--{k.replace('_', '-')}" for k in tester}}
    _head_unused(args, "synthesize")
    if args.kind == "actuator":
        if arm is not None:
            raise ValueError("--arm describes an arm; --kind actuator takes the muscle law with "
                             "--force-law")
        if args.duration is not None:
            raise ValueError("--duration is an arm option; for --kind actuator use --cycles, "
                             "--period and --sample-rate")
        opts = {k: getattr(args, k) for k in tester if getattr(args, k) is not None}
        with _options(**names):
            data = synthesize(args.experiment, effects, noise=args.noise, seed=args.seed,
                              kind="actuator", position=args.position, **opts)
    else:
        extra = [f"--{k.replace('_', '-')}" for k in tester if getattr(args, k) is not None]
        if args.position:
            extra.append("--position")
        if extra:
            raise ValueError(f"{', '.join(extra)}: option(s) of --kind actuator only")
        if (args.experiment or "open-loop") != "closed-loop":
            given = [o for o, v, d in (("--controller", args.controller, _SYN_CONTROLLER),
                                       ("--reference", args.reference, _SYN_REFERENCE))
                     if v != d]
            if given:
                raise ValueError(f"{', '.join(given)}: option(s) of --experiment closed-loop "
                                 f"only, not of {args.experiment or 'open-loop'}")
        with _options(**names):
            data = synthesize(args.experiment, effects, noise=args.noise, seed=args.seed,
                              duration=args.duration, controller=args.controller,
                              reference=args.reference, arm=arm)
    with _options(**{"measured data file": "--out"}):
        path = data.save(args.out, overwrite=args.overwrite)
    print(f"record written to {path} ({len(data)} rows)")
    if args.kind != "actuator":
        _print_synthesized(args, arm)
    return EXIT_OK


def _print_synthesized(args, arm) -> None:
    """What an arm record was made with: the experiment's reference and the noise."""
    from .diagnose import noise_variances
    from .experiments.trajectories import experiment_references
    from .params import thesis_arm

    a = thesis_arm() if arm is None else arm
    exp = args.experiment or "open-loop"
    refs = experiment_references(a)
    if exp == "closed-loop":
        which = "step" if args.reference == "step" else "circle"
        print(f"reference: {args.reference}: {refs.describe(which)}")
    elif exp == "static-sawtooth":
        print(f"reference: {refs.describe('sawtooth')}")
    noise = args.noise or "arm"
    var = noise_variances(a, noise)
    origin = "the arm's [sensors]" if noise == "arm" else "thesis Table 3.2"
    print("noise: none" if var is None else
          f"noise: {noise}: q {list(var[0])} rad^2, qd {list(var[1])} rad^2/s^2 ({origin}), "
          f"p 500 Pa standard deviation")


def _cmd_impact(args) -> int:
    from .impact.verdicts import check_head_for_region
    from .params.iso_ts_15066 import resolve_region
    from .params import thesis_arm

    if args.history is not None:        # fail before simulating, not after
        check_new_file(args.history, overwrite=args.overwrite, name="--history")
    arm = _arm_of(args) or thesis_arm()
    chosen = _head_of(args)             # None: no --head given
    with _named("--region", args.region):
        region = resolve_region(args.region)
    try:
        check_head_for_region(region, chosen)
    except ValueError as exc:
        raise ValueError(f"--head {args.head} --region {args.region}: {exc}") from None
    q = np.array(args.q, dtype=float) * DEG
    with warnings.catch_warnings():
        if _pose_outside(args.q, arm):  # said once, in degrees, instead of the library's warning
            warnings.filterwarnings("ignore", message=r"q: case\(s\)")
        return _impact(args, arm, chosen, region, q)


def _pose_outside(q_deg, arm) -> bool:
    """Warn when ``--q`` (degrees) lies outside the arm's working area by more than the impact
    model's margin, with the hint "looks like radians" when the numbers read as radians lie
    inside it; True when it warned."""
    from .impact.model import ANGLE_MARGIN

    g = arm.geometry
    lo, hi = np.array([g.q1_min, g.q2_min]), np.array([g.q1_max, g.q2_max])
    given = np.array(q_deg, dtype=float)
    if np.all((given * DEG >= lo - ANGLE_MARGIN) & (given * DEG <= hi + ANGLE_MARGIN)):
        return False
    area = (f"the working area q1 in [{g.q1_min / DEG:.0f}, {g.q1_max / DEG:.0f}] deg, q2 in "
            f"[{g.q2_min / DEG:.0f}, {g.q2_max / DEG:.0f}] deg")
    hint = ""
    if np.all((given >= lo) & (given <= hi)):
        deg = np.degrees(given)
        hint = (f"; looks like radians: --q takes degrees, did you mean --q {deg[0]:.4g} "
                f"{deg[1]:.4g} (inside the working area)?")
    warnings.warn(f"--q {given[0]:g} {given[1]:g} deg lies outside {area} (by more than "
                  f"{ANGLE_MARGIN / DEG:g} deg); the impact model is still evaluated{hint}",
                  UserWarning, stacklevel=2)
    return True


def _impact(args, arm, chosen, region, q) -> int:
    """``impact`` once the arm, the head chosen by ``--head`` (None: none given), the region
    and the pose are read."""
    from .design import rest_stiffness
    from .impact.model import simulate_impacts
    from .impact.verdicts import impact_verdicts, region_head
    from .params import is_thesis_arm

    with _options(q="--q", qd="--qd", stiffness="--stiffness", head="--head", dt="--dt"):
        if args.stiffness is None:      # the arm's own stiffness at rest in this pose
            rest = rest_stiffness(arm, q)
            stiffness = rest.stiffness
            origin = ("the arm's own at rest in this pose: (2.18) with the static pressures "
                      + ", ".join(f"{v / BAR:.3f}" for v in rest.pressures) + " bar"
                      + ("" if rest.holdable else ", clipped to [0, max_pressure]: the arm "
                                                  "cannot hold this pose"))
        else:
            stiffness, origin = tuple(args.stiffness), "given by --stiffness"
    if args.contact is not None or args.covering is not None:
        return _impact_at_point(args, arm, region, q, stiffness, origin)
    body = region_head(region, chosen)  # the region's own body (a head region: the head model)
    with _options(q="--q", qd="--qd", stiffness="--stiffness", head="--head", dt="--dt"):
        res = simulate_impacts(arm, q, args.qd, stiffness, head=body, dt=args.dt,
                               history=args.history is not None)
    s = res.summary.iloc[0]
    what = "the head" if region.head else f"the {region.name}"
    if not s.tcp_speed >= 1e-3:
        raise ValueError(f"--qd {args.qd[0]:g} {args.qd[1]:g} rad/s at --q {args.q[0]:g} "
                         f"{args.q[1]:g} deg gives a tool speed of {s.tcp_speed:.3g} m/s: the "
                         f"arm does not move, so nothing hits {what}; give joint speeds "
                         f"(e.g. --qd 1 0)")
    h = res.head
    print(f"arm             {arm.name or args.arm}")
    print(f"pose            q = {args.q[0]:g}, {args.q[1]:g} deg, qd = {args.qd[0]:g}, "
          f"{args.qd[1]:g} rad/s")
    print(f"joint stiffness K1 = {stiffness[0]:.4g}, K2 = {stiffness[1]:.4g} N m/rad ({origin})")
    if region.head:
        print(f"head model      {h.name}: m = {h.mass:g} kg, R = {h.radius:g} m, Hunt-Crossley "
              f"k = {h.stiffness:.4g} N/m^n, n = {h.exponent:g}, lambda = {h.damping:.4g} "
              f"N s/m^(n+1)")
        if chosen is None:
            print(f"                no --head: the thesis' head, a contact fitted to the "
                  f"thesis arm's Table 6.1 impacts (that arm's surface and the head lumped)"
                  f"{'' if is_thesis_arm(arm) else ', not to this arm'}; the head validated on "
                  f"its own (Hybrid III drop) is --contact 'tool point'; --head chooses another")
    else:
        print(f"body model      {h.name}: the ISO/TS 15066 Annex A body model of "
              f"{region.name}, m_H = {h.mass:g} kg, linear spring K = "
              f"{h.stiffness / 1e3:g} N/mm, undamped (Table A.3)")
    print(f"tool speed      {s.tcp_speed:.4g} m/s")
    print(f"F_max           {s.F_max:.4g} N at {1e3 * s.t_Fmax:.3g} ms")
    if region.head:
        print(f"HIC36           {s.HIC36:.4g}  window [{1e3 * s.HIC36_t1:.3g}, "
              f"{1e3 * s.HIC36_t2:.3g}] ms")
        print(f"HIC15           {s.HIC15:.4g}  window [{1e3 * s.HIC15_t1:.3g}, "
              f"{1e3 * s.HIC15_t2:.3g}] ms")
        print(f"max penetration {1e3 * s.delta_max:.4g} mm, peak head acceleration "
              f"{s.a_max_g:.4g} g")
        print(f"energy to head  {s.E_head_final:.4g} J of {s.E_initial:.4g} J")
    else:
        print(f"max compression {1e3 * s.delta_max:.4g} mm (HIC and the AIS risk are head "
              f"criteria: not judged for {region.name})")
        print(f"energy to body  {s.E_head_final:.4g} J of {s.E_initial:.4g} J")
    verdicts = impact_verdicts(arm, q, args.qd, stiffness, head=chosen, dt=args.dt,
                               region=region)
    for line in verdicts.lines():
        print(line)
    if args.history is not None:
        from .impact.engine import HIST
        from .results import layout_units, with_units

        hist = with_units(res.histories[0], layout_units(HIST))
        atomic_write(args.history, lambda tmp: hist.to_csv(tmp, index=False),
                     overwrite=args.overwrite, name="--history")
        print(f"time history written to {args.history}")
    return EXIT_OK


def _layers_text(layers) -> str:
    """One phrase per layer: name, law and its numbers (SI)."""
    out = []
    for lay in layers:
        if lay.law == "power":
            law = f"k = {lay.stiffness:.4g} N/m^{lay.exponent:g}, b = {lay.damping:.4g}"
        else:
            law = f"E = {lay.modulus / 1e6:.4g} MPa" + (
                f", {1e3 * lay.thickness:.4g} mm" if math.isfinite(lay.thickness) else "")
            if lay.hysteresis:
                law += f", alpha = {lay.hysteresis:g} s/m"
        out.append(f"{lay.name} ({lay.law}: {law})")
    return "; ".join(out)


def _lumped_spring(body) -> bool:
    """The body is one linear undamped spring (an Annex A body model, no material law)."""
    return (len(body.layers) == 1 and body.layers[0].law == "power"
            and body.layers[0].exponent == 1.0)


def _impact_at_point(args, arm, region, q, stiffness, origin) -> int:
    """``impact --contact POINT --covering NAME|FILE``: one impact of any contact point through
    a covering into the body region, judged against the region's limits."""
    from .impact.anywhere import simulate_contacts
    from .impact.summary import body_model_name, region_body
    from .impact.verdicts import Verdicts, ais_risk_table, annex_a_head, criteria_for, evaluate
    from .params.contact import covering_notes
    from .params.contact_files import resolve_contact_point, resolve_covering

    with _named("--contact", args.contact):
        point = resolve_contact_point("tool point" if args.contact is None else args.contact,
                                      arm)
    cov = None
    if args.covering is not None:
        with _named("--covering", args.covering):
            cov = resolve_covering(args.covering)
    for note in covering_notes(point.covering if cov is None else cov):
        print(f"ppamsafety: note: {args.covering if cov is not None else args.contact}: {note}",
              file=sys.stderr)
    head = _head_of(args)
    body = region_body(region, head=head)
    model = body_model_name(region, head=head)
    with _options(q="--q", qd="--qd", stiffness="--stiffness", dt="--dt", point="--contact",
                  covering="--covering"):
        res = simulate_contacts(arm, q, args.qd, stiffness, point=point, body=body,
                                covering=cov, dt=args.dt, history=args.history is not None)
    s = res.summary.iloc[0]
    if not s.point_speed >= 1e-3:
        raise ValueError(f"--qd {args.qd[0]:g} {args.qd[1]:g} rad/s at --q {args.q[0]:g} "
                         f"{args.q[1]:g} deg gives the {point.name} a speed of "
                         f"{s.point_speed:.3g} m/s: it does not move, so nothing is hit; give "
                         f"joint speeds that move it")
    c = res.contact
    print(f"arm             {arm.name or args.arm}")
    print(f"pose            q = {args.q[0]:g}, {args.q[1]:g} deg, qd = {args.qd[0]:g}, "
          f"{args.qd[1]:g} rad/s")
    print(f"joint stiffness K1 = {stiffness[0]:.4g}, K2 = {stiffness[1]:.4g} N m/rad ({origin})")
    radius = "" if point.shape == "flat" else f", radius {1e3 * point.radius:.4g} mm"
    print(f"contact point   {point.name}: link {point.link} at {1e3 * point.position:.4g} mm, "
          f"{point.shape}{radius}")
    print(f"covering        {c.covering.name}"
          + (f": {_layers_text(c.covering.layers)}" if c.covering.layers else ""))
    kind = "Annex A two-body model " if model == annex_a_head(region).name else ""
    print(f"body region     {region.name} ({kind}{model}): m = {body.mass:g} kg, R = {1e3 * body.radius:.4g} mm, "
          f"{_layers_text(body.layers)}")
    print(f"point speed     {s.point_speed:.4g} m/s (effective mass {s.m_eff:.4g} kg)")
    print(f"F_max           {s.F_max:.4g} N at {1e3 * s.t_Fmax:.3g} ms")
    if region.head:
        print(f"HIC36           {s.HIC36:.4g}, HIC15 {s.HIC15:.4g}")
    if math.isfinite(s.p_max):
        print(f"p_max           {s.p_max / 1e4:.4g} N/cm^2 (mean pressure over the contact area)")
        if _lumped_spring(body) and not c.covering.layers:
            print(f"                the Annex A spring is the whole region's compliance: its "
                  f"footprint gives p = K / (pi R_e), the same at every speed, a lower bound "
                  f"of the mean pressure (docs/impact_models.md)")
    print(f"max compression {1e3 * s.delta_max:.4g} mm, peak body acceleration "
          f"{s.a_max_g:.4g} g" + ("" if region.head else f" (HIC and the AIS risk are head "
                                                       f"criteria: not judged for {region.name})"))
    if c.covering.layers:
        print(f"covering use    {s.covering_use:.2f} of its strain limit"
              + (": THE COVERING BOTTOMS OUT (compressed to its strain limit, it passes the "
                 "force on as a rigid layer; a thicker or stiffer covering, or a lower speed, "
                 "keeps it within its limit)" if s.covering_use >= 1.0 else ""))
    vals = {"F_max": float(s.F_max), "HIC36": float(s.HIC36), "HIC15": float(s.HIC15)}
    if math.isfinite(s.p_max):          # a contact geometry with an area: its pressure judged
        vals["p_max"] = float(s.p_max)
    table = evaluate(vals, criteria_for(region), head=model, contact_point=point.name,
                     region=region.name)
    risk = ais_risk_table(vals["HIC15"], head=model, hic_name="HIC15") if region.head \
        else None
    for line in (Verdicts(table) if risk is None else Verdicts(table, risk)).lines():
        print(line)
    if args.history is not None:
        from .impact.points import PHIST
        from .results import layout_units, with_units

        hist = res.histories[0].copy()
        nc = len(c.covering.layers)
        if nc:              # each sample's compression of the covering over its limit
            lim = c.table()["limit"].to_numpy()[:nc]
            hist["covering_use"] = np.max(
                [hist[f"delta{i + 1}"].clip(lower=0.0) / lim[i] for i in range(nc)], axis=0)
        hist = with_units(hist, {**layout_units(PHIST), "covering_use": "-"})
        atomic_write(args.history, lambda tmp: hist.to_csv(tmp, index=False),
                     overwrite=args.overwrite, name="--history")
        print(f"time history written to {args.history}")
    return EXIT_OK


def _cmd_info(args) -> int:
    from .impact.head import head_model
    from .params import is_thesis_arm, thesis_arm
    from .params.arm_file import arm_fingerprint

    arm = _arm_of(args) or thesis_arm()
    head = _head_of(args) or head_model()          # both checked before anything is printed
    L = arm.links
    label = arm.name or "unnamed arm"
    print(f"{label}{' (the thesis arm)' if is_thesis_arm(arm) else ''} (plant):")
    print(f"  link masses m1 = {L.m1:.3f} kg, m2 = {L.m2:.3f} kg")
    print("  mean pressures p_m = " + ", ".join(f"{p / BAR:.4g}" for p in arm.pneumatics.p_mean)
          + " bar")
    print("  valve time constants = "
          + ", ".join(f"{1e3 * v.time_constant:.4g}" for v in arm.valves.valves) + " ms")
    print(f"  muscles per group = {[g.n_muscles for g in arm.muscles.groups]}")
    print(f"  effects on: {', '.join(arm.effects.enabled()) or 'none'}")
    print(f"  fingerprint (sha256 of its arm file) {arm_fingerprint(arm)}")
    for part, text in arm.sources:
        print(f"  source [{part}]: {text}")
    print(f"head model {head.name!r}: m = {head.mass:g} kg, R = {head.radius:g} m, "
          f"k = {head.stiffness:.4g} N/m^n, n = {head.exponent:g}, "
          f"lambda = {head.damping:.4g} N s/m^(n+1)")
    if head.source:
        print(f"  source: {head.source}")
    if args.head is not None:          # a head the user asked about: compute its checks
        from .impact.head_fit import head_checks

        for r in head_checks(head).itertuples(index=False):
            claim = "" if r.claimed is None else (
                f"; claimed {'met' if r.claimed else 'not met'}"
                f"{'' if r.claim_holds else ' -- THE CLAIM IS WRONG'}")
            print(f"  check {r.check}: {r.value} (target {r.target}): "
                  f"{'met' if r.met else 'not met'}{claim}")
    else:
        for name, met, note in head.checks:
            print(f"  check {name}: claimed {'met' if met else 'not met'} ({note})")
    return EXIT_OK


def _cmd_arm_export(args) -> int:
    from .params import thesis_arm
    from .params.arm_file import arm_to_toml

    if Path(args.out).suffix.lower() != ".toml":
        raise ValueError(f"--out {args.out!r}: an arm file is TOML; give a name ending in .toml "
                         f"(e.g. my_arm.toml)")
    arm = _arm_of(args) or thesis_arm()
    _head_unused(args, "arm export")
    text = arm_to_toml(arm, comments=True)
    atomic_write(args.out, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"),
                 overwrite=args.overwrite, name="--out")
    print(f"arm file written to {args.out} ({arm.name or 'unnamed arm'}); edit it, then run "
          f"`ppamsafety arm check {args.out}`")
    return EXIT_OK


THESIS_TWIN = ", the thesis arm's parameters"


def _cmd_arm_check(args) -> int:
    from .design import arm_notes, arm_summary, load_arm
    from .params import is_thesis_arm
    from .params.arm_file import arm_fingerprint

    arm = load_arm(args.file)
    q = None if args.q is None else np.array(args.q, dtype=float) * DEG
    summary = arm_summary(arm, q=q)
    notes = arm_notes(arm)
    n = len(notes)
    print(f"{args.file}: valid arm file ({arm.name or 'unnamed arm'}"
          f"{THESIS_TWIN if is_thesis_arm(arm) else ''}; sha256 "
          f"{arm_fingerprint(arm)[:16]}"
          f"{f'; {n} note' + ('s' if n > 1 else '') + ' on stderr' if n else ''})")
    print("\n".join(summary.lines()))
    _print_notes(arm, args.file, notes)
    if not summary.pose_holdable:
        print("ppamsafety: warning: the static pressures at the stiffness pose leave "
              "[0, max_pressure]: the Delta-p approach cannot hold the arm there with these "
              "mean pressures", file=sys.stderr)
    return EXIT_OK


def _add_arm_head(p, *, head_used: bool = True) -> None:
    """The ``--arm FILE`` and ``--head NAME|FILE`` options every command takes."""
    p.add_argument("--arm", type=_path, default=None, metavar="FILE",
                   help="arm file (TOML, docs/arm_files.md; default: the thesis arm; "
                        "`ppamsafety arm export` writes a template)")
    p.add_argument("--head", type=_path, default=None, metavar="NAME|FILE",
                   help="head model: a name (thesis-frontal, iso15066-forehead, iso15066-face, "
                        "child-frontal) or a head file (TOML)"
                        + ("" if head_used else "; this command computes no impact, so it is "
                                                "only validated"))


def build_parser() -> argparse.ArgumentParser:
    """The argparse parser of the ``ppamsafety`` command."""
    p = _Parser(
        prog="ppamsafety",
        description="Safety and impact analysis of a 2-DOF arm driven by pleated pneumatic "
                    "artificial muscles (PPAMs).",
        epilog=_EPILOG)
    p.add_argument("--version", action="version", version=f"ppamsafety {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("report", help="regenerate the report folder from scratch", epilog=_EPILOG)
    r.add_argument("--outdir", type=_path, default="reports",
                   help="output folder (default: reports)")
    r.add_argument("--quick", action="store_true", help="coarse grids and short sweeps")
    r.add_argument("--only", type=_section_names, default=None, metavar="NAMES",
                   help="comma-separated report section names to run, and no other (default: "
                        "every section that concerns the arm: all of them for the thesis arm)")
    r.add_argument("--include", type=_section_names, default=None, metavar="NAMES",
                   help="sections to add to the arm's default selection (e.g. "
                        "cylinder_friction, the bench case study, which is left out of the "
                        "report for another arm)")
    r.add_argument("--exclude", type=_section_names, default=None, metavar="NAMES",
                   help="sections to leave out of the default selection")
    r.add_argument("--overwrite", action="store_true",
                   help="replace a previous ppamsafety report in OUTDIR (never other files)")
    r.add_argument("--replace-other-kind", action="store_true",
                   help="with --overwrite: also replace a ppamsafety output of another kind")
    r.add_argument("--processes", type=_positive_int, default=None, metavar="N",
                   help="sections run at the same time in worker processes (default: every "
                        "core; 1: one after the other in this process)")
    _add_arm_head(r)
    r.set_defaults(func=_cmd_report)
    d = sub.add_parser("identify", help="identify parameters from a measured data file",
                       description="Identify parameters from a measured record (format: "
                                   "docs/measured_data.md). static: gravity parameters from "
                                   "equilibria, valve models, or an actuator's muscle law; "
                                   "dynamic: base parameters from an open/closed-loop record.",
                       epilog=_EPILOG)
    d.add_argument("data", type=_path, metavar="DATA",
                   help="measured data file (.csv or .parquet)")
    d.add_argument("--kind", choices=("static", "dynamic"), required=True,
                   help="static or dynamic identification")
    d.add_argument("--out", type=_path, required=True, metavar="DIR",
                   help="output folder for identification.json/.csv/.png")
    d.add_argument("--method", choices=("LS", "WLS"), default="LS",
                   help="ordinary or two-step per-joint weighted least squares (default LS)")
    d.add_argument("--no-friction", action="store_true",
                   help="dynamic: model without Coulomb and viscous friction (6 parameters)")
    d.add_argument("--drop", type=_count(0, 10 ** 7), default=None, metavar="R",
                   help="dynamic: filtered samples dropped per segment (default 300, thesis B.7)")
    d.add_argument("--sign-velocity", type=_positive, default=None, metavar="V",
                   help="dynamic: Coulomb columns tanh(qd/V) [rad/s] instead of sgn(qd)")
    d.add_argument("--confidence", type=_finite, default=0.95,
                   help="confidence level of the intervals, in (0, 1) (default 0.95)")
    d.add_argument("--allow-gaps", action="store_true",
                   help="drop rows with missing values and split the record at time gaps")
    d.add_argument("--loose-units", action="store_true",
                   help="only warn when values look like bar, degrees or mm")
    d.add_argument("--overwrite", action="store_true",
                   help="replace a previous ppamsafety identification in DIR (never other files)")
    _add_arm_head(d, head_used=False)
    d.add_argument("--replace-other-kind", action="store_true",
                   help="with --overwrite: also replace a ppamsafety output of another kind")
    d.set_defaults(func=_cmd_identify)
    w = sub.add_parser("sweep", help="run a study file (TOML): a safety sweep into a folder",
                       epilog=_EPILOG + """
sweep folder: --resume reuses the finished cases of an interrupted sweep in OUT (allowed
without --overwrite when OUT holds a previous sweep); --overwrite recomputes everything.
""")
    w.add_argument("study", type=_path, metavar="STUDY",
                   help="study file (TOML), or the name of a study shipped with the "
                        "package (the report's: an unknown name lists them)")
    w.add_argument("--out", type=_path, required=True, metavar="DIR", help="output folder")
    w.add_argument("--backend", choices=("local", "dask"), default="local",
                   help="local processes (default) or a dask.distributed cluster")
    w.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="dask scheduler address, e.g. tcp://10.0.0.5:8786 (default with "
                        "--backend dask: a LocalCluster on this machine)")
    w.add_argument("--processes", type=_processes, default=None, metavar="N",
                   help="worker processes (default: every available core)")
    w.add_argument("--resume", action="store_true",
                   help="reuse the finished cases of a previous run in DIR")
    w.add_argument("--overwrite", action="store_true",
                   help="replace a previous ppamsafety output in DIR, recomputing every case")
    w.add_argument("--max-cases", type=_processes, default=None, metavar="N",
                   help="run only the first N cases (a preview)")
    w.add_argument("--yes", action="store_true",
                   help="start even if the estimate exceeds 1 h of wall time (a long run, "
                        "confirmed); runs whose results exceed 2 GB are refused anyway")
    w.add_argument("--replace-other-kind", action="store_true",
                   help="with --overwrite: also replace a ppamsafety output of another kind "
                        "(a diagnosis, a report ...)")
    w.add_argument("--no-progress", action="store_true", help="no progress bar")
    _add_arm_head(w)
    w.set_defaults(func=_cmd_sweep)
    g = sub.add_parser("diagnose", help="find and name the effect the model is missing",
                       description="Compare a measured arm record (q, qd, p and the valve set "
                                   "values u), or an actuator record from a test bench (force, "
                                   "pressure, contraction, nominal force law), with the model, "
                                   "name the missing effects with fitted parameters, or report "
                                   "'unexplained' (docs/diagnose.md). Exit code 0 whenever the "
                                   "analysis ran.",
                       epilog=_EPILOG)
    g.add_argument("data", type=_path, metavar="DATA",
                   help="measured data file (.csv or .parquet), or a bench campaign manifest "
                   "(.toml, docs/measured_data.md)")
    g.add_argument("--out", type=_path, required=True, metavar="DIR",
                   help="output folder for diagnosis.json, diagnosis.md and figures")
    g.add_argument("--experiment", choices=("open-loop", "closed-loop", "static-sawtooth",
                                            "tensile"), default=None,
                   help="experiment hint (must agree with the metadata)")
    g.add_argument("--alpha", type=_positive, default=0.01,
                   help="level of the likelihood-ratio test (default 0.01, Bonferroni-divided)")
    g.add_argument("--rho-max", type=_positive, default=1.5,
                   help="largest residual/noise RMS ratio counted as explained (default 1.5)")
    g.add_argument("--block", type=_positive, default=None, metavar="SECONDS",
                   help="arm records: block length of the subsystem residuals [s] (default 0.05)")
    g.add_argument("--seed", type=_seed, default=None,
                   help="arm records: seed of the noise propagation, the stability selection "
                        "and the bootstrap (default 0)")
    g.add_argument("--stability", type=_count(0, 10000), default=None, metavar="B",
                   help="arm records: complementary pairs of the stability selection behind "
                        "'high' confidence (default 25; 0: off, then nothing is 'high')")
    g.add_argument("--bootstrap", type=_count(0, 10000), default=None, metavar="B",
                   help="moving-block bootstrap replicates of the selection, reported as "
                        "bootstrap_frequency (default 0: off)")
    g.add_argument("--allow-gaps", action="store_true",
                   help="drop rows with missing values; the longest gap-free segment is used")
    g.add_argument("--loose-units", action="store_true",
                   help="only warn when values look like bar, degrees or mm")
    g.add_argument("--overwrite", action="store_true",
                   help="replace a previous ppamsafety diagnosis in DIR (never other files)")
    _add_arm_head(g, head_used=False)
    g.add_argument("--allow-other-arm", action="store_true",
                   help="arm records: diagnose a record that names another arm (metadata "
                        "[arm], as synthesize writes it) against this one on purpose; "
                        "refused otherwise (every difference between the two arms would be "
                        "named as a missing effect)")
    g.add_argument("--replace-other-kind", action="store_true",
                   help="with --overwrite: also replace a ppamsafety output of another kind")
    g.set_defaults(func=_cmd_diagnose)
    y = sub.add_parser("synthesize", help="write a record with hidden effects (rehearsal data)",
                       description="Simulate an experiment on a plant with hidden effects and "
                                   "write it in the measured-data format; the file carries no "
                                   "hint of what is hidden (docs/diagnose.md).",
                       epilog=_EPILOG)
    y.add_argument("--kind", choices=("arm", "actuator"), default="arm",
                   help="the arm (default) or one actuator on a tensile tester")
    y.add_argument("--experiment", choices=("open-loop", "closed-loop", "static-sawtooth",
                                            "tensile"), default=None,
                   help="arm: open-loop Fourier excitation (default), a closed-loop thesis "
                        "experiment (--controller, --reference) or the static "
                        "gravity-compensation sawtooth of thesis 3.5.1.6 (rest points only); "
                        "actuator: tensile (default)")
    y.add_argument("--controller", default=_SYN_CONTROLLER, metavar="VARIANT",
                   help="closed loop: thesis controller variant label (default "
                        "'PSMC joint Ki=2 λ=0.4'; e.g. 'PID', 'PSMC task λ=0.8')")
    y.add_argument("--reference", default=_SYN_REFERENCE,
                   choices=("step", "switch", "circle5", "circle10", "circle20"),
                   help="closed loop: thesis experiment (default circle10), placed in the "
                        "arm's working area (the thesis arm: the thesis' references; another "
                        "arm: at the same fractions of its joint ranges; printed)")
    y.add_argument("--effect", type=_effect_arg, action="append", metavar="NAME=VALUE",
                   help="hidden effect, repeatable (e.g. payload_mass=0.4, "
                        "valve_time_constant_factor=1.5, valve_dead_time=0.02)")
    y.add_argument("--noise", choices=("arm", "table-3.2", "tester", "none"), default=None,
                   help="arm: the noise variances the arm file declares in [sensors] (arm "
                        "default; the thesis arm: Table 3.2); table-3.2: the thesis' Table 3.2 "
                        "variances whatever the arm declares (a warning names both); tester "
                        "(actuator default); none")
    y.add_argument("--seed", type=_seed, default=0, help="seed of the excitation and the noise")
    y.add_argument("--duration", type=_positive, default=None,
                   help="record length [s] (arm; default 10 s, the whole sawtooth)")
    y.add_argument("--protocol", choices=("sawtooth", "pressure-sweep"), default=None,
                   help="actuator: contraction sawtooth (default) or pressure sweep")
    y.add_argument("--pressures", type=_float_list, default=None, metavar="PA,PA,...",
                   help="actuator: gauge pressures [Pa] (default 1e5,1.5e5,2.5e5)")
    y.add_argument("--cycles", type=_count(1, 100), default=None,
                   help="actuator: cycles per pressure")
    y.add_argument("--period", type=_positive, default=None, help="actuator: cycle period [s]")
    y.add_argument("--sample-rate", type=_positive, default=None, metavar="HZ",
                   help="actuator: sampling rate [Hz] (default 50)")
    y.add_argument("--force-law", type=_float_list, default=None, metavar="A0,A1,A2,A3,A4",
                   help="actuator: nominal law (3.9) [N/Pa] (default Table B.1 group 1; a "
                        "cylinder: 0,AREA,0,0,0)")
    y.add_argument("--position", action="store_true",
                   help="actuator: write the length 'position' [m] instead of 'contraction'")
    y.add_argument("--jitter", type=_nonnegative, default=None,
                   help="actuator: relative jitter of the sampling intervals (non-uniform t)")
    y.add_argument("--out", type=_path, required=True, metavar="DATA",
                   help="new .csv (or .parquet) file")
    y.add_argument("--overwrite", action="store_true", help="allow replacing an existing file")
    _add_arm_head(y, head_used=False)
    y.set_defaults(func=_cmd_synthesize)
    m = sub.add_parser("impact", help="simulate one impact of the arm with a head",
                       epilog=_EPILOG)
    m.add_argument("--q", nargs=2, type=_angle_deg, required=True, metavar=("Q1", "Q2"),
                   help="link angles at impact [deg], each in [-360, 360]")
    m.add_argument("--qd", nargs=2, type=_finite, required=True, metavar=("QD1", "QD2"),
                   help="link angular velocities at impact [rad/s]")
    m.add_argument("--stiffness", nargs=2, type=_nonnegative, default=None,
                   metavar=("K1", "K2"),
                   help="joint stiffnesses [Nm/rad], >= 0 (default: the arm's own at rest in "
                        "the pose --q, (2.18) with its static pressures)")
    m.add_argument("--dt", type=_impact_dt, default=2e-5,
                   help=f"integration step [s], in [{_DT_RANGE[0]:g}, {_DT_RANGE[1]:g}] s "
                        f"(default 2e-05)")
    m.add_argument("--history", type=_path, default=None, metavar="FILE",
                   help="write the time history to this new CSV file")
    m.add_argument("--region", default="skull/forehead", metavar="NAME|FILE",
                   help="body region of the verdicts: an ISO/TS 15066 Annex A location "
                        "(skull/forehead, face, chest/sternum ...; docs/body_regions.md), its "
                        "number 1-29, or a region file (TOML); default skull/forehead")
    m.add_argument("--contact", default=None, metavar="POINT|FILE",
                   help="contact point of the arm: tool point, elbow, forearm, upper arm, or a "
                        "contact point file (TOML, docs/impact_models.md); the body region is "
                        "then hit in layers (the skull/forehead as the head that passes the "
                        "Hybrid III drop, another region as its Annex A two-body model, a head "
                        "region as --head when given); default: the tool point against --head")
    m.add_argument("--covering", default=None, metavar="NAME|FILE",
                   help="covering of the contact point: bare metal, thesis-implied, or a "
                        "covering file (TOML); it replaces the point's own covering. Default: "
                        "the covering a contact point file names (bare metal if it names none, "
                        "and for the arm's named points). Implies --contact tool point when "
                        "--contact is not given")
    m.add_argument("--overwrite", action="store_true",
                   help="allow --history to replace an existing file")
    _add_arm_head(m)
    m.set_defaults(func=_cmd_impact)
    i = sub.add_parser("info", help="print the arm's key parameters and the head model",
                       epilog=_EPILOG)
    _add_arm_head(i)
    i.set_defaults(func=_cmd_info)
    a = sub.add_parser("arm", help="arm files: export a template, check a file",
                       description="Arm files describe your own arm in TOML (docs/arm_files.md): "
                                   "`ppamsafety arm export --out my_arm.toml` writes the thesis "
                                   "arm as a commented template; `ppamsafety arm check "
                                   "my_arm.toml` validates it and prints stiffness at a pose, "
                                   "maximum load and working area.", epilog=_EPILOG)
    asub = a.add_subparsers(dest="arm_command", required=True)
    ae = asub.add_parser("export", help="write an arm file (default: the thesis arm) as a "
                                        "commented template", epilog=_EPILOG)
    ae.add_argument("--out", type=_path, required=True, metavar="FILE", help="new .toml file")
    ae.add_argument("--arm", type=_path, default=None, metavar="FILE",
                    help="re-export this arm file (canonical form, with comments)")
    ae.add_argument("--head", type=_path, default=None, metavar="NAME|FILE",
                    help=argparse.SUPPRESS)
    ae.add_argument("--overwrite", action="store_true", help="allow replacing an existing file")
    ae.set_defaults(func=_cmd_arm_export)
    ac = asub.add_parser("check", help="validate an arm file and print its key numbers",
                         epilog=_EPILOG)
    ac.add_argument("file", type=_path, metavar="FILE", help="arm file (.toml)")
    ac.add_argument("--q", nargs=2, type=_angle_deg, default=None, metavar=("Q1", "Q2"),
                    help="pose of the stiffness numbers [deg] (default 50 -80, the thesis' "
                         "step-response impact, or the centre of the working area)")
    ac.set_defaults(func=_cmd_arm_check)
    return p


def main(argv=None) -> int:
    """Entry point of the ``ppamsafety`` command; returns the exit status.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name (default ``sys.argv[1:]``).

    Returns
    -------
    int
        0 success, 2 bad usage or input, 1 failure that is not the user's,
        130 interrupted (see the module docstring).
    """
    return run_guarded(build_parser(), lambda args: args.func(args), argv)


if __name__ == "__main__":
    sys.exit(main())
