"""Safety against tracking over a lambda x Ki grid of joint PSMC (resumable sweep).

Run alone:  python studies/lambda_sweep.py [outdir]
"""

import pathlib
import sys

from ppamsafety.studies import lambda_sweep

if __name__ == "__main__":
    out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "reports")
    out.mkdir(parents=True, exist_ok=True)
    print(lambda_sweep.run(out).markdown)
