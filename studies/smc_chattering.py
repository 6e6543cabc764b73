"""Sliding mode control: chattering against boundary layer and valve time constant.

Run alone:  python studies/smc_chattering.py [outdir] [--quick] [--overwrite]
"""

from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("smc"))
