"""Measured data: the file format, loading and validation, identification from files.

* :mod:`.measured` -- the format (CSV or Parquet + TOML metadata, SI units,
  ``docs/measured_data.md``), :class:`MeasuredData`, :func:`load_measured`.
* :mod:`.identification` -- :func:`identify_measured` (``ppamsafety identify``).
* :mod:`.synthetic` -- synthetic records (static equilibria, tensile test,
  open-loop excitation) for tests, examples and the discrepancy workflow.
"""

from .identification import Identification, identify_measured
from .measured import (MeasuredData, MeasuredDataError, MeasuredDataWarning, load_measured,
                       read_metadata)
from .synthetic import synthetic_excitation, synthetic_static, synthetic_tensile

__all__ = ["MeasuredData", "MeasuredDataError", "MeasuredDataWarning", "load_measured",
           "read_metadata", "Identification", "identify_measured", "synthetic_static",
           "synthetic_tensile", "synthetic_excitation"]
