"""Worst head placement around the tool point, over every instant.

Regenerates the report section ``worst_direction`` (:mod:`ppamsafety.sections.worst_direction`) alone:
    python studies/worst_direction.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("worst_direction"))
