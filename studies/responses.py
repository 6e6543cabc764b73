"""Step and trajectory-switch responses (figs. 5.15-5.19).

Regenerates the report section ``responses`` (:mod:`ppamsafety.sections.responses`) alone:
    python studies/responses.py [outdir] [--quick] [--overwrite]
"""
from ppamsafety.sections import main

if __name__ == "__main__":
    raise SystemExit(main("responses"))
