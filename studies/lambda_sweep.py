"""Safety against tracking over a lambda x Ki grid of joint PSMC.

Run alone:  python studies/lambda_sweep.py [outdir] [--quick]
"""

from ppamsafety.studies import main

if __name__ == "__main__":
    main("lambda_sweep")
