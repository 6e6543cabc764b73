"""Measured data: the file format, loading and validation, identification from files.

* :mod:`.measured` -- the format (CSV or Parquet + TOML metadata, SI units,
  ``docs/measured_data.md``), :class:`MeasuredData`, :func:`load_measured`.
* :mod:`.identification` -- :func:`identify_measured` (``ppamsafety identify``).
* :mod:`.bench_import` -- :func:`import_bench`: a raw bench file (any units,
  signs, offsets, no header) into the format, with an import profile.
* :mod:`.campaign` -- :class:`Campaign`, :func:`load_campaign`: several records
  of one actuator (a manifest), diagnosed together.
* :mod:`.datasets` -- real bench data shipped with the package (CC0).
* :mod:`.synthetic` -- synthetic records (static equilibria, tensile test,
  open-loop excitation) for tests, examples and the discrepancy workflow.
"""

from .bench_import import Actuator, BenchProfile, import_bench
from .campaign import Campaign, load_campaign
from .identification import Identification, identify_measured
from .measured import (MeasuredData, MeasuredDataError, MeasuredDataWarning, load_measured,
                       read_metadata)
from .synthetic import synthetic_excitation, synthetic_static, synthetic_tensile

__all__ = ["MeasuredData", "MeasuredDataError", "MeasuredDataWarning", "load_measured",
           "read_metadata", "Identification", "identify_measured", "synthetic_static",
           "synthetic_tensile", "synthetic_excitation", "BenchProfile", "Actuator",
           "import_bench", "Campaign", "load_campaign"]
