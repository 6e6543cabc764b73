"""Reconstruction of the thesis' head contact model and its evidence.

Run alone:  python studies/head_model.py [outdir] [--quick]
"""

from ppamsafety.studies import main

if __name__ == "__main__":
    main("head_model")
