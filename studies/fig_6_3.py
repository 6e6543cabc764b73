"""Joint-stiffness sweep of the step-response impact (thesis §6.3.4, fig. 6.3).

Run alone:  python studies/fig_6_3.py [outdir]
"""

import pathlib
import sys

from ppamsafety.studies import stiffness

if __name__ == "__main__":
    out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "reports")
    out.mkdir(parents=True, exist_ok=True)
    print(stiffness.run(out).markdown)
