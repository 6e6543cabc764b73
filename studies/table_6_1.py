"""Collision safety: Table 6.1 reproduction and the every-instant impact scan.

Run alone:  python studies/table_6_1.py [outdir] [--quick] [--overwrite]
"""

from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("safety"))
