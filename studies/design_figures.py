"""Design figures of thesis chapter 2 (torque functions, stiffness, maximum load).

Run alone:  python studies/design_figures.py [outdir]
"""

import sys

from ppamsafety.studies import design

if __name__ == "__main__":
    out = sys.argv[1] if len(sys.argv) > 1 else "reports"
    import pathlib
    pathlib.Path(out).mkdir(parents=True, exist_ok=True)
    res = design.run(out)
    print(res.markdown)
