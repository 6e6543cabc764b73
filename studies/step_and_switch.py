"""Step and trajectory-switch responses of the ten thesis controller variants (figs. 5.15-5.19).

Run alone:  python studies/step_and_switch.py [outdir]
"""

import pathlib
import sys

from ppamsafety.studies import responses

if __name__ == "__main__":
    out = sys.argv[1] if len(sys.argv) > 1 else "reports"
    pathlib.Path(out).mkdir(parents=True, exist_ok=True)
    res = responses.run(out)
    print(res.markdown)
