"""Physical interaction: force estimation, admittance control and the release hazard (§5.4).

Regenerates the report section ``interaction`` (:mod:`ppamsafety.sections.interaction`) alone:
    python studies/interaction.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("interaction"))
