"""ppamsafety: safety and impact analysis of PPAM-driven compliant arms.

Start with :func:`ppamsafety.params.thesis_arm` for the cited parameter set of the
thesis arm, :mod:`ppamsafety.plant` for the physics, and the ``ppamsafety report``
command for the full report.
"""

from ._version import __version__

__all__ = ["__version__"]
