"""The whole person on the thesis arm: validated head, implied covering, every region and point.

Regenerates the report section ``person`` (:mod:`ppamsafety.sections.person`) alone:
    python studies/person.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("person"))
