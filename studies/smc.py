"""Sliding mode control: chattering against boundary layer and valve time constant.

Regenerates the report section ``smc`` (:mod:`ppamsafety.sections.smc`) alone:
    python studies/smc.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("smc"))
