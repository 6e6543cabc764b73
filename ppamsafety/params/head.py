"""Tolerance data of the human head.

The head *contact models* (mass, radius, Hunt-Crossley parameters) are in
:mod:`ppamsafety.impact.head`, where each is checked against the contact law.
"""

#: Maxilla fracture tolerance [N] (Haddadin et al. 2007a, quoted in thesis §6.3.3).
MAXILLA_FRACTURE_N = 660.0

__all__ = ["MAXILLA_FRACTURE_N"]
