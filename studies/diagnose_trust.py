"""Trust in the diagnosis: calibration of 'high', the battery's scores, detection limits.

Regenerates the report section ``diagnose_trust`` (:mod:`ppamsafety.sections.diagnose_trust`) alone:
    python studies/diagnose_trust.py [outdir] [--quick] [--overwrite]
The battery itself (>= 1000 scenarios): ``python -m ppamsafety.diagnose.scenarios``.
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("diagnose_trust"))
