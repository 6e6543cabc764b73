"""The thesis revisited with muscle hysteresis in the plant (sawtooth, Tables 5.2 and 6.1).

Regenerates the report section ``effects`` (:mod:`ppamsafety.sections.effects`) alone:
    python studies/effects.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("effects"))
