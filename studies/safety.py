"""Collision safety: Table 6.1 reproduction and the every-instant impact scan.

Regenerates the report section ``safety`` (:mod:`ppamsafety.sections.safety`) alone:
    python studies/safety.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("safety"))
