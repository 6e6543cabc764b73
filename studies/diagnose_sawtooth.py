"""Discrepancy workflow, case (a): hidden hysteresis in the static sawtooth (§3.5.1.6).

Regenerates the report section ``diagnose_sawtooth`` (:mod:`ppamsafety.sections.diagnose_sawtooth`) alone:
    python studies/diagnose_sawtooth.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("diagnose_sawtooth"))
