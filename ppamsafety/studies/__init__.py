"""Studies: each composes computation and plotting into report artifacts.

Every study module defines ``run(outdir, *, quick=False) -> StudyResult``.
The scripts in the repository's ``studies/`` folder call them so each study
can also be run alone; :mod:`ppamsafety.report.build` runs them all.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class StudyResult:
    """What a study produced.

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


#: Study modules in report order (module names inside ppamsafety.studies).
REGISTRY = ["design", "tracking", "responses", "smc", "head_model", "safety", "stiffness",
            "lambda_sweep"]


def main(name: str, argv=None) -> None:
    """Run one study alone: ``python studies/<script>.py [outdir] [--quick]``."""
    import importlib
    import pathlib
    import sys

    args = list(sys.argv[1:] if argv is None else argv)
    quick = "--quick" in args
    args = [a for a in args if a != "--quick"]
    out = pathlib.Path(args[0] if args else "reports")
    out.mkdir(parents=True, exist_ok=True)
    res = importlib.import_module(f"ppamsafety.studies.{name}").run(out, quick=quick)
    print(f"# {res.title}\n\n{res.markdown}")
