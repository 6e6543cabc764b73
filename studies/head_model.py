"""Reconstruction of the thesis' head contact model and its evidence.

Run alone:  python studies/head_model.py [outdir] [--quick] [--overwrite]
"""

from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("head_model"))
