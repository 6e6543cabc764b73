"""Joint-stiffness sweep of the step-response impact (fig. 6.3).

Run alone:  python studies/fig_6_3.py [outdir] [--quick] [--overwrite]
"""

from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("stiffness"))
