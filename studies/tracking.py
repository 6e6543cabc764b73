"""Table 5.2: circle tracking errors of the thesis' controller variants, with ratios.

Regenerates the report section ``tracking`` (:mod:`ppamsafety.sections.tracking`) alone:
    python studies/tracking.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("tracking"))
