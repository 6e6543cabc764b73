"""Injury tolerances of the head: fracture forces and the HIC -> AIS risk curves, cited.

Data only (the formulas that use them are in :mod:`ppamsafety.impact.verdicts`).  Every
value carries its source and whether a public source we read confirms it (the pain-onset
limits of ISO/TS 15066 are in :mod:`ppamsafety.params.iso_ts_15066`).

Fracture forces of the skull and face (:data:`FRACTURE_FORCES`):

* maxilla 660 N -- the weakest bone of the face; thesis §6.3.3 quotes it from Haddadin et
  al. (2007a), and it is the thesis's own safety line;
* mandible 1.78 kN (anterior-posterior) and frontal bone about 4 kN -- the values the
  robotics literature quotes beside the maxilla (Haddadin et al. 2007a, RSS; after the
  cadaver impact tests of Nahum et al. 1968 and Allsop et al. 1988); not confirmed against
  a source we could read here.

HIC to the probability of an injury of level AIS >= n (:data:`AIS_RISK`): the lognormal
risk curves of the US National Highway Traffic Safety Administration,

    P(AIS >= n | HIC) = Phi((ln HIC - mu_n) / sigma_n),

Phi the standard normal distribution function, with (Kleinberger et al. 1998, NHTSA,
"Development of Improved Injury Criteria for the Assessment of Advanced Automotive
Restraint Systems", §2.3; Eppinger et al. 1999, part II; the AIS 3+ curve is the one NHTSA's
NCAP uses with HIC15, 73 FR 40016, 2008):

=======  ========  ========
level    mu        sigma
=======  ========  ========
AIS 2+   6.96352   0.84664
AIS 3+   7.45231   0.73998
AIS 4+   7.65605   0.60580
=======  ========  ========

(coefficients confirmed by a public transcription: a crash-metrics script citing NHTSA 1999
and Kuppa 2004).  The curves were fitted to car-crash data (long pulses, high speeds): the
thesis (§6.3.3, after Haddadin et al. 2007b) warns that they overstate the risk of the
short, low-speed robot impacts; they are shown for comparison, never as a pass/fail line.
"""

from __future__ import annotations

from dataclasses import dataclass

from .head import HIC_SERIOUS_5PCT, MAXILLA_FRACTURE_N


@dataclass(frozen=True)
class Tolerance:
    """A cited injury tolerance (a force or an HIC value).

    Attributes
    ----------
    name : str
        Short name.
    value : float
        The tolerance [SI unit of ``unit``].
    unit : str
        ``"N"`` or ``""`` (HIC).
    label : str
        What it is.
    source : str
        Citation.
    confirmed : bool
        A public source we read prints it.
    """

    name: str
    value: float
    unit: str
    label: str
    source: str
    confirmed: bool


#: Fracture forces of the head's bones [N].
FRACTURE_FORCES = {
    "maxilla": Tolerance("maxilla", MAXILLA_FRACTURE_N, "N",
                         f"maxilla fracture {MAXILLA_FRACTURE_N:g} N",
                         "Haddadin et al. 2007a, quoted in thesis §6.3.3", True),
    "mandible": Tolerance("mandible", 1780.0, "N", "mandible fracture (A-P) 1.78 kN",
                          "Haddadin et al. 2007a (after Nahum et al. 1968); not confirmed "
                          "against a source read here", False),
    "frontal bone": Tolerance("frontal bone", 4000.0, "N", "frontal bone fracture about 4 kN",
                              "Haddadin et al. 2007a (after Nahum et al. 1968, Allsop et al. "
                              "1988); not confirmed against a source read here", False),
}

#: HIC36 of a 5 % risk of AIS 3+ (thesis §6.3.3, after Haddadin et al. 2007b).
HIC36_LIMIT = Tolerance("HIC36", HIC_SERIOUS_5PCT, "",
                        f"HIC36 {HIC_SERIOUS_5PCT:g} (5 % risk of AIS 3+)",
                        "thesis §6.3.3, after Haddadin et al. 2007b (automotive mapping)",
                        True)

#: Source of the AIS risk curves.
AIS_SOURCE = ("NHTSA lognormal head risk curves: Kleinberger et al. 1998 (NHTSA, Development "
              "of Improved Injury Criteria for the Assessment of Advanced Automotive Restraint "
              "Systems, §2.3), Eppinger et al. 1999 (part II); AIS 3+ with HIC15 in NCAP, "
              "73 FR 40016 (2008)")
#: AIS level -> (mu, sigma) of P(AIS >= level) = Phi((ln HIC - mu) / sigma).
AIS_RISK = {2: (6.96352, 0.84664), 3: (7.45231, 0.73998), 4: (7.65605, 0.60580)}

__all__ = ["Tolerance", "FRACTURE_FORCES", "HIC36_LIMIT", "AIS_SOURCE", "AIS_RISK"]
