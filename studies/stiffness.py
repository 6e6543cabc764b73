"""Joint-stiffness sweep of the step-response impact (fig. 6.3).

Regenerates the report section ``stiffness`` (:mod:`ppamsafety.sections.stiffness`) alone:
    python studies/stiffness.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("stiffness"))
