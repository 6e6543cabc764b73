"""Reconstruction of the thesis' head contact model and its evidence (§6.3.1).

Run alone:  python studies/head_model.py [outdir]
"""

import pathlib
import sys

from ppamsafety.studies import head_model

if __name__ == "__main__":
    out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "reports")
    out.mkdir(parents=True, exist_ok=True)
    print(head_model.run(out).markdown)
