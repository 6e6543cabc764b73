"""Tolerance data of the human head.

The head *contact models* (mass, radius, Hunt-Crossley parameters) are in
:mod:`ppamsafety.impact.head`, where each is checked against the contact law.
"""

#: Maxilla fracture tolerance [N] (Haddadin et al. 2007a, quoted in thesis §6.3.3).
MAXILLA_FRACTURE_N = 660.0
#: HIC36 of a 5 % risk of an injury classified "serious" or worse on the Abbreviated Injury
#: Scale (thesis §6.3.3, quoting Haddadin et al. 2007b; automotive mapping, which the thesis
#: notes overstates the risk of low-speed robot impacts).
HIC_SERIOUS_5PCT = 650.0

__all__ = ["MAXILLA_FRACTURE_N", "HIC_SERIOUS_5PCT"]
