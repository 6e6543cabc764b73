"""The safety summary: per controller family and experiment, what governs the verdict.

Regenerates the report section ``safety_summary`` (:mod:`ppamsafety.sections.safety_summary`) alone:
    python studies/safety_summary.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("safety_summary"))
