"""The bench case study: real 3D-printed pneumatic cylinders, campaigns over pressure.

Regenerates the report section ``cylinder_friction`` (:mod:`ppamsafety.sections.cylinder_friction`) alone:
    python studies/cylinder_friction.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("cylinder_friction"))
