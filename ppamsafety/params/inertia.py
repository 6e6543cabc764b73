"""Inertial and friction parameters of the two links.

Two kinds of parameter set live here:

* **Identified base parameters** (thesis Table 3.5, dynamic identification
  with friction; Table 3.1, static gravity identification).  These are what
  the thesis' controllers use as their *model*.  They are not physically
  consistent: theta3 = I_zO,1 + m2 L1^2 = 0.0181 kg m^2 is smaller than
  m2 L1^2 alone (about 0.09 kg m^2), so the identified inertia matrix is
  indefinite in most of the working area.
* **Physical link parameters** (masses, centres of gravity, centroidal
  inertias) for the *plant*: they give a positive-definite inertia matrix for
  every q and satisfy the parallel-axis relations.  They are derived by
  :func:`derive_physical_links`, a documented weighted least-squares
  reconciliation of everything the thesis says about the links:

  ===========================  ====================  =======================
  quantity                     value                 source
  ===========================  ====================  =======================
  m1                           1.5 +- 0.15 kg        §6.3.3 "around 1.5 kg"
  m2                           1.05 +- 0.10 kg       §6.3.3 "just over 1 kg"
  L_G1, d_G1                   192, 0 +- 20 mm       Table 2.2 (CAD, "not very accurate")
  L_G2, d_G2                   196, 2 +- 20 mm       Table 2.2 (CAD)
  m1 L_G1 + m2 L1              0.5267 / 0.5238 kg m  Tables 3.1 / 3.5
  m2 L_G2                      0.2943 / 0.3028 kg m  Tables 3.1 / 3.5
  m2 d_G2                      0.0570 / 0.0153 kg m  Tables 3.1 / 3.5
  m1 d_G1                      -0.0806 / -0.1400     Tables 3.1 / 3.5
  ===========================  ====================  =======================

  Each identified first moment enters as the mean of its static and dynamic
  estimate with standard deviation max(|static - dynamic|, 0.005 kg m): the
  gravity terms that both identifications agree on (m1 L_G1 + m2 L1 to
  0.6 %) dominate, the poorly identified offsets (d_G1, d_G2) are pulled
  towards the CAD values.  The masses, CAD positions and gravity terms are
  mutually inconsistent in the thesis (m2 L_G2 = 0.30 kg m needs
  m2 = 1.55 kg at the CAD L_G2 = 196 mm), so the reconciliation is a
  compromise by construction; :func:`derive_physical_links` returns the
  residuals so the compromise is visible.

  Centroidal inertias are not identifiable from the thesis (its identified
  inertias are inconsistent).  We model each link as a slender bar over its
  physical extent, I_G = m k^2 with radius of gyration k = extent/sqrt(12):
  link 1 spans about 0.375 m (base bearing to the muscle-3 attachment at
  L32 = 334.8 mm), link 2 about 0.36 m (elbow bearing to the tool).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .._validation import check_instance, check_range, check_vector
from ..units import MM


def _check_friction(obj) -> None:
    """Validate and store the per-joint friction pairs of ``obj`` (2 non-negative entries)."""
    cls = type(obj).__name__
    for name, unit in (("coulomb", "N m"), ("viscous", "N m s/rad")):
        object.__setattr__(obj, name, check_vector(f"{cls}.{name}", getattr(obj, name), 2,
                                                   0.0, 100.0, unit=unit))


def _set_ranges(obj, spec) -> None:
    """Validate and store float fields: ``spec`` is (field, lo, hi, lo_open, unit) tuples."""
    cls = type(obj).__name__
    for name, lo, hi, lo_open, unit in spec:
        object.__setattr__(obj, name, check_range(f"{cls}.{name}", getattr(obj, name), lo, hi,
                                                  lo_open=lo_open, unit=unit))


@dataclass(frozen=True)
class BaseParameters:
    """Base parameters theta of (B.5)/(B.6) plus friction (3.30).

    Attributes
    ----------
    m1LG1_m2L1 : float
        theta1 = m1 L_G1 + m2 L1 [kg m].
    m1dG1 : float
        theta2 = m1 d_G1 [kg m].
    IO1_m2L1sq : float
        theta3 = I_zO,1 + m2 L1^2 [kg m^2].
    m2LG2 : float
        theta4 = m2 L_G2 [kg m].
    m2dG2 : float
        theta5 = m2 d_G2 [kg m].
    IS2 : float
        theta6 = I_zS,2 [kg m^2].
    coulomb : tuple of 2 float
        Coulomb friction c per joint [N m].
    viscous : tuple of 2 float
        Viscous friction b per joint [N m s/rad].

    Notes
    -----
    Ranges: first moments [-10, 10] kg m, theta3 and theta6 (0, 100] kg m^2,
    friction [0, 100].  The inertia matrix built from identified parameters
    may be indefinite (thesis Table 3.5 is); this is *not* refused, because the
    controllers use them as the thesis did.
    """

    m1LG1_m2L1: float
    m1dG1: float
    IO1_m2L1sq: float
    m2LG2: float
    m2dG2: float
    IS2: float
    coulomb: tuple = (0.0, 0.0)
    viscous: tuple = (0.0, 0.0)

    def __post_init__(self):
        # Identified parameters need not be physically consistent (Table 3.5 gives an
        # indefinite inertia matrix, see the module docstring), so only signs that every
        # identification must get right are enforced: theta3, theta6 > 0.
        _set_ranges(self, (("m1LG1_m2L1", -10.0, 10.0, False, "kg m"),
                           ("m1dG1", -10.0, 10.0, False, "kg m"),
                           ("IO1_m2L1sq", 0.0, 100.0, True, "kg m^2"),
                           ("m2LG2", -10.0, 10.0, False, "kg m"),
                           ("m2dG2", -10.0, 10.0, False, "kg m"),
                           ("IS2", 0.0, 100.0, True, "kg m^2")))
        _check_friction(self)

    def as_vector(self) -> np.ndarray:
        """theta as in (B.5): [theta1 .. theta6]."""
        return np.array([self.m1LG1_m2L1, self.m1dG1, self.IO1_m2L1sq,
                         self.m2LG2, self.m2dG2, self.IS2])

    def replace(self, **changes) -> "BaseParameters":
        """Return a copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            New values of fields of :class:`BaseParameters`, by field name (as for
            :func:`dataclasses.replace`); the copy is checked like a newly
            constructed object.
        """
        return replace(self, **changes)


@dataclass(frozen=True)
class LinkInertia:
    """Physical mass properties of both links.

    Attributes
    ----------
    m1, m2 : float
        Link masses [kg].
    LG1, dG1, LG2, dG2 : float
        Centre-of-gravity coordinates along / perpendicular to each link,
        with the sign convention of fig. 2.9 and (B.1) [m].
    IG1, IG2 : float
        Centroidal moments of inertia about z [kg m^2].
    coulomb, viscous : tuple of 2 float
        Joint friction (3.30) [N m], [N m s/rad].

    Notes
    -----
    Positive masses and centroidal inertias make the inertia matrix positive
    definite for *every* q: the kinetic energy
    1/2 (IG1 w1^2 + IG2 (w1 + w2)^2 + m1 |v_G1|^2 + m2 |v_G2|^2) vanishes only
    for w = 0.  (Equivalently det H = theta3 theta6 - L1^2 m2^2 (L_G2 cos q2 +
    d_G2 sin q2)^2 > 0 because theta3 > m2 L1^2 and theta6 > m2 (L_G2^2 + d_G2^2).)
    :class:`~ppamsafety.params.ArmParameters` additionally refuses a matrix
    that is numerically near singular in the working area.
    Ranges: masses (0, 100] kg, CoG coordinates [-2, 2] m, inertias
    (0, 100] kg m^2, friction [0, 100].
    """

    m1: float
    m2: float
    LG1: float
    dG1: float
    LG2: float
    dG2: float
    IG1: float
    IG2: float
    coulomb: tuple = (0.0, 0.0)
    viscous: tuple = (0.0, 0.0)

    def __post_init__(self):
        _set_ranges(self, (("m1", 0.0, 100.0, True, "kg"), ("m2", 0.0, 100.0, True, "kg"),
                           ("LG1", -2.0, 2.0, False, "m"), ("dG1", -2.0, 2.0, False, "m"),
                           ("LG2", -2.0, 2.0, False, "m"), ("dG2", -2.0, 2.0, False, "m"),
                           ("IG1", 0.0, 100.0, True, "kg m^2"),
                           ("IG2", 0.0, 100.0, True, "kg m^2")))
        _check_friction(self)

    def base_parameters(self, L1: float) -> BaseParameters:
        """Base parameters (B.5) by the parallel-axis (Steiner) relations.

        Parameters
        ----------
        L1 : float
            Upper-arm length [m], in (0, 5].
        """
        L1 = check_range("L1", L1, 0.0, 5.0, lo_open=True, unit="m")
        IO1 = self.IG1 + self.m1 * (self.LG1 ** 2 + self.dG1 ** 2)
        IS2 = self.IG2 + self.m2 * (self.LG2 ** 2 + self.dG2 ** 2)
        return BaseParameters(
            m1LG1_m2L1=self.m1 * self.LG1 + self.m2 * L1, m1dG1=self.m1 * self.dG1,
            IO1_m2L1sq=IO1 + self.m2 * L1 ** 2, m2LG2=self.m2 * self.LG2,
            m2dG2=self.m2 * self.dG2, IS2=IS2, coulomb=self.coulomb, viscous=self.viscous)

    def replace(self, **changes) -> "LinkInertia":
        """Return a copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            New values of fields of :class:`LinkInertia`, by field name (as for
            :func:`dataclasses.replace`); the copy is checked like a newly
            constructed object.
        """
        return replace(self, **changes)


def identified_dynamic() -> BaseParameters:
    """Thesis Table 3.5, estimate *including friction* (the one withheld)."""
    return BaseParameters(m1LG1_m2L1=0.5238, m1dG1=-0.1400, IO1_m2L1sq=0.0181,
                          m2LG2=0.3028, m2dG2=0.0153, IS2=0.0185,
                          coulomb=(0.0302, 0.0712), viscous=(0.8294, 0.0037))


def identified_static_gravity() -> BaseParameters:
    """Thesis Table 3.1 gravity parameters (static identification, §3.5.1.3).

    Only the first moments are identified statically; the inertial entries
    are copied from Table 3.5 so the object is complete.  Used by the static
    gravity compensation (3.18)-(3.19) as in §3.5.1.5.
    """
    dyn = identified_dynamic()
    return dyn.replace(m1LG1_m2L1=0.5267, m2LG2=0.2943, m2dG2=0.0570, m1dG1=-0.0806)


#: Priors of the reconciliation (value, standard deviation), see module doc.
LINK_PRIORS = {
    "m1": (1.5, 0.15), "m2": (1.05, 0.10),
    "LG1": (192.0 * MM, 20.0 * MM), "dG1": (0.0, 20.0 * MM),
    "LG2": (196.0 * MM, 20.0 * MM), "dG2": (2.0 * MM, 20.0 * MM),
}
#: Radii of gyration about the centre of gravity [m] (slender-bar model).
RADIUS_OF_GYRATION = (0.375 / math.sqrt(12.0), 0.36 / math.sqrt(12.0))


@dataclass(frozen=True)
class LinkDerivation:
    """Result of :func:`derive_physical_links` with its evidence.

    Attributes
    ----------
    links : LinkInertia
        The reconciled physical links.
    residuals : dict
        ``{evidence name: (fitted, target, sigma)}`` for every prior and
        identified first moment of the fit (SI units of the quantity).
    """

    links: LinkInertia
    residuals: dict   # name -> (fitted, target, sigma)


def derive_physical_links(*, L1: float = 0.3, static: BaseParameters | None = None,
                          dynamic: BaseParameters | None = None) -> LinkDerivation:
    """Reconcile masses, CAD centres of gravity and identified gravity terms.

    Weighted nonlinear least squares over (m1, m2, L_G1, d_G1, L_G2, d_G2)
    with the priors of :data:`LINK_PRIORS` and the identified first moments of
    Tables 3.1 and 3.5 (see the module docstring for the weighting).  Friction
    is taken from Table 3.5.

    Parameters
    ----------
    L1 : float
        Upper-arm length [m].
    static, dynamic : BaseParameters, optional
        Identified sets; default to the thesis Tables 3.1 and 3.5.

    Returns
    -------
    LinkDerivation
        The physical links and, for every piece of evidence, the fitted value,
        the target and its standard deviation.
    """
    from scipy.optimize import least_squares

    L1 = check_range("L1", L1, 0.0, 5.0, lo_open=True, unit="m")
    static = identified_static_gravity() if static is None else check_instance(
        "static", static, BaseParameters)
    dynamic = identified_dynamic() if dynamic is None else check_instance(
        "dynamic", dynamic, BaseParameters)
    keys = ("m1", "m2", "LG1", "dG1", "LG2", "dG2")
    prior = np.array([LINK_PRIORS[k][0] for k in keys])
    prior_sd = np.array([LINK_PRIORS[k][1] for k in keys])

    def moments(x):
        m1, m2, LG1, dG1, LG2, dG2 = x
        return np.array([m1 * LG1 + m2 * L1, m2 * LG2, m2 * dG2, m1 * dG1])

    s, d = static, dynamic
    meas_s = np.array([s.m1LG1_m2L1, s.m2LG2, s.m2dG2, s.m1dG1])
    meas_d = np.array([d.m1LG1_m2L1, d.m2LG2, d.m2dG2, d.m1dG1])
    target = 0.5 * (meas_s + meas_d)
    sd = np.maximum(np.abs(meas_s - meas_d), 0.005)

    def residual(x):
        return np.concatenate([(x - prior) / prior_sd, (moments(x) - target) / sd])

    sol = least_squares(residual, prior, method="lm")
    k1, k2 = RADIUS_OF_GYRATION
    m1, m2, LG1, dG1, LG2, dG2 = (float(v) for v in sol.x)
    links = LinkInertia(m1=m1, m2=m2, LG1=LG1, dG1=dG1, LG2=LG2, dG2=dG2,
                        IG1=m1 * k1 ** 2, IG2=m2 * k2 ** 2,
                        coulomb=dynamic.coulomb, viscous=dynamic.viscous)
    names = ["m1 [kg]", "m2 [kg]", "L_G1 [m]", "d_G1 [m]", "L_G2 [m]", "d_G2 [m]",
             "m1 L_G1 + m2 L1 [kg m]", "m2 L_G2 [kg m]", "m2 d_G2 [kg m]", "m1 d_G1 [kg m]"]
    fitted = np.concatenate([sol.x, moments(sol.x)])
    targets = np.concatenate([prior, target])
    sds = np.concatenate([prior_sd, sd])
    residuals = {n: (float(f), float(t), float(sd_)) for n, f, t, sd_ in
                 zip(names, fitted, targets, sds)}
    return LinkDerivation(links=links, residuals=residuals)


__all__ = ["BaseParameters", "LinkInertia", "LinkDerivation", "identified_dynamic",
           "identified_static_gravity", "derive_physical_links", "LINK_PRIORS",
           "RADIUS_OF_GYRATION"]
