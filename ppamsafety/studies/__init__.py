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


def main(name: str, argv=None) -> int:
    """Run one study alone: ``python studies/<script>.py [outdir] [--quick] [--overwrite]``.

    The study writes into ``outdir`` (default ``reports``) under the rules of
    :mod:`ppamsafety.output`: a missing or empty folder is used; a previous
    ppamsafety output is updated only with ``--overwrite`` (files of the same
    name are replaced, the other toolkit files are kept); a folder holding
    files ppamsafety did not write is refused.

    Returns
    -------
    int
        Exit status: 0 success, 2 bad usage or input, 1 failure (see
        :func:`ppamsafety.cli.main`).
    """
    import argparse
    import importlib

    from ..cli import run_guarded
    from ..output import OutputFolder

    if name not in REGISTRY:
        raise ValueError(f"unknown study {name!r}; choose from {REGISTRY}")
    p = argparse.ArgumentParser(prog=f"studies/{name}.py",
                                description=f"Run the study {name!r} alone.")
    p.add_argument("outdir", nargs="?", default="reports",
                   help="output folder (default: reports)")
    p.add_argument("--quick", action="store_true", help="coarse grids and short sweeps")
    p.add_argument("--overwrite", action="store_true",
                   help="replace files of a previous ppamsafety output in OUTDIR")

    def run(args):
        mod = importlib.import_module(f"ppamsafety.studies.{name}")
        with OutputFolder(args.outdir, kind="study", overwrite=args.overwrite,
                          clean=False) as stage:
            res = mod.run(stage, quick=args.quick)
        print(f"# {res.title}\n\n{res.markdown}")
        return 0

    return run_guarded(p, run, argv)
