"""Reconstruction of the thesis' head contact model and its evidence.

Regenerates the report section ``head_model`` (:mod:`ppamsafety.sections.head_model`) alone:
    python studies/head_model.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("head_model"))
