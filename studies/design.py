"""Design figures of thesis chapter 2 (torque functions, stiffness, maximum load).

Regenerates the report section ``design`` (:mod:`ppamsafety.sections.design`) alone:
    python studies/design.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("design"))
