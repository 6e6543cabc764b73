"""Contact layers in series: the robot's covering, a body region's tissue and bone, contact points.

A contact between the arm and a person is a stack of compliant layers in series that share one
force: the robot's *covering* (none for bare metal) on the arm side, the body region's *soft
tissue* and *bone* on the person's side.  Each layer is a :class:`Layer` with one elastic law
and a Hunt-Crossley hysteresis; the physics that puts them in series is
:mod:`ppamsafety.impact.layers`.  This module holds the data only: layers, coverings
(:class:`Covering`), body regions' contact models (:class:`BodyContact`: effective mass,
curvature, layers) and contact points on the arm (:class:`ContactPoint`: link, position,
surface shape, covering), each named and cited, immutable and checked on construction.

Elastic laws of a layer (SI units; R_e is the effective radius of the contact, set by the
body's curvature and the robot surface's shape, :func:`ppamsafety.impact.layers.effective_radius`):

* ``"thin-layer"`` -- a layer of thickness h on a rigid backing, wide contact (contact radius
  much larger than h: a robot's foam or rubber covering, the scalp on the skull): each column
  of the layer is a spring of stiffness E/h (Winkler foundation), so a sphere-like indenter
  gives F = pi E R_e delta^2 / h (exponent 2);
* ``"hertz"`` -- an elastic half-space (a layer much thicker than the contact radius, bone):
  F = (4/3) E / (1 - nu^2) sqrt(R_e) delta^(3/2) (Hertz 1882; Johnson, *Contact Mechanics*,
  1985, ch. 4);
* ``"power"`` -- F = k delta^n with k and n given (a fitted law independent of the geometry,
  e.g. the thesis' head contact, or the linear spring of ISO/TS 15066 Annex A with n = 1).

Each layer may *bottom out*: a layer of thickness h compresses at most ``strain_limit`` x h
(a foam densifies, a tissue is squeezed onto the bone); beyond it the layer is rigid and the
layers behind it take the rest.  The innermost layer of a body (the bone) has no limit.

Damping.  A material layer carries a Hunt-Crossley hysteresis factor alpha [s/m]: the layer's
force is its elastic force times (1 + alpha d(delta)/dt) (Hunt & Crossley 1975; for a single
layer alpha = 3 (1 - e) / (2 v) gives the restitution e at the impact speed v, Lankarani &
Nikravesh 1990).  A power-law layer carries the Hunt-Crossley b of the thesis' eq. (6.2)
directly (F = k delta^n + b delta^n d(delta)/dt), so a one-layer stack *is* the thesis' law.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from .._validation import check_choice, check_int, check_range, check_str, did_you_mean
from .arm import LINK_EXTENT_FACTOR

#: Elastic laws of a :class:`Layer` (module docstring).
LAWS = ("thin-layer", "hertz", "power")
#: Robot surface shapes at a contact point: principal radii of the surface (r across, r along
#: the link): ``sphere`` (r, r) -- an end cap, a joint housing; ``cylinder`` (r, inf) -- the
#: side of a tubular link; ``edge`` (r, inf) -- an edge of radius r (a bracket, a face's rim);
#: ``flat`` (inf, inf) -- a flat face.
SHAPES = ("sphere", "cylinder", "edge", "flat")
#: Largest number of layers of one contact (covering layers plus body layers).
MAX_LAYERS = 4


def _num(name, value, lo, hi, *, lo_open=False, unit="", allow_inf=False):
    """A checked number; ``inf`` passes when ``allow_inf``."""
    if allow_inf and isinstance(value, (int, float)) and not isinstance(value, bool) \
            and value == math.inf:
        return math.inf
    return check_range(name, value, lo, hi, lo_open=lo_open, unit=unit)


@dataclass(frozen=True)
class Layer:
    """One compliant layer of a contact: its elastic law, hysteresis and thickness.

    Attributes
    ----------
    name : str
        Label (``"PU foam"``, ``"forehead soft tissue"``, ``"frontal bone"``).
    law : {"thin-layer", "hertz", "power"}
        Elastic law (module docstring).
    modulus : float
        Young's modulus E [Pa] (``"thin-layer"``: the layer's compressive modulus; ``"hertz"``),
        in (0, 1e12]; NaN for ``"power"``.
    poisson : float
        Poisson's ratio nu [-] (``"hertz"`` only), in [0, 0.5).
    thickness : float
        Layer thickness h [m], in (0, 1] (required for ``"thin-layer"``); ``inf``: a half-space
        that never bottoms out.
    strain_limit : float
        The layer bottoms out at a compression of ``strain_limit`` x ``thickness`` [-], in
        (0, 1] (foams densify near 0.6-0.8, Gibson & Ashby, *Cellular Solids*, 1997).
    hysteresis : float
        Hunt-Crossley hysteresis factor alpha [s/m] of a material law, in [0, 100]: the force
        is the elastic force times (1 + alpha d(delta)/dt).
    stiffness : float
        k [N/m^n] of a ``"power"`` law, in (0, 1e20]; NaN otherwise.
    exponent : float
        n [-] of a ``"power"`` law, in [1, 3]; NaN otherwise.
    damping : float
        Hunt-Crossley b [N s/m^(n+1)] of a ``"power"`` law (thesis eq. 6.2), in [0, 1e20].
    source : str
        Where the values come from.
    """

    name: str
    law: str
    modulus: float = math.nan
    poisson: float = 0.0
    thickness: float = math.inf
    strain_limit: float = 1.0
    hysteresis: float = 0.0
    stiffness: float = math.nan
    exponent: float = math.nan
    damping: float = 0.0
    source: str = field(default="", compare=False)

    def __post_init__(self):
        check_str("Layer.name", self.name, allow_empty=False)
        check_str("Layer.source", self.source)
        check_choice(f"Layer.law (layer {self.name!r})", self.law, LAWS)
        w = f" (layer {self.name!r})"
        t = _num(f"Layer.thickness{w}", self.thickness, 0.0, 1.0, lo_open=True, unit="m",
                 allow_inf=True)
        object.__setattr__(self, "thickness", t)
        object.__setattr__(self, "strain_limit", check_range(
            f"Layer.strain_limit{w}", self.strain_limit, 0.0, 1.0, lo_open=True))
        if self.law == "power":
            for attr in ("modulus",):
                if not (isinstance(getattr(self, attr), float) and math.isnan(getattr(self, attr))):
                    raise ValueError(f"Layer.{attr}{w} is not used by the 'power' law (give "
                                     f"stiffness, exponent and damping)")
            if self.hysteresis != 0.0:
                raise ValueError(f"Layer.hysteresis{w}: a 'power' law carries its damping as the "
                                 f"Hunt-Crossley b (Layer.damping), not alpha")
            object.__setattr__(self, "stiffness", check_range(
                f"Layer.stiffness{w}", self.stiffness, 0.0, 1e20, lo_open=True, unit="N/m^n"))
            object.__setattr__(self, "exponent", check_range(
                f"Layer.exponent{w}", self.exponent, 1.0, 3.0))
            object.__setattr__(self, "damping", check_range(
                f"Layer.damping{w}", self.damping, 0.0, 1e20, unit="N s/m^(n+1)"))
        else:
            for attr in ("stiffness", "exponent"):
                if not (isinstance(getattr(self, attr), float) and math.isnan(getattr(self, attr))):
                    raise ValueError(f"Layer.{attr}{w} is only for the 'power' law; a "
                                     f"{self.law!r} layer takes modulus (and thickness)")
            if self.damping != 0.0:
                raise ValueError(f"Layer.damping{w} is the b of a 'power' law; a {self.law!r} "
                                 f"layer takes its damping as Layer.hysteresis (alpha, s/m)")
            object.__setattr__(self, "modulus", check_range(
                f"Layer.modulus{w}", self.modulus, 0.0, 1e12, lo_open=True, unit="Pa"))
            object.__setattr__(self, "poisson", check_range(
                f"Layer.poisson{w}", self.poisson, 0.0, 0.5, hi_open=True))
            object.__setattr__(self, "hysteresis", check_range(
                f"Layer.hysteresis{w}", self.hysteresis, 0.0, 100.0, unit="s/m"))
            if self.law == "thin-layer" and t == math.inf:
                raise ValueError(f"Layer.thickness{w}: a 'thin-layer' law needs a finite "
                                 f"thickness (F = pi E R delta^2 / h)")

    @property
    def limit(self) -> float:
        """Largest compression of the layer [m] (``inf``: never bottoms out)."""
        return self.strain_limit * self.thickness

    def replace(self, **changes) -> "Layer":
        """A copy with some fields changed (checked again).

        Parameters
        ----------
        **changes
            New values of fields, by name.
        """
        return replace(self, **changes)


def _layers(name, layers) -> tuple:
    if isinstance(layers, Layer) or isinstance(layers, (str, bytes)) \
            or not isinstance(layers, (tuple, list)):
        raise TypeError(f"{name} must be a tuple of Layer, got {type(layers).__name__}")
    out = tuple(layers)
    for i, lay in enumerate(out):
        if not isinstance(lay, Layer):
            raise TypeError(f"{name}[{i}] must be a Layer, got {type(lay).__name__}")
    return out


@dataclass(frozen=True)
class Covering:
    """The robot's covering at a contact point: layers on the link, outermost first.

    Attributes
    ----------
    name : str
        Label.
    layers : tuple of Layer
        Outermost first; empty: bare metal (a rigid surface: the body's own layers take the
        whole compression).  Every covering layer must have a finite thickness (a covering
        bottoms out on the link).
    source : str
        Where it comes from.
    """

    name: str
    layers: tuple = ()
    source: str = field(default="", compare=False)

    def __post_init__(self):
        check_str("Covering.name", self.name, allow_empty=False)
        check_str("Covering.source", self.source)
        lays = _layers(f"Covering.layers (covering {self.name!r})", self.layers)
        if len(lays) > MAX_LAYERS - 1:
            raise ValueError(f"Covering.layers (covering {self.name!r}): at most "
                             f"{MAX_LAYERS - 1} layers (a contact has at most {MAX_LAYERS})")
        for lay in lays:
            if lay.limit == math.inf:
                raise ValueError(f"Covering {self.name!r}: layer {lay.name!r} has no finite "
                                 f"thickness; a covering layer lies on the link and bottoms out "
                                 f"(give Layer.thickness)")
        object.__setattr__(self, "layers", lays)

    @property
    def bare(self) -> bool:
        """No layer: the link's bare (rigid) surface."""
        return not self.layers

    @property
    def thickness(self) -> float:
        """Total thickness of the covering [m] (0 for bare metal)."""
        return float(sum(lay.thickness for lay in self.layers))

    def replace(self, **changes) -> "Covering":
        """A copy with some fields changed (checked again).

        Parameters
        ----------
        **changes
            New values of fields, by name.
        """
        return replace(self, **changes)


@dataclass(frozen=True)
class BodyContact:
    """The contact model of one body region: effective mass, curvature and layers.

    Attributes
    ----------
    name : str
        Label (the body region or location it models).
    mass : float
        Effective mass of the body region [kg], in (0, 200] (a free body of this mass is hit).
    radius : float
        Radius of curvature of the body surface hit [m], in [5 mm, 1 m]: sets the contact's
        effective radius (material laws, contact area) and where the body's centre starts.
    layers : tuple of Layer
        Outermost first (skin and soft tissue, then bone); at least one; the innermost has no
        thickness limit (``Layer.thickness = inf``, or a ``"power"`` law without thickness).
    source : str
        Where the values come from.
    checks : tuple of (str, bool, str)
        What the model is claimed to meet, ``(check, met, note)`` (e.g. the Hybrid III drop;
        recomputed by :func:`ppamsafety.impact.bodies.hybrid3_drop`).
    """

    name: str
    mass: float
    radius: float
    layers: tuple
    source: str = field(default="", compare=False)
    checks: tuple = field(default=(), compare=False)

    def __post_init__(self):
        check_str("BodyContact.name", self.name, allow_empty=False)
        check_str("BodyContact.source", self.source)
        w = f" (body {self.name!r})"
        object.__setattr__(self, "mass", check_range(f"BodyContact.mass{w}", self.mass, 0.0,
                                                     200.0, lo_open=True, unit="kg"))
        object.__setattr__(self, "radius", check_range(f"BodyContact.radius{w}", self.radius,
                                                       5e-3, 1.0, unit="m"))
        lays = _layers(f"BodyContact.layers{w}", self.layers)
        if not lays:
            raise ValueError(f"BodyContact.layers{w}: give at least one layer")
        if len(lays) > MAX_LAYERS:
            raise ValueError(f"BodyContact.layers{w}: at most {MAX_LAYERS} layers")
        if lays[-1].limit != math.inf:
            raise ValueError(f"BodyContact.layers{w}: the innermost layer ({lays[-1].name!r}) "
                             f"must not bottom out (thickness inf): something must stop the "
                             f"robot")
        object.__setattr__(self, "layers", lays)
        if not isinstance(self.checks, tuple):
            raise TypeError(f"BodyContact.checks{w} must be a tuple of (check, met, note)")

    def replace(self, **changes) -> "BodyContact":
        """A copy with some fields changed (checked again).

        Parameters
        ----------
        **changes
            New values of fields, by name.
        """
        return replace(self, **changes)


@dataclass(frozen=True)
class ContactPoint:
    """A point of the arm that can touch a person, with its surface and covering.

    The point is a material point of link ``link`` at distance ``position`` from that link's
    joint along the link axis (link 1 from the shoulder O, link 2 from the elbow S; the tool
    point is link 2 at L2, the elbow link 2 at 0).  The body is placed touching it, its centre
    along the point's velocity (the worst case, thesis fig. 6.2).

    Attributes
    ----------
    name : str
        Label (``"tool point"``, ``"elbow"``, ``"forearm"``, ``"upper arm"``).
    link : int
        1 or 2.
    position : float
        Distance from the link's joint along the link [m], in [0, 5].
    shape : {"sphere", "cylinder", "edge", "flat"}
        Robot surface at the point (:data:`SHAPES`).
    radius : float
        Radius of the surface [m], in [0.1 mm, 1 m] (``inf`` for ``"flat"``).
    covering : Covering
        The covering on the surface (``Covering("bare")``: bare metal).
    source : str
        Where the geometry comes from.
    """

    name: str
    link: int
    position: float
    shape: str
    radius: float
    covering: Covering
    source: str = field(default="", compare=False)

    def __post_init__(self):
        check_str("ContactPoint.name", self.name, allow_empty=False)
        check_str("ContactPoint.source", self.source)
        w = f" (contact point {self.name!r})"
        object.__setattr__(self, "link", check_int(f"ContactPoint.link{w}", self.link, 1, 2))
        object.__setattr__(self, "position", check_range(
            f"ContactPoint.position{w}", self.position, 0.0, 5.0, unit="m"))
        check_choice(f"ContactPoint.shape{w}", self.shape, SHAPES)
        if self.shape == "flat":
            if self.radius != math.inf:
                raise ValueError(f"ContactPoint.radius{w} = {self.radius!r}: a flat surface has "
                                 f"radius inf")
        else:
            object.__setattr__(self, "radius", check_range(
                f"ContactPoint.radius{w}", self.radius, 1e-4, 1.0, unit="m"))
        if not isinstance(self.covering, Covering):
            raise TypeError(f"ContactPoint.covering{w} must be a Covering, got "
                            f"{type(self.covering).__name__}")

    @property
    def radii(self) -> tuple:
        """Principal radii of the robot surface (across, along the link) [m]."""
        r = self.radius
        return {"sphere": (r, r), "cylinder": (r, math.inf), "edge": (r, math.inf),
                "flat": (math.inf, math.inf)}[self.shape]

    def replace(self, **changes) -> "ContactPoint":
        """A copy with some fields changed (checked again).

        Parameters
        ----------
        **changes
            New values of fields, by name.
        """
        return replace(self, **changes)


#: Bare metal: no covering (the link's own, rigid surface).
BARE = Covering("bare metal", (), source="no covering: the link's rigid surface")

# ---- the head: soft tissue over the frontal bone -------------------------------------------
#: Midline forehead soft-tissue thickness [m] of adult males, skin to the outer table of the
#: frontal bone (MRI of 160 adults: Cakmakoglu et al. 2025, Aesthetic Plastic Surgery,
#: doi:10.1007/s00266-025-04957-y; females 5.0 mm).
FOREHEAD_TISSUE_THICKNESS = 5.4e-3
#: Compressive modulus [Pa] of the forehead soft tissue as a thin layer on the skull:
#: calibrated so that the head meets the middle (250 g) of the Hybrid III head-drop corridor
#: (49 CFR 572.32, 225-275 g), rounded (:func:`ppamsafety.impact.bodies.calibrate_soft_tissue`
#: recomputes 15.53 MPa).  Plausibility: the tensile modulus of the human scalp measured by
#: Falland-Cheung et al. (2018) is 22.3 +- 9.3 MPa (fronto-parietal, mean +- SD, as tabulated
#: by the VIVA+ human body model documentation); 15.5 MPa lies within one SD, and the
#: measured mean gives 280 g in the drop (2 % above the corridor).
FOREHEAD_TISSUE_MODULUS = 15.5e6
#: Hunt-Crossley hysteresis factor of the soft tissue [s/m]: an assumption, restitution 0.66 in
#: the drop (2.7 m/s).  The drop's peak is insensitive to it: 250-265 g for 0.1 to 1 s/m
#: (an elastic tissue, 0, gives 287 g).
FOREHEAD_TISSUE_HYSTERESIS = 0.3
#: Strain at which the soft tissue is squeezed onto the bone [-] (an assumption; the drop
#: compresses it to 63 %).
FOREHEAD_TISSUE_STRAIN_LIMIT = 0.9
#: Young's modulus [Pa] and Poisson's ratio of cranial cortical bone (Reilly & Burstein 1975,
#: as used by the VIVA+ human body model for the skull: 17.1 GPa, 0.3).
SKULL_MODULUS = 17.1e9
SKULL_POISSON = 0.3
#: Radius of curvature of the forehead [m]: the head surface of the thesis-era head model
#: (thesis-frontal); an assumption of the order of the frontal bone's curvature (the drop's
#: peak force scales with R^(1/3): +-20 % on R moves it by +-6 %).
FOREHEAD_RADIUS = 0.1
#: Mass of the head [kg]: the Hybrid III 50th-percentile head of the drop test (49 CFR 572.32,
#: 10 lb = 4.54 kg); an adult male head is 4.42 kg (Yoganandan et al. 2009, via VIVA+).
HEAD_MASS = 4.54

FOREHEAD = BodyContact(
    name="head (forehead)", mass=HEAD_MASS, radius=FOREHEAD_RADIUS,
    layers=(Layer("forehead soft tissue", "thin-layer", modulus=FOREHEAD_TISSUE_MODULUS,
                  thickness=FOREHEAD_TISSUE_THICKNESS,
                  strain_limit=FOREHEAD_TISSUE_STRAIN_LIMIT,
                  hysteresis=FOREHEAD_TISSUE_HYSTERESIS,
                  source="thickness: Cakmakoglu et al. 2025 (MRI, adult males, midline); "
                         "modulus: calibrated on the Hybrid III drop (49 CFR 572.32), within "
                         "the scatter of Falland-Cheung et al. 2018; hysteresis: assumed"),
            Layer("frontal bone", "hertz", modulus=SKULL_MODULUS, poisson=SKULL_POISSON,
                  source="cortical bone, Reilly & Burstein 1975 (as used by the VIVA+ model)")),
    source="soft tissue (thin layer, exponent 2) in series with the frontal bone (Hertz, 3/2); "
           "passes the Hybrid III head drop of 49 CFR 572.32 (see docs/impact_models.md)",
    checks=(("hybrid_iii_drop", True, "250 g with its own mass, 225-275 g required"),))

# ---- the covering the thesis' numbers imply --------------------------------------------------
#: Thickness of the covering fitted to Table 6.1 [m]: thin layers fit the 20 (HIC, F_max)
#: pairs equally for any thickness with the same modulus / thickness (the fitted quantity),
#: as long as the layer does not bottom out; 10 mm keeps the PID step impact (about 4.8 mm of
#: compression) below the 80 % strain limit.
THESIS_COVERING_THICKNESS = 10e-3
#: Its modulus [Pa] and hysteresis [s/m], fitted to Table 6.1 with the head above (5 kg, as in
#: the thesis) at the tool point (a 30 mm sphere), rounded
#: (:func:`ppamsafety.impact.covering_fit.fit_covering` recomputes 1.163 MPa and 9.78 s/m).
THESIS_COVERING_MODULUS = 1.16e6
THESIS_COVERING_HYSTERESIS = 9.8
#: Strain at which a foam or elastomer covering bottoms out [-] (foams densify near 0.6-0.8,
#: Gibson & Ashby, Cellular Solids, 1997).
COVERING_STRAIN_LIMIT = 0.8

THESIS_COVERING = Covering(
    name="thesis-implied", layers=(Layer(
        "covering implied by Table 6.1", "thin-layer", modulus=THESIS_COVERING_MODULUS,
        thickness=THESIS_COVERING_THICKNESS, strain_limit=COVERING_STRAIN_LIMIT,
        hysteresis=THESIS_COVERING_HYSTERESIS,
        source="fitted to the 20 (HIC, F_max) pairs of thesis Table 6.1 in series with the "
               "validated head (ppamsafety.impact.covering_fit.fit_covering)"),),
    source="what the thesis' Table 6.1 implies in front of a head that passes its drop test")

_BODIES = {b.name: b for b in (FOREHEAD,)}
_COVERINGS = {c.name: c for c in (BARE, THESIS_COVERING)}


def body_contact(name: str = "head (forehead)") -> BodyContact:
    """A named body contact model: one of :func:`body_contact_names`.

    Parameters
    ----------
    name : str
        ``"head (forehead)"`` (the head that passes the Hybrid III drop).
    """
    check_str("name", name)
    if name not in _BODIES:
        raise ValueError(f"unknown body contact model {name!r}{did_you_mean(name, list(_BODIES))}"
                         f"; choose from {sorted(_BODIES)}")
    return _BODIES[name]


def body_contact_names() -> list:
    """Names accepted by :func:`body_contact`."""
    return sorted(_BODIES)


def covering(name: str = "bare metal") -> Covering:
    """A named covering: one of :func:`covering_names`.

    Parameters
    ----------
    name : str
        ``"bare metal"`` or ``"thesis-implied"``.
    """
    check_str("name", name)
    if name not in _COVERINGS:
        raise ValueError(f"unknown covering {name!r}{did_you_mean(name, list(_COVERINGS))}; "
                         f"choose from {sorted(_COVERINGS)}")
    return _COVERINGS[name]


def covering_names() -> list:
    """Names accepted by :func:`covering`."""
    return sorted(_COVERINGS)


# ---- contact points of an arm ----------------------------------------------------------------
#: Smallest surface radius of a default contact point [m] (an arm whose muscle attachments sit
#: on its link axes gets this).
MIN_POINT_RADIUS = 10e-3


def arm_contact_points(arm, covering: Covering = BARE) -> tuple:
    """The default contact points of an arm: tool point, elbow, forearm, upper arm.

    Positions follow the arm's geometry (L1, L2): the tool point is the end of link 2 (L2),
    the elbow the joint S (link 2 at 0), the forearm the middle of link 2, the upper arm the
    middle of link 1.  Surface radius: the thesis prints no cross-section of the links; the
    muscle attachment points sit at the offsets d (Table 2.1) from the link axes, so the
    links' structure reaches at least that far: the radius of a link is the largest offset
    of its attachment points (thesis arm: 30 mm for both links; at least
    :data:`MIN_POINT_RADIUS`).  Shapes: a sphere at the tool point (the link's end) and the
    elbow (the joint), a cylinder along the links.

    Parameters
    ----------
    arm : ArmParameters
        The arm.
    covering : Covering
        Covering of every point (default bare metal).

    Returns
    -------
    tuple of ContactPoint
    """
    g = arm.geometry
    r1 = max(MIN_POINT_RADIUS, abs(g.d12), abs(g.d22))
    r2 = max(MIN_POINT_RADIUS, abs(g.d32), abs(g.d42), abs(g.d33), abs(g.d43))
    src = ("position from the arm's link lengths; radius from the offsets of the muscle "
           "attachment points (the links reach at least that far from their axes)")
    return (ContactPoint("tool point", 2, g.L2, "sphere", r2, covering, src),
            ContactPoint("elbow", 2, 0.0, "sphere", max(r1, r2), covering, src),
            ContactPoint("forearm", 2, 0.5 * g.L2, "cylinder", r2, covering, src),
            ContactPoint("upper arm", 1, 0.5 * g.L1, "cylinder", r1, covering, src))


#: How far from its link's joint a contact point may lie, in link lengths: as far as the arm's
#: own parts (:data:`~ppamsafety.params.arm.LINK_EXTENT_FACTOR`), which leaves room for a tool,
#: a bracket or a covering past the link's end and refuses what a unit slip gives (a position
#: in mm read as cm is 10 times too far).
POINT_EXTENT_FACTOR = LINK_EXTENT_FACTOR

_LINK_NAMES = {1: ("upper arm", "base joint O"), 2: ("forearm", "elbow S")}


def check_point_on_arm(point: ContactPoint, arm) -> ContactPoint:
    """Refuse a contact point that does not lie on its link of ``arm``.

    A point lies at most :data:`POINT_EXTENT_FACTOR` link lengths (L1 for link 1, L2 for link
    2) from its link's joint: the margin is for a tool, a bracket or a covering that reaches
    past the link's end.

    Parameters
    ----------
    point : ContactPoint
        The point.
    arm : ArmParameters
        The arm it belongs to.

    Returns
    -------
    ContactPoint
        ``point``, unchanged.

    Raises
    ------
    ValueError
        Naming the point, its position (m and mm), the link length and the allowed range.
    """
    length = getattr(arm.geometry, f"L{point.link}")
    hi = POINT_EXTENT_FACTOR * length
    if point.position > hi:
        name, joint = _LINK_NAMES[point.link]
        raise ValueError(
            f"contact point {point.name!r}: position = {point.position:.4g} m "
            f"({1e3 * point.position:.4g} mm) along link {point.link} lies beyond the {name}: "
            f"{point.position / length:.3g} times its length L{point.link} = {length:.4g} m "
            f"({1e3 * length:.4g} mm); allowed [0, {hi:.4g}] m ([0, {1e3 * hi:.4g}] mm) from the "
            f"{joint}, i.e. up to {POINT_EXTENT_FACTOR:g} L{point.link} for a tool or covering "
            f"past the link's end; check the value, its unit and link")
    return point


#: A thin-layer or Hertz layer softer than this [Pa] gets a note: the softest coverings and
#: skin-like elastomers have a compressive modulus of some 10 kPa (silicone gels such as
#: Ecoflex 00-10: about 55 kPa; low-density polyurethane foams: 10-100 kPa, Gibson & Ashby,
#: Cellular Solids, 1997); a modulus in kPa or MPa written as Pa lands below it.
SOFT_LAYER_MODULUS = 1.0e4
#: Unit slips of a layer's modulus: the factor to the value meant, and the slip (the first whose
#: corrected value lies within :data:`PLAUSIBLE_LAYER_MODULUS` is named).
_MODULUS_SLIPS = ((1.0e3, "kPa"), (1.0e6, "MPa"))
#: Moduli a covering layer plausibly has [Pa]: soft gels to hard plastics.
PLAUSIBLE_LAYER_MODULUS = (SOFT_LAYER_MODULUS, 5.0e9)


def covering_notes(cov: Covering) -> tuple:
    """What is possible in a covering but likely a unit slip: one line each.

    * a layer (thin-layer or Hertz) softer than :data:`SOFT_LAYER_MODULUS`: the likely slip
      (kPa or MPa written as Pa) and the value it would mean.

    Parameters
    ----------
    cov : Covering
        Any covering.

    Returns
    -------
    tuple of str
        The notes (empty for the named coverings).
    """
    notes = []
    for i, lay in enumerate(cov.layers):
        if lay.law == "power" or not lay.modulus < SOFT_LAYER_MODULUS:
            continue
        lo, hi = PLAUSIBLE_LAYER_MODULUS
        hint = next((f"; did you mean {lay.modulus:.4g} {unit} ({lay.modulus * f:.4g} Pa: a "
                     f"unit slip, a value in {unit} given in Pa)?"
                     for f, unit in _MODULUS_SLIPS if lo <= lay.modulus * f <= hi), "")
        notes.append(f"layer[{i}].modulus = {lay.modulus:.4g} Pa ({lay.name!r}) is softer than "
                     f"any covering material (gels and soft foams: {lo / 1e3:g} kPa and more); "
                     f"such a layer bottoms out at low speed{hint}")
    return tuple(notes)


__all__ = ["Layer", "Covering", "BodyContact", "ContactPoint", "LAWS", "SHAPES", "MAX_LAYERS",
           "BARE", "FOREHEAD", "THESIS_COVERING", "body_contact", "body_contact_names",
           "covering", "covering_names", "arm_contact_points", "check_point_on_arm",
           "covering_notes", "POINT_EXTENT_FACTOR", "SOFT_LAYER_MODULUS"]
