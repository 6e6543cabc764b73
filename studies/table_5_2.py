"""Circle tracking: Table 5.2 reproduced, the thesis' conclusions tested, ablations.

Run alone:  python studies/table_5_2.py [outdir] [--quick]
"""

import pathlib
import sys

from ppamsafety.studies import tracking

if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--quick"]
    out = args[0] if args else "reports"
    pathlib.Path(out).mkdir(parents=True, exist_ok=True)
    res = tracking.run(out, quick="--quick" in sys.argv)
    print(res.markdown)
