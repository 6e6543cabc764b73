"""Collision safety: Table 6.1 reproduction and the every-instant scan (thesis §6.3.3).

Run alone:  python studies/table_6_1.py [outdir]
"""

import pathlib
import sys

from ppamsafety.studies import safety

if __name__ == "__main__":
    out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "reports")
    out.mkdir(parents=True, exist_ok=True)
    print(safety.run(out).markdown)
