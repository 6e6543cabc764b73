"""Shared pieces of the property-based tests (tests/test_properties*.py), issue 8.

* Strategies of mostly invalid input: wrong types, special floats, numbers.
* :class:`Recorder`: runs one call of a public entry point and requires either a
  ``TypeError``/``ValueError`` whose message names the argument, or a result (the
  caller then checks that it is finite and sane); it counts both per entry point and
  prints the table at the end of the module.  With ``PPAMSAFETY_PROPERTY_COUNTS`` set to a
  folder, the table is also written there as ``property_counts_<tag>.txt``.
"""

import math
import os
import re
import warnings
from collections import Counter, defaultdict
from pathlib import Path

from hypothesis import strategies as st

bad_types = st.one_of(st.text(max_size=4), st.none(), st.dictionaries(st.text(max_size=2),
                                                                      st.integers(), max_size=2),
                      st.complex_numbers(allow_nan=False, max_magnitude=1e3).filter(
                          lambda z: z.imag != 0), st.booleans(),
                      st.lists(st.lists(st.floats(), max_size=2), min_size=1, max_size=2))
SPECIAL_VALUES = [math.nan, math.inf, -math.inf, 0.0, -0.0, -1.0, 1e-300, 1e300, -1e300,
                  10 ** 400]
special = st.sampled_from(SPECIAL_VALUES)
numbers = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                    st.floats(-10.0, 10.0), st.integers(-10 ** 6, 10 ** 6))
anything = st.one_of(bad_types, special, numbers)


class Recorder:
    """Counts clear errors and sane results per entry point (see the module docstring).

    Parameters
    ----------
    tag : str
        Name of the counts file (``property_counts_<tag>.txt``).
    ignore : tuple of Warning classes
        Warnings silenced while a call runs (e.g. the documented ``UserWarning`` s of
        implausible-but-allowed input).
    """

    def __init__(self, tag, *, ignore=()):
        self.tag = tag
        self.ignore = tuple(ignore)
        self.counts = defaultdict(Counter)

    def outcome(self, entry, call, *names):
        """Run ``call``; a clear error must name one of ``names``.  Returns the result or None."""
        try:
            with warnings.catch_warnings():
                for w in self.ignore:
                    warnings.simplefilter("ignore", w)
                result = call()
        except (TypeError, ValueError) as exc:
            msg = str(exc)
            assert any(re.search(rf"(?<![A-Za-z0-9_]){re.escape(n)}(?![A-Za-z0-9_])", msg)
                       for n in names), f"{entry}: message does not name {names}: {msg!r}"
            self.counts[entry]["error"] += 1
            return None
        self.counts[entry]["sane"] += 1
        return result

    def report(self):
        """Print the table of counts (and write it where ``PPAMSAFETY_PROPERTY_COUNTS`` says)."""
        c = self.counts
        lines = [f"{'entry point':45s} {'examples':>8s} {'clear error':>11s} {'sane result':>11s}"]
        for entry in sorted(c):
            e, s = c[entry]["error"], c[entry]["sane"]
            lines.append(f"{entry:45s} {e + s:8d} {e:11d} {s:11d}")
        tot_e = sum(v["error"] for v in c.values())
        tot_s = sum(v["sane"] for v in c.values())
        lines.append(f"{'total':45s} {tot_e + tot_s:8d} {tot_e:11d} {tot_s:11d}")
        text = "\n".join(lines)
        print("\n" + text)
        folder = os.environ.get("PPAMSAFETY_PROPERTY_COUNTS")
        if folder:
            Path(folder).mkdir(parents=True, exist_ok=True)
            (Path(folder) / f"property_counts_{self.tag}.txt").write_text(text + "\n")
