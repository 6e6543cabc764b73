"""Step and trajectory-switch responses (figs. 5.15-5.19).

Run alone:  python studies/step_and_switch.py [outdir] [--quick] [--overwrite]
"""

from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("responses"))
