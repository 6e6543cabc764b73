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

from .._validation import check_choice, check_int, check_range, check_str

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
        """A copy with some fields changed (checked again)."""
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
        """A copy with some fields changed (checked again)."""
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
        recomputed by :func:`ppamsafety.impact.layers.hybrid3_drop`).
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
        """A copy with some fields changed (checked again)."""
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
        """A copy with some fields changed (checked again)."""
        return replace(self, **changes)


#: Bare metal: no covering (the link's own, rigid surface).
BARE = Covering("bare metal", (), source="no covering: the link's rigid surface")

__all__ = ["Layer", "Covering", "BodyContact", "ContactPoint", "LAWS", "SHAPES", "MAX_LAYERS",
           "BARE"]
