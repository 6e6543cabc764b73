"""Clamping and ISO/TS 15066 power and force limiting for the head.

Regenerates the report section ``iso_15066`` (:mod:`ppamsafety.sections.iso_15066`) alone:
    python studies/iso_15066.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("iso_15066"))
