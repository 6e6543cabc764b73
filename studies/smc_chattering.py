"""Sliding mode control: defaults, chattering vs boundary layer and valve time constant.

Run alone:  python studies/smc_chattering.py [outdir] [--quick]
"""

import pathlib
import sys

from ppamsafety.studies import smc

if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--quick"]
    out = args[0] if args else "reports"
    pathlib.Path(out).mkdir(parents=True, exist_ok=True)
    res = smc.run(out, quick="--quick" in sys.argv)
    print(res.markdown)
