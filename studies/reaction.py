"""Collision detection and reaction in the closed loop (beyond thesis §6.3.5).

Regenerates the report section ``reaction`` (:mod:`ppamsafety.sections.reaction`) alone:
    python studies/reaction.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("reaction"))
