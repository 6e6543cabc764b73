"""What every record kind shares before its residuals: the segment a diagnosis analyses."""

from __future__ import annotations


def longest_segment(data) -> tuple:
    """The longest gap-free segment of a record, the one a diagnosis analyses.

    Parameters
    ----------
    data : MeasuredData
        A loaded record (``data.segments``: row ranges split at gaps).

    Returns
    -------
    a, b : int
        First and one-past-last row.
    notes : list of str
        A note naming the segment when the record has more than one.
    """
    a, b = max(data.segments, key=lambda s: s[1] - s[0])
    notes = []
    if len(data.segments) > 1:
        notes.append(f"the record has {len(data.segments)} gap-free segments; the longest "
                     f"(rows {a}..{b - 1}) is diagnosed")
    return a, b, notes


__all__ = ["longest_segment"]
