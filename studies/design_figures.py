"""Design figures of thesis chapter 2 (torque functions, stiffness, maximum load).

Run alone:  python studies/design_figures.py [outdir] [--quick] [--overwrite]
"""

from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("design"))
