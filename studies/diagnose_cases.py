"""Discrepancy diagnosis: a two-effect closed-loop case, Table 5.2 against the library, a blind battery.

Regenerates the report section ``diagnose_cases`` (:mod:`ppamsafety.sections.diagnose_cases`) alone:
    python studies/diagnose_cases.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("diagnose_cases"))
