"""Regenerate the tiny example records of this folder (run from the repository root).

    python tests/data/measured/make_examples.py

* ``equilibria.csv`` -- 31 synthetic equilibrium readings of the thesis arm (§3.5.1.4,
  :func:`ppamsafety.data.synthetic_static`, seed 0, Table 3.2 noise), metadata in the
  commented header; values rounded (1e-6 rad, 1e-3 N, 1 Pa) to keep the file small.
* ``tensile_group1.csv`` + ``tensile_group1.toml`` -- a synthetic tensile test of one muscle
  of group 1 (:func:`ppamsafety.data.synthetic_tensile`, 3 pressures x 12 lengths, seed 0),
  with the actuator length ``position`` [m] instead of the contraction, metadata in the
  sidecar file.
"""

from pathlib import Path

import pandas as pd

from ppamsafety.data import MeasuredData, synthetic_static, synthetic_tensile

HERE = Path(__file__).resolve().parent


def _rounded(data, digits):
    df = data.frame.copy()
    for col, d in digits.items():
        for c in [c for c in df.columns if c == col or (len(col) == 1 and c[:1] == col
                                                        and c[1:].isdigit())]:
            df[c] = df[c].round(d)
    return MeasuredData(data.meta, df, source=data.source)


def main():
    s = _rounded(synthetic_static(), {"q": 6, "F": 3, "p": 0, "u": 0})
    s.save(HERE / "equilibria.csv", overwrite=True)
    t = synthetic_tensile(n_per_level=12, position=True)
    t = _rounded(t, {"force": 3, "pressure": 0, "position": 7})
    t.save(HERE / "tensile_group1.csv", overwrite=True, sidecar=True)
    for f in sorted(HERE.glob("*.csv")) + sorted(HERE.glob("*.toml")):
        print(f.name, f.stat().st_size, "bytes")


if __name__ == "__main__":
    pd.set_option("display.width", 120)
    main()
