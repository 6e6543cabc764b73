"""Table 5.2: circle tracking errors of the thesis' controller variants, with ratios.

Run alone:  python studies/table_5_2.py [outdir] [--quick] [--overwrite]
"""

from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("tracking"))
