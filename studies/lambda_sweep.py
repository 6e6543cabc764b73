"""Safety against tracking over a lambda x Ki grid of joint PSMC.

Regenerates the report section ``lambda_sweep`` (:mod:`ppamsafety.sections.lambda_sweep`) alone:
    python studies/lambda_sweep.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("lambda_sweep"))
