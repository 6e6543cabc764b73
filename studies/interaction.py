"""Physical interaction: force estimation, admittance control and the release hazard (§5.4).

Not part of ``ppamsafety report`` (not in the study REGISTRY).

Run alone:  python studies/interaction.py [outdir] [--quick] [--overwrite]
(default outdir: reports-interaction; the output-folder rules of
:mod:`ppamsafety.output` apply).
"""

import argparse

from ppamsafety.cli import run_guarded
from ppamsafety.output import OutputFolder
from ppamsafety.studies import interaction, write_section


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="studies/interaction.py",
                                description="Run the interaction study alone.")
    p.add_argument("outdir", nargs="?", default="reports-interaction",
                   help="output folder (default: reports-interaction)")
    p.add_argument("--quick", action="store_true", help="shorter runs")
    p.add_argument("--overwrite", action="store_true",
                   help="replace files of a previous ppamsafety output in OUTDIR")

    def run(args):
        with OutputFolder(args.outdir, kind="study", overwrite=args.overwrite,
                          clean=False) as stage:
            res = write_section(interaction.render(interaction.compute(quick=args.quick)),
                                stage)
        print(f"# {res.title}\n\n{res.markdown}")
        return 0

    return run_guarded(p, run, argv)


if __name__ == "__main__":
    raise SystemExit(main())
