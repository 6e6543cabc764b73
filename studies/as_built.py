"""The as-built arm: effects and sensor faults fitted jointly to the thesis' printed measurements.

Regenerates the report section ``as_built`` (:mod:`ppamsafety.sections.as_built`) alone:
    python studies/as_built.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("as_built"))
