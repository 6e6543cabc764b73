"""The sections of the report, each in three parts: compute, plot, render.

Every section module ``ppamsafety.sections.<name>`` defines

* ``compute(*, quick=False, arm=None, head=None, ...) -> <Name>Study``: runs
  the simulations for ``arm`` (any valid arm; default the thesis arm) and
  ``head`` (a head model; default ``thesis-frontal``) and returns a dataclass
  holding DataFrames, arrays, result objects and a ``metrics`` dict.  It writes
  no file, makes no figure and formats no Markdown.  The result object has
  ``to_pandas()`` (its main table) and ``plot()`` (its figures, ``{file name:
  Figure}``, composed from the plot functions of :mod:`ppamsafety.plots`).
  Thesis values and ratios are joined only when :func:`compares_to_thesis` holds
  (the thesis arm, and for impacts the thesis head): every other number is
  computed for the arm given.
* ``render(result) -> Section``: formatting only -- the Markdown text of the
  report section and the artifacts (file name, Figure or DataFrame) it
  references.

:func:`write_section` writes the artifacts of a :class:`Section` to a folder
and :func:`run_section` chains the three steps; the report builder
(:func:`ppamsafety.report.build.build_report`) and :func:`main` (one section
alone, ``python studies/<name>.py [outdir] [--quick]``) use it.

"Section" is a part of the report; "study" means a sweep study (a TOML study
file run by ``ppamsafety sweep``, :mod:`ppamsafety.study_files`).
"""

from __future__ import annotations

import functools
import importlib
import inspect
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from .._commandline import Parser, run_guarded
from .._validation import check_bool
from ..output import OutputFolder
# the impact.head module by its own name: ``head_model`` is a section module here
from ..impact import head as _head
from ..design import load_arm
from ..params import ArmParameters, is_thesis_arm, thesis_arm
from ..plots.figure import save


@dataclass(frozen=True)
class SectionInfo:
    """What the report says of a section before running it: every section module's ``SECTION``.

    Attributes
    ----------
    summary : str
        What the section shows (a row of the README's section table).
    thesis : str
        The parts of the thesis it reproduces, or ``"(new)"``.
    typical_seconds : float
        Its wall time [s] in a full report on 2 cores with a cold kernel cache; a
        first report (no previous ``metrics.json``) starts the longest sections first.
    scope : str
        Which arms it concerns (:data:`SCOPES`): ``"arm"`` (any arm, the default),
        ``"hysteresis"`` (the arm's muscle hysteresis: an arm that declares
        ``hysteresis_delta``), ``"thesis"`` (the thesis arm's own measurements) or
        ``"bench"`` (a bench case study, not about an arm).  The report for an arm that is
        not the thesis arm leaves out the sections that do not concern it unless asked for
        (:func:`concerns`).
    """

    summary: str
    thesis: str
    typical_seconds: float
    scope: str = "arm"

    def __post_init__(self):
        for name in ("summary", "thesis"):
            if not isinstance(getattr(self, name), str) or not getattr(self, name).strip():
                raise ValueError(f"SectionInfo.{name} must be a non-empty string, "
                                 f"got {getattr(self, name)!r}")
        if not (isinstance(self.typical_seconds, (int, float)) and self.typical_seconds > 0):
            raise ValueError(f"SectionInfo.typical_seconds = {self.typical_seconds!r} must be a "
                             f"positive number [s]")
        if self.scope not in SCOPES:
            raise ValueError(f"SectionInfo.scope = {self.scope!r} must be one of {list(SCOPES)}")


#: What each :attr:`SectionInfo.scope` concerns, as the report says it when it leaves a
#: section out.
SCOPES = {
    "arm": "computed for any arm",
    "hysteresis": "it studies the arm's muscle hysteresis, and the arm declares none "
                  "(effects.hysteresis_delta)",
    "thesis": "it fits the thesis arm's own published measurements",
    "bench": "a bench case study of real cylinders, not about an arm",
}


@dataclass
class Section:
    """A rendered report section, not yet written to disk.

    Attributes
    ----------
    title : str
        Section title in the report.
    markdown : str
        Section body (Markdown; references the artifacts by file name).
    artifacts : list of (str, object)
        (file name, content) pairs: a matplotlib ``Figure`` is written as PNG
        (150 dpi), a pandas ``DataFrame`` as CSV without index.
    metrics : dict
        Headline numbers, for tests and for ``metrics.json``.
    """

    title: str
    markdown: str
    artifacts: list = field(default_factory=list)
    metrics: dict = field(default_factory=dict)


@dataclass
class SectionResult:
    """What a section wrote: a :class:`Section` after :func:`write_section`.

    Attributes
    ----------
    title : str
        Section title in the report.
    markdown : str
        Section body (Markdown, may reference the artifacts by file name).
    artifacts : list of str
        Files written (figures, CSV tables).
    metrics : dict
        Headline numbers, for tests and for the issue notes.
    """

    title: str
    markdown: str
    artifacts: list = field(default_factory=list)
    metrics: dict = field(default_factory=dict)


#: Section modules in report order (module names inside ppamsafety.sections).
REGISTRY = ["design", "tracking", "responses", "smc", "head_model", "safety", "worst_direction",
            "stiffness", "lambda_sweep", "effects", "interaction", "iso_15066", "reaction",
            "diagnose_sawtooth", "diagnose_cases", "diagnose_trust", "as_built", "cylinder_friction"]


def section_infos() -> dict:
    """Every registered section's :class:`SectionInfo`, in report order.

    Imports every section module (as the report does).

    Returns
    -------
    dict
        Section name -> :class:`SectionInfo`.
    """
    return {name: section_module(name).SECTION for name in REGISTRY}


def readme_table() -> str:
    """The README's table of the report sections, generated from :func:`section_infos`.

    ``tests/test_sections.py`` checks that README.md holds exactly this table; after adding
    or changing a section, paste the output of ``python -m ppamsafety.sections``.

    Returns
    -------
    str
        A Markdown table: section name, what it shows, the thesis parts.
    """
    lines = ["| section | what it shows | thesis |", "|---|---|---|"]
    lines += [f"| `{name}` | {info.summary} | {info.thesis} |"
              for name, info in section_infos().items()]
    return "\n".join(lines)


def concerns(name: str, arm=None) -> tuple:
    """Whether a section concerns an arm, and if not, why.

    Every section concerns the thesis arm (the thesis report runs them all).  For another
    arm, a section of scope ``"arm"`` always does, ``"hysteresis"`` if the arm declares a
    muscle hysteresis, ``"thesis"`` and ``"bench"`` never.

    Parameters
    ----------
    name : str
        A section of :data:`REGISTRY`.
    arm : ArmParameters or None
        The arm (None: the thesis arm).

    Returns
    -------
    (bool, str)
        Whether it concerns the arm; the reason when it does not (else "").
    """
    scope = section_module(name).SECTION.scope
    if arm is None or is_thesis_arm(resolve_arm(arm)) or scope == "arm":
        return True, ""
    if scope == "hysteresis" and resolve_arm(arm).effects.hysteresis_delta is not None:
        return True, ""
    return False, SCOPES[scope]


def resolve_arm(arm):
    """The arm a section runs: ``arm``, or the thesis arm when None.

    Parameters
    ----------
    arm : ppamsafety.params.ArmParameters or None
        Arm parameters.

    Returns
    -------
    ppamsafety.params.ArmParameters
        ``arm`` or :func:`ppamsafety.params.thesis_arm`.
    """
    if arm is None:
        return thesis_arm()
    if not isinstance(arm, ArmParameters):
        raise TypeError(f"arm must be an ArmParameters or None, not {type(arm).__name__}")
    return arm


def resolve_head_model(head) -> "_head.HeadContactModel":
    """The head a section crashes into: ``head``, or ``thesis-frontal`` when None.

    Parameters
    ----------
    head : HeadContactModel, str or None
        A model, a name or a head file (:func:`ppamsafety.impact.head.resolve_head`).

    Returns
    -------
    HeadContactModel
    """
    return _head.resolve_head(head)


def checked_compute(compute):
    """Decorator of a section's ``compute``: its common arguments are checked first.

    ``quick`` must be a bool, ``arm`` an ArmParameters or None, ``head`` a head model, a
    name or a head file (resolved, so a wrong head is refused even by a section that
    crashes into none and does not use it).

    Parameters
    ----------
    compute : callable
        The section's ``compute(*, quick=False, arm=None, head=None, ...)``.
    """
    sig = inspect.signature(compute)

    @functools.wraps(compute)
    def checked(*args, **kwargs):
        given = sig.bind(*args, **kwargs).arguments
        if "quick" in given:
            check_bool("quick", given["quick"])
        if given.get("arm") is not None:
            resolve_arm(given["arm"])
        if given.get("head") is not None:
            resolve_head_model(given["head"])
        return compute(*args, **kwargs)
    return checked


def compares_to_thesis(arm, head=None) -> bool:
    """True if thesis values apply: the thesis arm (and the thesis head, if given).

    Parameters
    ----------
    arm : ArmParameters or None
        The section's arm (None: the thesis arm).
    head : HeadContactModel, str or None
        The section's head, for sections that crash into one (None: not compared).

    Returns
    -------
    bool
    """
    arm_ok = arm is None or is_thesis_arm(resolve_arm(arm))
    return arm_ok and (head is None or _head.resolve_head(head) == _head.head_model())


def other_arm_note(arm, head=None) -> str:
    """The line a section prints instead of its thesis comparison for another arm or head.

    Parameters
    ----------
    arm : ArmParameters
        The section's arm.
    head : HeadContactModel, optional
        The section's head.

    Returns
    -------
    str
    """
    arm = resolve_arm(arm)
    what = f"arm `{arm.name or 'unnamed arm'}`"
    if head is not None:
        what += f" and head model `{_head.resolve_head(head).name}`"
    return (f"*Computed for {what}: thesis values and ratios apply to the thesis arm and head "
            f"only and are not shown.*")


def write_artifact(obj, path) -> str:
    """Write one artifact: a Figure as PNG (150 dpi), a DataFrame as CSV (no index).

    Parameters
    ----------
    obj : matplotlib.figure.Figure or pandas.DataFrame
        The content.
    path : path-like
        Target file.

    Returns
    -------
    str
        ``str(path)``.
    """
    if isinstance(obj, pd.DataFrame):
        obj.to_csv(path, index=False)
    elif hasattr(obj, "savefig"):

        save(obj, path)
    else:
        raise TypeError(f"artifact {str(path)!r} is a {type(obj).__name__}; expected a "
                        "matplotlib Figure or a pandas DataFrame")
    return str(path)


def write_section(section: Section, outdir) -> SectionResult:
    """Write the artifacts of a rendered section into ``outdir``.

    Parameters
    ----------
    section : Section
        Output of a section's ``render``.
    outdir : path-like
        Existing folder; the artifacts are written under their file names.

    Returns
    -------
    SectionResult
        The section's text and metrics with the paths written.
    """
    out = Path(outdir)
    paths = [write_artifact(obj, out / name) for name, obj in section.artifacts]
    return SectionResult(section.title, section.markdown, paths, dict(section.metrics))


def section_module(name: str):
    """The module ``ppamsafety.sections.<name>`` of a registered section.

    Parameters
    ----------
    name : str
        One of :data:`REGISTRY`.

    Returns
    -------
    module
        The section module (with ``compute`` and ``render``).
    """
    if name not in REGISTRY:
        raise ValueError(f"unknown report section name={name!r}; choose from {REGISTRY}")
    return importlib.import_module(f"{__name__}.{name}")


def run_section(name: str, outdir, *, quick: bool = False, arm=None,
                head=None, processes: int | None = None) -> SectionResult:
    """Compute, render and write one section: ``write_section(render(compute(...)), outdir)``.

    Every warning the section raises is raised again naming the section
    (``section NAME: ...``), after it finished.

    Parameters
    ----------
    name : str
        Section name (see :data:`REGISTRY`).
    outdir : path-like
        Existing folder the artifacts are written to.
    quick : bool
        Coarser grids and shorter runs (smoke tests).
    arm : ArmParameters, optional
        The arm (default the thesis arm).
    head : HeadContactModel, optional
        The head model of the impacts (default ``thesis-frontal``).  A section whose
        ``compute`` takes no ``head`` (it crashes into none) runs without it: the report
        passes each section only the options it takes (:func:`section_options`).
    processes : int, optional
        Worker processes a section that runs a sweep of its own may start (its
        ``compute(processes=...)``; default the section's own choice).

    Returns
    -------
    SectionResult
        Title, Markdown, written paths and metrics.
    """
    mod = section_module(name)
    kw = {}
    if arm is not None:
        kw["arm"] = resolve_arm(arm)
    if head is not None:
        kw["head"] = _head.resolve_head(head)
    if processes is not None:
        kw["processes"] = processes
    taken = section_options(name)
    kw = {k: v for k, v in kw.items() if k in taken}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = write_section(mod.render(mod.compute(quick=quick, **kw)), outdir)
    for w in named_warnings(name, caught):
        warnings.warn(w.message, w.category, stacklevel=2)
    return res


class _Named:
    def __init__(self, message, category):
        self.message, self.category = message, category


def named_warnings(name: str, caught) -> list:
    """The warnings a section raised, each once, with the section's name in front.

    Parameters
    ----------
    name : str
        The section.
    caught : list of warnings.WarningMessage
        What ``warnings.catch_warnings(record=True)`` recorded.

    Returns
    -------
    list
        Objects with ``message`` (str, ``"section NAME: ..."``) and ``category``.
    """
    out, seen = [], set()
    for w in caught:
        text = " ".join(str(w.message).split())
        if text in seen:
            continue
        seen.add(text)
        out.append(_Named(f"section {name}: {text}", w.category))
    return out


def section_options(name: str) -> frozenset:
    """The keyword options a section's ``compute`` takes (``quick``, ``arm``, ``head`` ...).

    Parameters
    ----------
    name : str
        Section name (see :data:`REGISTRY`).

    Returns
    -------
    frozenset of str
        Names of the keyword parameters of ``compute`` (read from its signature, through
        the :func:`checked_compute` wrapper).
    """
    params = inspect.signature(section_module(name).compute).parameters.values()
    return frozenset(p.name for p in params
                     if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD))


def main(name: str, argv=None) -> int:
    """Run one section alone: ``python studies/<name>.py [outdir] [--quick] [--overwrite]``.

    The section writes into ``outdir`` (default ``reports``) under the rules of
    :mod:`ppamsafety.output`: a missing or empty folder is used; a previous
    ppamsafety output is updated only with ``--overwrite`` (files of the same
    name are replaced, the other toolkit files are kept); a folder holding
    files ppamsafety did not write is refused.

    Parameters
    ----------
    name : str
        Section name (see :data:`REGISTRY`).
    argv : list of str, optional
        Command-line arguments (default ``sys.argv[1:]``).

    Returns
    -------
    int
        Exit status: 0 success, 2 bad usage or input, 1 failure (see
        :func:`ppamsafety.cli.main`).
    """
    if name not in REGISTRY:
        raise ValueError(f"unknown report section {name!r}; choose from {REGISTRY}")
    p = Parser(prog=f"studies/{name}.py", description=f"Run the report section {name!r} alone.")
    p.add_argument("outdir", nargs="?", default="reports",
                   help="output folder (default: reports)")
    p.add_argument("--quick", action="store_true", help="coarse grids and short sweeps")
    p.add_argument("--overwrite", action="store_true",
                   help="replace files of a previous ppamsafety output in OUTDIR")
    p.add_argument("--arm", default=None, metavar="FILE",
                   help="arm file (TOML; default: the thesis arm)")
    p.add_argument("--head", default=None, metavar="NAME|FILE",
                   help="head model name or head file (default: thesis-frontal)")

    def named(option, value, load):
        try:
            return load(value)
        except (ValueError, TypeError, OSError) as exc:     # the option, then why
            raise ValueError(f"{option} {value!r}: {exc}") from None

    def run(args):
        arm = None if args.arm is None else named("--arm", args.arm, load_arm)
        head = None if args.head is None else named("--head", args.head, _head.resolve_head)
        with OutputFolder(args.outdir, kind="section", overwrite=args.overwrite,
                          clean=False, kinds=("section", "report")) as stage:
            res = run_section(name, stage, quick=args.quick, arm=arm, head=head)
        print(f"# {res.title}\n\n{res.markdown}")
        return 0

    return run_guarded(p, run, argv)
