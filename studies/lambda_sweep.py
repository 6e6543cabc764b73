"""Safety against tracking over a lambda x Ki grid of joint PSMC.

Run alone:  python studies/lambda_sweep.py [outdir] [--quick] [--overwrite]
"""

from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("lambda_sweep"))
