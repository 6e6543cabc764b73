"""The complete arm parameter set: plant truth plus the controllers' model.

:func:`thesis_arm` assembles the cited sub-sets:

========================  ==============================================
field                     source
========================  ==============================================
geometry                  Tables 2.1, 2.2, eqs. (2.6)-(2.7)
muscles                   §2.3.3.1, Table B.1
valves                    Table B.2 + documented time constants
pneumatics                §3.3 + calibrated mean pressures (§6.3.3)
links (plant)             physically consistent reconciliation
model (controllers)       identified Table 3.5 (dynamic, with friction)
model_gravity             identified Table 3.1 (static gravity)
sensors                   §2.4.5, Table 3.2 (encoders, timing board, noise)
========================  ==============================================

The plant is what the simulator integrates; ``model`` and ``model_gravity``
are what the controllers believe (gravity compensation (3.18)-(3.19), the
sliding-mode controller's feedback linearisation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np

from .._validation import check_instance, check_range, check_str
from . import arm_file
from .effects import Effects
from .geometry import GROUP_FIELDS, ArmGeometry, group_length_range, thesis_geometry
from .inertia import (BaseParameters, LinkInertia, derive_physical_links, identified_dynamic,
                      identified_static_gravity)
from .muscles import MAX_CONTRACTION, MuscleSet, thesis_muscles
from .pneumatics import PneumaticParams, thesis_pneumatics
from .sensors import SensorHardware
from .valves import ValveSet, thesis_valves


@dataclass(frozen=True)
class ArmParameters:
    """Everything needed to simulate the pneumatic arm.

    Attributes
    ----------
    geometry : ArmGeometry
    muscles : MuscleSet
    valves : ValveSet
    pneumatics : PneumaticParams
    links : LinkInertia
        Physical mass properties used by the plant.
    model : BaseParameters
        Identified dynamics used by model-based controllers.
    model_gravity : BaseParameters
        Identified gravity terms used by the static gravity compensation.
    gravity : float
        Gravitational acceleration along -y [m/s^2] (0 for a horizontal arm).
    friction_velocity : float
        Velocity scale of the smooth Coulomb friction c tanh(qdot/v_s)
        [rad/s].  A fixed-step integrator cannot resolve an ideal sign
        function; 0.01 rad/s is below the encoder velocity dead band
        (0.025 rad/s, §2.4.5.3).
    effects : Effects
        Optional plant effects (payload, truth-vs-model friction, valves,
        polytropic exponent), all off by default.  Read only by the plant
        truth row ``plant.packing.pack(arm)``, never by the controllers' views
        (see :mod:`ppamsafety.params.effects`).
    sensors : SensorHardware
        The joint sensors the arm carries (encoders, timing board, noise
        variances; default the thesis hardware, §2.4.5, Table 3.2).  The
        simulated measurement is ``SensorConfig.for_arm(arm)``.
    name : str
        A label (``"thesis arm"``; an arm file's ``[arm] name``).  Not compared:
        two arms with the same physics are equal whatever their names.
    sources : tuple of (str, str)
        Provenance per part of the arm, ``(table, text)`` pairs such as
        ``("muscles.group1", "Table B.1")`` (an arm file's ``source`` keys).
        Not compared, like ``name``; read with :meth:`source`.

    Notes
    -----
    Besides the types and ranges of ``gravity`` ([0, 30] m/s^2) and
    ``friction_velocity`` ([1e-5, 1] rad/s), construction refuses sets that
    cannot be built: a point of a link (muscle attachment, load point, centre of
    gravity) or its radius of gyration farther from its joint than
    :data:`LINK_EXTENT_FACTOR` times its length (``L2 = 0.31 mm`` with the forearm's
    attachments at 0.285 m; ``LG2 = 1.5 m`` on a 0.31 m forearm), non-positive
    connection lengths or contractions outside
    [0, 0.4] anywhere in the working area (e.g. ``L22 = 0``), a plant
    inertia matrix that is numerically singular, and a link whose inertia about
    its joint is below m (0.05 L)^2 (:data:`MIN_GYRATION_FRACTION`).  The identified ``model``
    sets are not required to be positive definite (Table 3.5 is not).
    """

    geometry: ArmGeometry
    muscles: MuscleSet
    valves: ValveSet
    pneumatics: PneumaticParams
    links: LinkInertia
    model: BaseParameters
    model_gravity: BaseParameters
    gravity: float = 9.81
    friction_velocity: float = 0.01
    effects: Effects = Effects()
    sensors: SensorHardware = SensorHardware()
    name: str = field(default="", compare=False)
    sources: tuple = field(default=(), compare=False)

    def __post_init__(self):
        for name, cls in (("geometry", ArmGeometry), ("muscles", MuscleSet), ("valves", ValveSet),
                          ("pneumatics", PneumaticParams), ("links", LinkInertia),
                          ("model", BaseParameters), ("model_gravity", BaseParameters)):
            check_instance(f"ArmParameters.{name}", getattr(self, name), cls)
        object.__setattr__(self, "gravity", check_range("ArmParameters.gravity", self.gravity,
                                                        0.0, 30.0, unit="m/s^2"))
        object.__setattr__(self, "friction_velocity", check_range(
            "ArmParameters.friction_velocity", self.friction_velocity, 1e-5, 1.0, unit="rad/s"))
        _check_link_extents(self.geometry, self.links)
        _check_muscles_fit(self.geometry, self.muscles)
        _check_plant_inertia(self.geometry, self.links)
        check_instance("ArmParameters.effects", self.effects, Effects)
        check_instance("ArmParameters.sensors", self.sensors, SensorHardware)
        check_str("ArmParameters.name", self.name)
        object.__setattr__(self, "sources", _check_sources(self.sources))

    def replace(self, **changes) -> "ArmParameters":
        """Return a copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            New values of fields of :class:`ArmParameters`, by field name (as for
            :func:`dataclasses.replace`); the copy is checked like a newly
            constructed object.
        """
        return replace(self, **changes)

    def to_toml(self, *, comments: bool = True) -> str:
        """The arm as the TOML text of an arm file (exact round trip; ``docs/arm_files.md``).

        Parameters
        ----------
        comments : bool
            Comment every key (what it is, its range) and list the effects that are
            off as commented-out examples: a template to edit.

        Returns
        -------
        str
            ``ArmParameters.from_toml(arm.to_toml()) == arm``, names and sources included.
        """
        return arm_file.arm_to_toml(self, comments=comments)

    @classmethod
    def from_toml(cls, text: str, *, where: str = "") -> "ArmParameters":
        """An arm from the TOML text of an arm file, validated.

        Parameters
        ----------
        text : str
            TOML text (``docs/arm_files.md``).
        where : str
            How to name the file in error messages (its path).

        Returns
        -------
        ArmParameters

        Raises
        ------
        ppamsafety.params.arm_file.ArmFileError
            A ``ValueError`` naming the dotted key, its value and what is allowed
            (``muscles.group3.l0 = -0.1 m: must be in (0, 1] m``).
        """
        return arm_file.arm_from_toml(text, cls=cls, where=where)

    @classmethod
    def from_file(cls, path) -> "ArmParameters":
        """An arm from an arm file, its data validated.

        The checks that need the arm's physics (it holds itself somewhere, its force laws
        are a PPAM's) are :func:`ppamsafety.design.check_arm`; read a file with
        :func:`ppamsafety.design.load_arm`, which makes both.

        Parameters
        ----------
        path : path-like
            The ``.toml`` file.

        Returns
        -------
        ArmParameters
        """
        return arm_file.read_arm_file(path, cls=cls)

    def fingerprint(self) -> str:
        """SHA-256 of the arm's canonical file text (:func:`~.arm_file.arm_fingerprint`).

        Returns
        -------
        str
            64 hex digits.
        """
        return arm_file.arm_fingerprint(self)

    def source(self, part: str) -> str:
        """The provenance of one part of the arm ("" if none is given).

        Parameters
        ----------
        part : str
            A table of the arm file, e.g. ``"geometry"``, ``"muscles.group1"``,
            ``"links"``.
        """
        check_str("part", part)
        return dict(self.sources).get(part, "")

    @property
    def plant_base(self) -> BaseParameters:
        """Base parameters (B.5) of the physical plant links."""
        return self.links.base_parameters(self.geometry.L1)


#: The parts of an arm that carry a source (the tables of an arm file; "arm" is its top
#: level), in the order ``ArmParameters.sources`` keeps them.
SOURCE_PARTS = ("arm", "geometry", "muscles", *(f"muscles.group{k}" for k in range(1, 5)),
                "valves", *(f"valves.valve{k}" for k in range(1, 5)), "pneumatics", "links",
                "model", "model_gravity", "effects", "sensors")


def _check_sources(sources) -> tuple:
    """``ArmParameters.sources`` as (str, str) pairs of :data:`SOURCE_PARTS`, in that order."""
    if isinstance(sources, dict):
        sources = tuple(sources.items())
    if isinstance(sources, (str, bytes)) or not isinstance(sources, (tuple, list)):
        raise TypeError(f"ArmParameters.sources must be a tuple of (part, text) pairs, "
                        f"got {sources!r:.80}")
    out, seen = [], set()
    for i, item in enumerate(sources):
        if not (isinstance(item, (tuple, list)) and len(item) == 2
                and all(isinstance(x, str) for x in item)):
            raise TypeError(f"ArmParameters.sources[{i}] must be a (part, text) pair of "
                            f"strings, got {item!r:.80}")
        if item[0] not in SOURCE_PARTS:
            raise ValueError(f"ArmParameters.sources[{i}]: unknown part {item[0]!r}; allowed: "
                             f"{list(SOURCE_PARTS)}")
        if item[0] in seen:
            raise ValueError(f"ArmParameters.sources names the part {item[0]!r} twice")
        seen.add(item[0])
        if item[1]:
            out.append((item[0], item[1]))
    return tuple(sorted(out, key=lambda kv: SOURCE_PARTS.index(kv[0])))


#: How far from its joint the parts of a link may lie, in link lengths (L1 for the upper arm,
#: L2 for the forearm): its muscle attachment points and load point (distance sqrt(L^2 + d^2)),
#: its centre of gravity (sqrt(L_G^2 + d_G^2)) and its radius of gyration sqrt(I_G / m).  The
#: thesis arm reaches 1.12 L1 (the group 3 attachment at L32 = 334.8 mm on a lever past the
#: 300 mm upper arm, Table 2.1) and 0.97 L2 (the load point); 1.5 leaves room for a longer
#: lever or a tool flange and refuses what a unit slip gives (a length in mm read as m is 1000
#: times too long, one in m read as mm 1000 times too short; a centre of gravity of 1.5 m on a
#: 0.31 m forearm is 4.8 lengths out).
LINK_EXTENT_FACTOR = 1.5

#: Points of each link, as (ArmGeometry or LinkInertia field along, field perpendicular, what).
_LINK_POINTS = {
    1: (("ArmGeometry", "L12", "d12", "the group 1 attachment"),
        ("ArmGeometry", "L22", "d22", "the group 2 attachment"),
        ("ArmGeometry", "L32", "d32", "the group 3 attachment"),
        ("ArmGeometry", "L42", "d42", "the group 4 attachment"),
        ("LinkInertia", "LG1", "dG1", "the centre of gravity")),
    2: (("ArmGeometry", "L33", "d33", "the group 3 attachment"),
        ("ArmGeometry", "L43", "d43", "the group 4 attachment"),
        ("ArmGeometry", "LL", "dL", "the load point"),
        ("LinkInertia", "LG2", "dG2", "the centre of gravity")),
}
#: Factors by which a length is too short after a unit slip, with the slip.
_LENGTH_SLIPS = ((10.0, "mm for cm"), (100.0, "cm for m"), (1000.0, "mm for m"))


def _check_link_extents(geometry: ArmGeometry, links: LinkInertia) -> None:
    """Refuse a link whose points or radius of gyration lie beyond
    :data:`LINK_EXTENT_FACTOR` link lengths from its joint, naming both keys."""
    objs = {"ArmGeometry": geometry, "LinkInertia": links}
    for k, name, joint in ((1, "upper arm", "base joint"), (2, "forearm", "elbow")):
        length = getattr(geometry, f"L{k}")
        limit = LINK_EXTENT_FACTOR * length
        far = []
        for cls, along, perp, what in _LINK_POINTS[k]:
            a, d = getattr(objs[cls], along), getattr(objs[cls], perp)
            r = math.hypot(a, d)
            if r > limit:
                far.append((r, f"{cls}.{along} = {a:.4g} m ({what}, {r / length:.3g} L{k} from "
                               f"the {joint})"))
        m, ig = getattr(links, f"m{k}"), getattr(links, f"IG{k}")
        gyration = math.sqrt(ig / m)
        if not far and gyration > limit:
            raise ValueError(
                f"ArmParameters: LinkInertia.IG{k} = {ig:.4g} kg m^2 with LinkInertia.m{k} = "
                f"{m:.4g} kg is a radius of gyration sqrt(IG{k}/m{k}) = {gyration:.4g} m about the "
                f"centre of gravity, {gyration / length:.3g} {name} lengths (ArmGeometry.L{k} = "
                f"{length:.4g} m): the mass of a link lies within {LINK_EXTENT_FACTOR:g} L{k} = "
                f"{limit:.4g} m of its joint.  Check both units: a mass in g written as kg is 1000 "
                f"times too small, an inertia in g m^2 written as kg m^2 1000 times too large")
        if not far:
            continue
        listed = "; ".join(t for _, t in sorted(far, reverse=True))
        if len(far) * 2 <= len(_LINK_POINTS[k]):          # one or two points: blame them
            raise ValueError(
                f"ArmParameters: {listed} lies beyond {LINK_EXTENT_FACTOR:g} {name} lengths from "
                f"the {joint} (ArmGeometry.L{k} = {length:.4g} m: within {limit:.4g} m); check "
                f"its value and unit, and ArmGeometry.L{k}")
        reach = max(r for r, _ in far)
        hint = next((f"  Did you mean ArmGeometry.L{k} = {length * f:.4g} m ({f:g} times longer: "
                     f"a unit slip such as {slip})?" for f, slip in _LENGTH_SLIPS
                     if 0.5 * length * f <= reach <= limit * f and length * f <= 5.0), "")
        raise ValueError(
            f"ArmParameters: ArmGeometry.L{k} = {length:.4g} m ({name} length) is too short for "
            f"what lies along the {name}: {listed}; every part of a link lies within "
            f"{LINK_EXTENT_FACTOR:g} L{k} = {limit:.4g} m of its joint.{hint}")


#: Smallest admissible relative determinant det H / (H11 H22) of the plant's inertia
#: matrix in the working area (1 would be decoupled links; the thesis arm has > 0.3).
#: Physical links are always positive definite (LinkInertia notes); this refuses
#: matrices so close to singular that the integrators would be ill-conditioned.
MIN_INERTIA_DET_RATIO = 1e-6


@lru_cache(maxsize=128)
def _check_muscles_fit(geometry: ArmGeometry, muscles: MuscleSet) -> None:
    """Refuse geometry/muscle combinations that cannot be built (cached per pair).

    With the design connection lengths L_conn of (A.35)-(A.38) (groups 1, 3 at
    ``eps_min`` at their longest, groups 2, 4 at ``eps_max`` at their shortest,
    §2.3.2.4) every group must have L_conn > 0 (a rod cannot have negative
    length) and its contraction must stay in [0, MAX_CONTRACTION] over the whole
    working area (a PPAM cannot be stretched beyond l0, and contracts at most
    40 %, §2.2).  Then every membrane and group length is positive.
    """
    ranges = group_length_range(geometry)
    for k, (grp, (dmin, dmax)) in enumerate(zip(muscles.groups, ranges)):
        joint = 1 if k < 2 else 2
        flds = ", ".join(f"ArmGeometry.{n}" for n in GROUP_FIELDS[k + 1])
        area = (f"q{joint} in [{np.degrees(getattr(geometry, f'q{joint}_min')):.4g}, "
                f"{np.degrees(getattr(geometry, f'q{joint}_max')):.4g}] deg")
        membrane = grp.n_muscles * grp.l0
        # the design rule (A.35)-(A.38) on the grid extremes (plant.geometry refines them for
        # the simulation): groups 1, 3 at eps_min at their longest, 2, 4 at eps_max at their
        # shortest
        lc = (dmax - membrane * (1.0 - muscles.eps_min) if k in (0, 2)
              else dmin - membrane * (1.0 - muscles.eps_max))
        what = (f"ArmParameters: muscle group {k + 1} ({grp.name!r}; {grp.n_muscles} x l0 = "
                f"{grp.l0:g} m; group length {dmin:.4g} to {dmax:.4g} m over {area})")
        if not (np.isfinite(lc) and lc > 0.0):
            eps, at = (muscles.eps_min, "longest") if k in (0, 2) else (muscles.eps_max,
                                                                       "shortest")
            raise ValueError(
                f"{what} has connection length L_conn = {lc:.4g} m <= 0 (A.35)-(A.38): its "
                f"attachment points are too close for the muscles at contraction {eps:g} at "
                f"the {at} length (needs a group length above {membrane * (1 - eps):.4g} m). "
                f"Change {flds}, the working area, MuscleGroup.n_muscles/l0 or "
                f"MuscleSet.eps_min/eps_max")
        e_lo = (lc + membrane - dmax) / membrane
        e_hi = (lc + membrane - dmin) / membrane
        tol = 1e-6
        if e_lo < -tol or e_hi > MAX_CONTRACTION + tol:
            raise ValueError(
                f"{what} would need contractions from {e_lo:.3g} to {e_hi:.3g}, outside "
                f"[0, {MAX_CONTRACTION:g}] (a PPAM cannot be stretched beyond l0 and contracts "
                f"at most 40 %, thesis §2.2): the length change over the working area is too "
                f"large for these muscles.  Change {flds}, the working area, "
                f"MuscleGroup.n_muscles/l0 or MuscleSet.eps_min/eps_max")


#: Smallest radius of gyration of a link about its joint, as a fraction of the link's length
#: (L1, L2): I_joint >= m (0.05 L)^2.  A uniform bar has 0.58 about its end (0.29 about its
#: centre; the thesis arm 0.55 and 0.86); 0.05 admits a link whose mass sits almost at its
#: joint, and refuses one with all its mass *at* the joint and no inertia (e.g. L_G2 = d_G2 =
#: 0, I_G2 = 1e-98 kg m^2), whose joint the integrators cannot resolve.
MIN_GYRATION_FRACTION = 0.05


def _check_plant_inertia(geometry: ArmGeometry, links: LinkInertia) -> None:
    """Refuse a plant inertia matrix that is (numerically) singular in the working area, or a
    link with (almost) no inertia about its joint."""
    b = links.base_parameters(geometry.L1)
    q2 = np.linspace(geometry.q2_min, geometry.q2_max, 181)
    a = geometry.L1 * (b.m2LG2 * np.cos(q2) + b.m2dG2 * np.sin(q2))
    h11, h12, h22 = b.IO1_m2L1sq + b.IS2 + 2.0 * a, b.IS2 + a, b.IS2
    ratio = (h11 * h22 - h12 * h12) / (np.abs(h11) * h22)
    j = int(np.argmin(ratio))
    if not (h11[j] > 0 and ratio[j] >= MIN_INERTIA_DET_RATIO):
        raise ValueError(
            f"ArmParameters.links: the plant inertia matrix is (nearly) singular at q2 = "
            f"{np.degrees(q2[j]):.4g} deg (det H / (H11 H22) = {ratio[j]:.3g}, needs >= "
            f"{MIN_INERTIA_DET_RATIO:g}); check LinkInertia.IG1/IG2 (too small for the masses?)")
    for k, (m, lg, dg, ig, length, ln) in enumerate((
            (links.m1, links.LG1, links.dG1, links.IG1, geometry.L1, "L1"),
            (links.m2, links.LG2, links.dG2, links.IG2, geometry.L2, "L2")), start=1):
        i_joint = ig + m * (lg * lg + dg * dg)
        i_min = m * (MIN_GYRATION_FRACTION * length) ** 2
        if not i_joint >= i_min:
            raise ValueError(
                f"ArmParameters.links: link {k}'s inertia about its joint, I_G{k} + m{k} "
                f"(L_G{k}^2 + d_G{k}^2) = {i_joint:.3g} kg m^2, is below m{k} "
                f"({MIN_GYRATION_FRACTION:g} {ln})^2 = {i_min:.3g} kg m^2: all its mass at the "
                f"joint, not a link the integrators can resolve; check LinkInertia.IG{k} "
                f"(and LG{k}, dG{k})")


#: Provenance of each part of the thesis arm (the ``source`` keys of its arm file).
THESIS_SOURCES = (
    ("arm", "M. Van Damme, Towards Safe Control of a Compliant Manipulator Powered by "
            "Pneumatic Muscles (PhD thesis, VUB, 2009); gravity 9.81 m/s^2; smooth Coulomb "
            "friction scale below the encoder dead band (§2.4.5.3)"),
    ("geometry", "thesis Table 2.1 (attachment points), Table 2.2 (load point, link "
                 "lengths), eqs. (2.6)-(2.7) (working area)"),
    ("muscles", "thesis §2.3.2.4 (design contraction limits 5 % and 30 %)"),
    ("muscles.group1", "thesis §2.3.3.1 (4 muscles, l0 = 6 cm, l0/R = 6), Table B.1"),
    ("muscles.group2", "thesis §2.3.3.1 (3 muscles, l0 = 6 cm, l0/R = 6), Table B.1"),
    ("muscles.group3", "thesis §2.3.3.1 (4 muscles, l0 = 6 cm, l0/R = 6), Table B.1"),
    ("muscles.group4", "thesis §2.3.3.1 (3 muscles, l0 = 6 cm, l0/R = 6), Table B.1"),
    ("valves", "thesis Table B.2 (static error (3.12)); time constants chosen from §3.5.2, "
               "§4.2.5 (T = 0.06 s for 4 muscles, 0.045 s for 3)"),
    ("pneumatics", "thesis §3.3 (n = 1.4, P_atm), §2.2.2 (3 bar); mean pressures calibrated "
                   "to K = (43, 27) Nm/rad at q = (50, -80) deg (§6.3.3)"),
    ("links", "physically consistent reconciliation of §6.3.3 masses, Table 2.2 CAD centres "
              "of gravity and the identified Tables 3.1/3.5 (params.inertia); slender-bar "
              "inertias; friction Table 3.5"),
    ("model", "thesis Table 3.5 (dynamic identification with friction)"),
    ("model_gravity", "thesis Table 3.1 (static gravity identification); inertias of "
                      "Table 3.5"),
    ("sensors", "thesis §2.4.5 (HEDM-6540 encoders x4, 2 MHz 16-bit timing board, 0.025 "
                "rad/s dead band), Table 3.2 (noise variances)"),
)


@lru_cache(maxsize=1)
def thesis_arm() -> ArmParameters:
    """The thesis arm with a physically consistent plant (see module doc)."""
    geometry = thesis_geometry()
    return ArmParameters(
        geometry=geometry, muscles=thesis_muscles(), valves=thesis_valves(),
        pneumatics=thesis_pneumatics(),
        links=derive_physical_links(L1=geometry.L1).links,
        model=identified_dynamic(), model_gravity=identified_static_gravity(),
        name="thesis arm", sources=THESIS_SOURCES)


def load_arm(path) -> ArmParameters:
    """Read an arm file with the data checks only (the former front door, kept for scripts).

    Commands and new code read arm files with :func:`ppamsafety.design.load_arm`, which adds
    the checks that need the arm's physics (it holds itself somewhere in its working area,
    its force laws are a PPAM's; this layer cannot compute them).

    Parameters
    ----------
    path : path-like
        The ``.toml`` file.

    Returns
    -------
    ArmParameters
        ``ArmParameters.from_file(path)``.
    """
    return ArmParameters.from_file(path)


def is_thesis_arm(arm) -> bool:
    """True if ``arm`` has the physics of :func:`thesis_arm` (names and sources aside).

    The report quotes thesis values and ratios only for such an arm.

    Parameters
    ----------
    arm : ArmParameters
        Any arm.
    """
    check_instance("arm", arm, ArmParameters)
    return arm == thesis_arm()


__all__ = ["ArmParameters", "thesis_arm", "is_thesis_arm", "load_arm", "THESIS_SOURCES",
           "SOURCE_PARTS", "LINK_EXTENT_FACTOR"]
