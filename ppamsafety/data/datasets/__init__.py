"""Data sets shipped with ppamsafety (real bench measurements; ``NOTICE.md`` in each folder).

``zillen2021``: friction tests of three 3D-printed pneumatic cylinders (E. Zillen,
H. Vallery, G. Smit, TU Delft 2021, CC0 1.0): the raw files byte for byte
(xz-compressed), their import profile and one campaign manifest per seal.
"""

from __future__ import annotations

from pathlib import Path

#: Folder of the Zillen (2021) bench files, their profile and manifests.
ZILLEN2021 = Path(__file__).resolve().parent / "zillen2021"
#: The seals shipped (the data set's other seals are kept for a blind check: not shipped).
ZILLEN2021_SEALS = ("O-ring257", "X-ring257", "Kidney_lc")


def zillen2021_manifest(seal: str) -> Path:
    """Path of the campaign manifest of one shipped seal.

    Parameters
    ----------
    seal : {"O-ring257", "X-ring257", "Kidney_lc"}
        The seal.

    Returns
    -------
    pathlib.Path
    """
    if seal not in ZILLEN2021_SEALS:
        raise ValueError(f"seal = {seal!r} is not one of the shipped seals "
                         f"{', '.join(map(repr, ZILLEN2021_SEALS))}")
    return ZILLEN2021 / f"{seal}.toml"


def zillen2021_file(seal: str, bar: int) -> Path:
    """Path of one shipped raw file (xz-compressed, byte-exact).

    Parameters
    ----------
    seal : {"O-ring257", "X-ring257", "Kidney_lc"}
        The seal.
    bar : int
        Nominal gauge pressure [bar]: 1, 3, 5, 7 (Kidney_lc: 1..7).
    """
    zillen2021_manifest(seal)
    p = ZILLEN2021 / f"{seal}_{bar}bar.csv.xz"
    if isinstance(bar, bool) or not p.is_file():
        raise ValueError(f"bar = {bar!r}: no {seal} file at that pressure (files: "
                         f"{sorted(q.name for q in ZILLEN2021.glob(seal + '_*'))})")
    return p


__all__ = ["ZILLEN2021", "ZILLEN2021_SEALS", "zillen2021_manifest", "zillen2021_file"]
