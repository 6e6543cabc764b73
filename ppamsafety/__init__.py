"""ppamsafety: safety and impact analysis of PPAM-driven compliant arms.

Start with :func:`ppamsafety.params.thesis_arm` for the cited parameter set of the
thesis arm, :mod:`ppamsafety.plant` for the physics, and the ``ppamsafety report``
command for the full report.
"""

__version__ = "0.1.0"
