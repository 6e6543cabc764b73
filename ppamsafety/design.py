"""Design-level analysis of the arm: torque functions, stiffness, maximum load.

Reproduces the design figures of thesis chapter 2 as data:

* torque functions m_tau,i over the working area (fig. 2.11);
* joint stiffness (2.18) over the working area with static Delta-p pressures;
* the maximum load the arm can hold anywhere (fig. 2.15, Appendix A.4).

All functions return result objects holding pandas DataFrames; plotting lives
in :mod:`ppamsafety.plots.design` (``result.plot()`` delegates there).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np
import pandas as pd

from .results import Result
from ._validation import check_instance, check_int, check_range
from .params import ArmParameters
from .params.arm_file import ArmFileError
from .params.effects import Effects
from .params.inertia import LINK_PRIORS, RADIUS_OF_GYRATION, LinkInertia
from .experiments.trajectories import arm_pose
from .plant import geometry as geo
from .plant import pneumatics as pn
from .plant import ppam_theory, torque
from .plant.muscle import polynomial
from .plots.design import (plot_arm_summary, plot_max_load, plot_stiffness_map,
                           plot_torque_functions)
from .units import BAR, DEG


def _arm(arm):
    return check_instance("arm", arm, ArmParameters)


def _grid(arm, n1: int, n2: int):
    arm = _arm(arm)
    n1 = check_int("n1", n1, 2, 2000)
    n2 = check_int("n2", n2, 2, 2000)
    g = arm.geometry
    q1, q2 = np.meshgrid(np.linspace(g.q1_min, g.q1_max, n1),
                         np.linspace(g.q2_min, g.q2_max, n2), indexing="ij")
    return np.stack([q1.ravel(), q2.ravel()], axis=-1)


@dataclass(frozen=True)
class TorqueFunctions(Result):
    """Torque functions along the driven joint (fig. 2.11).

    Made by :func:`torque_function_curves`.

    Attributes
    ----------
    data : pandas.DataFrame
        One row per sample and muscle group; columns ``group`` (1..4),
        ``angle_rad`` (q1 for groups 1-2, q2 for 3-4) [rad],
        ``m_tau_Nm_per_Pa`` (torque function m_tau,i (B.2)) [N m/Pa = m^3],
        ``eps`` (contraction) [-].
    """

    data: pd.DataFrame

    def to_pandas(self) -> pd.DataFrame:
        """The data as a pandas DataFrame (SI units)."""
        return self.data.copy()

    def plot(self, **kwargs):
        """The figure (drawn by :mod:`ppamsafety.plots`), a matplotlib Figure.

        Parameters
        ----------
        **kwargs
            Passed to :func:`ppamsafety.plots.design.plot_torque_functions`.
        """
        return plot_torque_functions(self, **kwargs)


def torque_function_curves(arm, *, n: int = 201) -> TorqueFunctions:
    """Torque functions m_tau,i over the working range of their joint.

    Parameters
    ----------
    arm : ArmParameters
    n : int, keyword-only
        Samples per joint range, in [2, 100000].
    """
    arm = _arm(arm)
    n = check_int("n", n, 2, 100000)
    g = arm.geometry
    q1 = np.linspace(g.q1_min, g.q1_max, n)
    q2 = np.linspace(g.q2_min, g.q2_max, n)
    qa = np.stack([q1, np.full(n, -80 * DEG)], -1)
    qb = np.stack([np.full(n, 50 * DEG), q2], -1)
    rows = []
    for k in range(4):
        q = qa if k < 2 else qb
        ang = q1 if k < 2 else q2
        rows.append(pd.DataFrame({"group": k + 1, "angle_rad": ang,
                                  "m_tau_Nm_per_Pa": torque.torque_functions(q, arm)[:, k],
                                  "eps": geo.contractions(q, arm)[:, k]}))
    return TorqueFunctions(pd.concat(rows, ignore_index=True))


@dataclass(frozen=True)
class StiffnessMap(Result):
    """Joint stiffness (2.18) over the working area.

    Made by :func:`stiffness_map`.

    Attributes
    ----------
    data : pandas.DataFrame
        One row per grid point; columns ``q1_rad``, ``q2_rad`` [rad],
        ``K1_Nm_per_rad``, ``K2_Nm_per_rad`` [N m/rad], ``p1_Pa`` ..
        ``p4_Pa`` (static Delta-p gauge pressures [Pa], clipped to [0,
        p_max]) and ``holdable`` (True where the static pressures are within
        [0, p_max] without clipping, i.e. the Delta-p approach with the
        chosen p_m can hold the arm there).
    """

    data: pd.DataFrame

    def to_pandas(self) -> pd.DataFrame:
        """The data as a pandas DataFrame (SI units)."""
        return self.data.copy()

    @property
    def ranges(self) -> dict:
        """Extremes over the working area: ``K1_min``, ``K1_max``, ``K2_min``, ``K2_max``
        [N m/rad] and ``holdable_fraction`` [-] (share of the grid the arm holds itself in)."""
        d = self.data
        return {"K1_min": float(d.K1_Nm_per_rad.min()), "K1_max": float(d.K1_Nm_per_rad.max()),
                "K2_min": float(d.K2_Nm_per_rad.min()), "K2_max": float(d.K2_Nm_per_rad.max()),
                "holdable_fraction": float(d.holdable.mean())}

    def plot(self, **kwargs):
        """The figure (drawn by :mod:`ppamsafety.plots`), a matplotlib Figure.

        Parameters
        ----------
        **kwargs
            Passed to :func:`ppamsafety.plots.design.plot_stiffness_map`.
        """
        return plot_stiffness_map(self, **kwargs)


def stiffness_map(arm, *, n1: int = 61, n2: int = 61) -> StiffnessMap:
    """Joint stiffness with static gravity-compensation pressures on a grid.

    Parameters
    ----------
    arm : ArmParameters
    n1, n2 : int, keyword-only
        Grid size over q1 and q2, each in [2, 2000].
    """
    q = _grid(arm, n1, n2)
    _, pc, holdable, K = _rest(q, arm)
    df = pd.DataFrame({"q1_rad": q[:, 0], "q2_rad": q[:, 1], "K1_Nm_per_rad": K[:, 0],
                       "K2_Nm_per_rad": K[:, 1]})
    for i in range(4):
        df[f"p{i + 1}_Pa"] = pc[:, i]
    df["holdable"] = holdable
    return StiffnessMap(df)


def _holding(arm, q) -> tuple:
    """(static Delta-p pressures (n, 4) [Pa], holdable (n,) bool) of ``arm`` at the poses ``q``.

    Holdable: every pressure in [0, p_max] without clipping (the Delta-p approach with the
    arm's mean pressures holds the arm there, (3.18)-(3.19)).
    """
    p = pn.static_pressures(q, arm)
    return p, np.all((p >= 0) & (p <= arm.pneumatics.p_max), axis=-1)


def cad_links() -> LinkInertia:
    """Link mass properties as the design chapter knew them (text masses + CAD CoG).

    m1 = 1.5 kg, m2 = 1.05 kg (§6.3.3), centres of gravity of Table 2.2;
    inertias from the slender-bar radii of gyration.  Used to recompute the
    maximum-load map the way §2.3.3.5 did (with CAD estimates).
    """
    p = {k: v[0] for k, v in LINK_PRIORS.items()}
    k1, k2 = RADIUS_OF_GYRATION
    return LinkInertia(m1=p["m1"], m2=p["m2"], LG1=p["LG1"], dG1=p["dG1"], LG2=p["LG2"],
                       dG2=p["dG2"], IG1=p["m1"] * k1 ** 2, IG2=p["m2"] * k2 ** 2)


@dataclass(frozen=True)
class MaxLoadMap(Result):
    """Maximum load (A.43)-(A.45) over the working area.

    Made by :func:`max_load_map`.

    Attributes
    ----------
    data : pandas.DataFrame
        One row per grid point; columns ``q1_rad``, ``q2_rad`` [rad],
        ``xL_m``, ``yL_m`` (load point A_L) [m], ``M1_kg`` (limit of joint
        1) [kg], ``M2_kg`` (limit of joint 2 with the carrying muscle) [kg],
        ``carrying_2`` (carrying group of joint 2, 3 or 4), ``M_max_kg`` =
        min(M1, M2) [kg].
    p_max : float
        Gauge pressure of the carrying muscle the map was computed with [Pa].
    """

    data: pd.DataFrame
    p_max: float

    def to_pandas(self) -> pd.DataFrame:
        """The data as a pandas DataFrame (SI units)."""
        return self.data.copy()

    @property
    def minimum(self) -> float:
        """The arm's true maximum load: the minimum of M_max over the working area [kg]."""
        return float(self.data["M_max_kg"].min())

    @property
    def argmin(self) -> tuple:
        """Configuration (q1, q2) [rad] where the minimum occurs."""
        r = self.data.loc[self.data["M_max_kg"].idxmin()]
        return float(r["q1_rad"]), float(r["q2_rad"])

    @property
    def limits(self) -> dict:
        """Each joint's limit over the working area [kg]: ``M1_min`` (joint 1, (A.43)),
        ``M2_min_muscle3`` and ``M2_min_muscle4`` (joint 2 with muscle 3 or 4 carrying,
        (A.44), (A.45); NaN where that muscle never carries) and the map's ``median``."""
        d = self.data
        return {"M1_min": float(d["M1_kg"].min()),
                "M2_min_muscle3": float(d[d.carrying_2 == 3]["M2_kg"].min()),
                "M2_min_muscle4": float(d[d.carrying_2 == 4]["M2_kg"].min()),
                "median": float(d.M_max_kg.median())}

    def plot(self, **kwargs):
        """The figure (drawn by :mod:`ppamsafety.plots`), a matplotlib Figure.

        Parameters
        ----------
        **kwargs
            Passed to :func:`ppamsafety.plots.design.plot_max_load`.
        """
        return plot_max_load(self, **kwargs)


def max_load_map(arm, *, links: LinkInertia | None = None, p_max: float | None = None,
                 n1: int = 171, n2: int = 201) -> MaxLoadMap:
    """Maximum load at the load point A_L anywhere in the working area (§2.3.3.5).

    The carrying muscle (1 for joint 1; 3, or 4 where (A.44) is negative) is
    at ``p_max``, its antagonist at zero gauge pressure.

    Parameters
    ----------
    arm : ArmParameters
    links : LinkInertia, optional
        Mass properties; default the plant's.  Pass :func:`cad_links` for the
        design-time (CAD) values the thesis used.
    p_max : float, optional
        Carrying pressure [Pa] in (0, 10] bar; default ``arm.pneumatics.p_max`` (3 bar).
    n1, n2 : int
        Grid size over q1 and q2, each in [2, 2000].

    Raises
    ------
    ValueError
        Besides bad arguments, if the load point passes exactly over a joint on
        the grid (zero moment arm: the load limit there is unbounded).
    """
    arm = _arm(arm)
    links = arm.links if links is None else check_instance("links", links, LinkInertia)
    p_max = arm.pneumatics.p_max if p_max is None else check_range(
        "p_max", p_max, 0.0, 10 * BAR, lo_open=True, unit="Pa")
    g = arm.geometry
    grav = 9.81
    q = _grid(arm, n1, n2)
    q1, q12 = q[:, 0], q[:, 0] + q[:, 1]
    c1, s1, c12, s12 = np.cos(q1), np.sin(q1), np.cos(q12), np.sin(q12)
    xS = g.L1 * c1
    xG1 = links.LG1 * c1 + links.dG1 * s1
    xG2 = xS + links.LG2 * c12 + links.dG2 * s12
    xL = xS + g.LL * c12 + g.dL * s12
    yL = g.L1 * s1 + g.LL * s12 - g.dL * c12
    mt = torque.torque_functions(q, arm)
    with np.errstate(divide="ignore", invalid="ignore"):   # checked below
        M1 = (p_max * mt[:, 0] - grav * (links.m1 * xG1 + links.m2 * xG2)) / (grav * xL)
        M2a = (p_max * mt[:, 2] - grav * links.m2 * (xG2 - xS)) / (grav * (xL - xS))
        M2b = (p_max * mt[:, 3] - grav * links.m2 * (xG2 - xS)) / (grav * (xL - xS))
    use_b = M2a < 0
    M2 = np.where(use_b, M2b, M2a)
    bad = ~(np.isfinite(M1) & np.isfinite(M2))
    if bad.any():
        k = int(np.argmax(bad))
        raise ValueError(f"max_load_map: the load point A_L passes over a joint at q = "
                         f"({np.degrees(q[k, 0]):.4g}, {np.degrees(q[k, 1]):.4g}) deg (zero "
                         f"moment arm, unbounded load); change n1/n2 or ArmGeometry.LL/dL")
    df = pd.DataFrame({"q1_rad": q[:, 0], "q2_rad": q[:, 1], "xL_m": xL, "yL_m": yL,
                       "M1_kg": M1, "M2_kg": M2, "carrying_2": np.where(use_b, 4, 3),
                       "M_max_kg": np.minimum(M1, M2)})
    return MaxLoadMap(df, p_max)


@dataclass(frozen=True)
class RestStiffness:
    """An arm's joint stiffness at rest in one pose.

    Made by :func:`rest_stiffness`.

    Attributes
    ----------
    q : tuple of 2 float
        The pose (q1, q2) [rad].
    pressures : tuple of 4 float
        Static Delta-p pressures of groups 1..4 that hold the arm there [Pa] (unclipped).
    holdable : bool
        Those pressures lie in [0, p_max] (otherwise the stiffness is that of the clipped
        pressures).
    stiffness : tuple of 2 float
        Joint stiffness K1, K2 (2.18) with the clipped pressures [N m/rad].
    """

    q: tuple
    pressures: tuple
    holdable: bool
    stiffness: tuple


def rest_stiffness(arm, q) -> RestStiffness:
    """The joint stiffness (2.18) of an arm at rest in pose ``q``.

    The muscles hold the pose with the static Delta-p pressures of the arm's own mean
    pressures (:func:`ppamsafety.plant.pneumatics.static_pressures`, the plant truth,
    payload included), clipped to [0, p_max]; the stiffness (2.18) follows from the
    muscles, those pressures and the pose.  This is the default stiffness of an impact
    of the arm at rest pressures (``ppamsafety impact``, :func:`ppamsafety.sweep_cases.
    impact_case`) and the stiffness ``ppamsafety arm check`` prints.

    Parameters
    ----------
    arm : ArmParameters
        Any valid arm.
    q : sequence of 2 float
        Pose (q1, q2) [rad], |q| <= 2 pi.

    Returns
    -------
    RestStiffness
    """
    arm = _arm(arm)
    q = np.asarray(q, dtype=float)
    if q.shape != (2,):
        raise ValueError(f"q = {q.tolist()!r} must be one pose (q1, q2) [rad]")
    p, _, holdable, K = _rest(q, arm)
    return RestStiffness(q=(float(q[0]), float(q[1])), pressures=tuple(float(v) for v in p),
                         holdable=bool(holdable), stiffness=(float(K[0]), float(K[1])))


def _rest(q, arm):
    """Static pressures (unclipped, clipped to [0, p_max]), whether they are in range, and the
    stiffness (2.18) with the clipped ones, for poses ``q`` of shape (..., 2)."""
    p, holdable = _holding(arm, q)
    pc = np.clip(p, 0.0, arm.pneumatics.p_max)
    return p, pc, holdable, pn.joint_stiffness(q, pc, arm)


#: Pose at which :func:`arm_summary` reports the stiffness when none is given: the
#: step-response impact configuration of thesis §6.3.3, q = (50, -80) deg (if it lies in
#: the arm's working area; else the centre of the working area).
SUMMARY_POSE = (50.0 * DEG, -80.0 * DEG)


@dataclass(frozen=True)
class ArmSummary(Result):
    """What ``ppamsafety arm check`` prints: an arm's key design numbers.

    Made by :func:`arm_summary`.

    Attributes
    ----------
    name : str
        The arm's name.
    pose : tuple of 2 float
        Configuration of the stiffness numbers (q1, q2) [rad].
    pose_pressures : tuple of 4 float
        Static Delta-p pressures that hold the arm there [Pa] (unclipped).
    pose_holdable : bool
        Those pressures lie in [0, p_max].
    stiffness : tuple of 2 float
        Joint stiffness (2.18) at the pose [N m/rad].
    data : pandas.DataFrame
        Every number: ``quantity``, ``value``, ``unit``.
    stiffness_map : StiffnessMap
        The stiffness over the working area the numbers come from.
    max_load_map : MaxLoadMap
        The maximum load over the working area the numbers come from.
    """

    name: str
    pose: tuple
    pose_pressures: tuple
    pose_holdable: bool
    stiffness: tuple
    data: pd.DataFrame
    stiffness_map: "StiffnessMap" = field(default=None, repr=False)
    max_load_map: "MaxLoadMap" = field(default=None, repr=False)

    def to_pandas(self) -> pd.DataFrame:
        """The numbers: ``quantity``, ``value``, ``unit``."""
        return self.data.copy()

    def plot(self):
        """K1, K2 and the maximum load over the working area, the pose marked; a Figure."""
        if self.stiffness_map is None or self.max_load_map is None:
            raise ValueError("this ArmSummary holds no maps to draw: make it with arm_summary()")
        return plot_arm_summary(self.stiffness_map.data, self.max_load_map.data, pose=self.pose,
                                stiffness_at_pose=self.stiffness, name=self.name)

    def lines(self) -> list:
        """The summary as text lines (what ``ppamsafety arm check`` prints).

        Returns
        -------
        list of str
        """
        out = []
        for r in self.data.itertuples(index=False):
            v = r.value
            text = f"{v:.4g}" if isinstance(v, float) else str(v)
            out.append(f"  {r.quantity:<46} {text} {r.unit}".rstrip())
        return out


def _payload_rows(arm, ml) -> list:
    """The maximum load's rows about the payload: what it counts, and what is left.

    The maximum load (A.43)-(A.45) is the largest point mass at the load point A_L with the
    links alone (:func:`max_load_map`), so a declared payload (``[effects] payload_mass``, a
    point mass at A_L) is part of it; the load beyond it is the maximum less the payload.
    """
    pay = arm.effects.payload_mass
    if not pay:
        return [("  of which a declared payload", "none declared", "")]
    return [("  of which the declared payload_mass", float(pay), "kg"),
            ("  left beyond the declared payload (min)", ml.minimum - float(pay), "kg")]


def arm_summary(arm, *, q=None, n: int = 61) -> ArmSummary:
    """An arm's key design numbers: stiffness at a pose, maximum load, working area.

    Parameters
    ----------
    arm : ArmParameters
        Any valid arm.
    q : sequence of 2 float, optional, keyword-only
        Pose of the stiffness numbers [rad] (default :data:`SUMMARY_POSE` at the same
        fractions of the arm's joint ranges, :func:`~ppamsafety.experiments.trajectories.arm_pose`,
        if in the working area, else its centre); must lie in the working area.
    n : int, keyword-only
        Grid points per joint for the maps, in [5, 2000].

    Returns
    -------
    ArmSummary
    """
    arm = _arm(arm)
    n = check_int("n", n, 5, 2000)
    g = arm.geometry
    if q is None:         # the thesis pose at the same fractions of the arm's joint ranges
        q = arm_pose(arm, np.array(SUMMARY_POSE))
        if not bool(geo.in_working_area(q, arm)):
            q = np.array([0.5 * (g.q1_min + g.q1_max), 0.5 * (g.q2_min + g.q2_max)])
    else:
        q = np.array([check_range(f"q[{i}]", v, -np.pi, np.pi, unit="rad")
                      for i, v in enumerate(np.asarray(q, dtype=float).ravel()[:2])])
        if q.size != 2 or not bool(geo.in_working_area(q, arm)):
            raise ValueError(f"q = {np.degrees(q).round(3).tolist()} deg is outside the working "
                             f"area q1 in [{np.degrees(g.q1_min):.4g}, {np.degrees(g.q1_max):.4g}]"
                             f", q2 in [{np.degrees(g.q2_min):.4g}, {np.degrees(g.q2_max):.4g}] deg")
    rest = rest_stiffness(arm, q)
    p, holdable, K = np.array(rest.pressures), rest.holdable, rest.stiffness
    smap = stiffness_map(arm, n1=n, n2=n)
    sm = smap.data
    ml = max_load_map(arm, n1=2 * n, n2=2 * n)
    grid = _grid(arm, n, n)
    tcp = geo.forward_kinematics(grid, arm)
    r = np.hypot(tcp[:, 0], tcp[:, 1])
    # TCP workspace area: the integral of |det J| over the joint ranges (one-to-one here)
    dq = (g.q1_max - g.q1_min) * (g.q2_max - g.q2_min)
    detj = np.abs(np.linalg.det(geo.jacobian(grid, arm)))
    eps = geo.contractions(grid, arm)
    L = arm.links
    rows = [
        ("stiffness pose q1, q2", f"{np.degrees(q[0]):.4g}, {np.degrees(q[1]):.4g}", "deg"),
        ("static pressures p1..p4 at the pose",
         ", ".join(f"{v / BAR:.3f}" for v in p) + ("" if holdable else "  (NOT holdable)"),
         "bar"),
        ("joint stiffness K1 at the pose (2.18)", float(K[0]), "N m/rad"),
        ("joint stiffness K2 at the pose (2.18)", float(K[1]), "N m/rad"),
        ("K1 over the working area", f"{sm.K1_Nm_per_rad.min():.4g} .. "
                                     f"{sm.K1_Nm_per_rad.max():.4g}", "N m/rad"),
        ("K2 over the working area", f"{sm.K2_Nm_per_rad.min():.4g} .. "
                                     f"{sm.K2_Nm_per_rad.max():.4g}", "N m/rad"),
        ("holdable share of the working area (Delta-p)", 100.0 * float(sm.holdable.mean()), "%"),
        ("maximum load at A_L, min over the working area", ml.minimum, "kg"),
        ("  where (q1, q2)", ", ".join(f"{np.degrees(v):.4g}" for v in ml.argmin), "deg"),
        *_payload_rows(arm, ml),
        ("maximum load at A_L, median over the area", float(ml.data.M_max_kg.median()), "kg"),
        ("joint 1 range", f"{np.degrees(g.q1_min):.4g} .. {np.degrees(g.q1_max):.4g}", "deg"),
        ("joint 2 range", f"{np.degrees(g.q2_min):.4g} .. {np.degrees(g.q2_max):.4g}", "deg"),
        ("TCP distance from joint 1", f"{r.min():.4g} .. {r.max():.4g}", "m"),
        ("TCP x extent", f"{tcp[:, 0].min():.4g} .. {tcp[:, 0].max():.4g}", "m"),
        ("TCP y extent", f"{tcp[:, 1].min():.4g} .. {tcp[:, 1].max():.4g}", "m"),
        ("TCP workspace area", float(detj.mean() * dq), "m^2"),
        ("link masses m1, m2 (plant)", f"{L.m1:.4g}, {L.m2:.4g}", "kg"),
        ("mean pressures p_m", ", ".join(f"{v / BAR:.4g}" for v in arm.pneumatics.p_mean),
         "bar"),
        *[(f"contraction of group {k + 1} over the working area",
           f"{eps[:, k].min():.3f} .. {eps[:, k].max():.3f}", "-") for k in range(4)],
        ("effects on", ", ".join(arm.effects.enabled()) or "none", ""),
    ]
    df = pd.DataFrame(rows, columns=["quantity", "value", "unit"])
    return ArmSummary(name=arm.name, pose=(float(q[0]), float(q[1])),
                      pose_pressures=tuple(float(v) for v in p), pose_holdable=holdable,
                      stiffness=(float(K[0]), float(K[1])), data=df, stiffness_map=smap,
                      max_load_map=ml)


# ----------------------------------------------------------------------------- arm checks
# What an arm file must satisfy beyond the data checks of its parameter classes (ranges,
# cross-field geometry: ppamsafety.params): the physics of the arm.  load_arm applies them to
# every file a command reads; arm_notes lists what is physically possible but likely a slip.

#: Poses per joint of the grid on which an arm must hold itself somewhere (as arm_summary).
HOLD_GRID = 61

#: A muscle group's force law (3.9) pulls, on average over the design contraction range
#: [eps_min, eps_max], within this factor of the theoretical PPAM of its size: F/p = l0^2
#: f_t0(eps, l0/R) (thesis (2.2), :mod:`ppamsafety.plant.ppam_theory`).  The thesis' identified
#: groups (Table B.1) pull 0.57 to 1.16 times the theory; a McKibben muscle of the same size
#: about 0.2 times.  Unit slips are 1e3 (kPa) to 1e5 (N/bar values written as N/Pa) times off.
FORCE_LAW_FACTOR = 30.0

#: The plant's gravity moments m1 L_G1 + m2 L1 and m2 L_G2 differ from the controllers'
#: identified model when the gap exceeds MODEL_GAP times the plant's value plus
#: MODEL_GAP_FLOOR [kg m] (a 1 kg link 1 cm off).  The thesis' two identifications of one arm
#: (Tables 3.1, 3.5) differ by up to 3 % on these moments and its reconciled plant by up to
#: 5 % (params.inertia); an arm with a 30 % heavier forearm and the thesis model differs by 35 %.
MODEL_GAP = 0.10
MODEL_GAP_FLOOR = 0.01

#: The controllers' identified inertias (theta3 = I_zO,1 + m2 L1^2, theta6 = I_zS,2) are not
#: physically consistent (Table 3.5 is 8 times below its plant on theta3, params.inertia), but
#: one more than this factor from the plant's is noted: an inertia in g m^2 written as kg m^2
#: is 1000 times off.
INERTIA_GAP_FACTOR = 30.0

#: A valve time constant at or above this [s] gets a note: the thesis' valves take 45-60 ms
#: (Table B.2, §4.2.5); 2-10 ms written with unit "s" land here.
SLOW_VALVE = 1.0

#: A joint working range narrower than this [rad] gets a note: the thesis arm's are 85 and
#: 100 deg (2.6)-(2.7); radian values written with unit "deg" (0.35 to 1.83 deg) land here.
NARROW_RANGE = 5.0 * DEG

#: An encoder coarser than this per count [rad] gets a note: the thesis arm's counts 2 pi/8000
#: (0.045 deg, §2.4.5); a resolution in degrees written with unit "rad" lands here.
COARSE_ENCODER = 1.0 * DEG

#: A timing-board clock slower than this [Hz] gets a note: the board times encoder pulses to
#: well below the 1 ms control period (the thesis': 2 MHz, §2.4.5); "2" meant in MHz lands here.
SLOW_CLOCK = 1.0e4

#: Unit slips of a pressure: the factor to the value meant, and the slip.
_PRESSURE_SLIPS = ((BAR, "bar written as Pa"), (1.0e3, "kPa written as Pa, or bar as mbar"))


def _bar(values) -> str:
    """Pressures [Pa] as ``"1.4 Pa (1.4e-05 bar)"`` or a list of them."""
    v = np.atleast_1d(np.asarray(values, dtype=float))
    pa = ", ".join(f"{x:.4g}" for x in v)
    bar = ", ".join(f"{x / BAR:.4g}" for x in v)
    return f"{pa} Pa ({bar} bar)" if v.size == 1 else f"[{pa}] Pa ([{bar}] bar)"


@lru_cache(maxsize=64)
def _theory_pull(slenderness: float, lo: float, hi: float) -> float:
    """Mean f_t0 of the theoretical PPAM over contractions [lo, hi] [-] (F/p = l0^2 f_t0)."""
    return float(np.mean(ppam_theory.f_t0(np.linspace(lo, hi, 5), slenderness)))


def _check_force_laws(arm) -> None:
    """Refuse a force law that no PPAM of its size can have (a unit slip, a sign error)."""
    m = arm.muscles
    for k, grp in enumerate(m.groups, start=1):
        lo = m.eps_min
        hi = min(m.eps_max, 0.95 * ppam_theory.max_contraction(grp.slenderness))
        if not hi > lo:          # too stubby a muscle for the theory over this range
            continue
        pull = float(np.mean(polynomial(grp.coefficients, np.linspace(lo, hi, 5))))
        theory = grp.l0 ** 2 * _theory_pull(grp.slenderness, lo, hi)
        ratio = pull / theory
        if 1.0 / FORCE_LAW_FACTOR <= ratio <= FORCE_LAW_FACTOR:
            continue
        if ratio > 0 and 1.0 / FORCE_LAW_FACTOR <= ratio / BAR <= FORCE_LAW_FACTOR:
            hint = (" The coefficients look like N/bar values written with unit \"N/Pa\": "
                    "write unit = \"N/bar\".")
        elif ratio > 0 and 1.0 / FORCE_LAW_FACTOR <= ratio * BAR <= FORCE_LAW_FACTOR:
            hint = (" The coefficients look like N/Pa (m^2) values written with unit "
                    "\"N/bar\": write unit = \"N/Pa\".")
        elif ratio <= 0:
            hint = " A muscle only pulls: check the signs of the coefficients."
        else:
            hint = " Check the coefficients' unit, and l0 and slenderness."
        raise ArmFileError(
            f"muscles.group{k}.force_law: the muscle pulls {pull * BAR:.4g} N/bar on average over "
            f"contractions {lo:g} to {hi:.3g} (muscles.eps_min, eps_max), {ratio:.3g} times the "
            f"theoretical PPAM of its size (muscles.group{k}.l0 = {grp.l0:.4g} m, slenderness = "
            f"{grp.slenderness:g}: {theory * BAR:.4g} N/bar, thesis (2.2)); a muscle of this size "
            f"pulls within a factor {FORCE_LAW_FACTOR:g} of it (the thesis' muscles: 0.57 to "
            f"1.16).{hint}")


def _hold_share(arm) -> tuple:
    """(share of the working area where ``arm`` holds itself, poses, pressures, holdable)."""
    q = _grid(arm, HOLD_GRID, HOLD_GRID)
    p, ok = _holding(arm, q)
    return float(ok.mean()), q, p, ok


def _closest_pose(arm, q, p) -> str:
    """The pose whose static pressures come closest to [0, p_max], and those pressures."""
    miss = np.max(np.maximum(-p, p - arm.pneumatics.p_max), axis=1)
    j = int(np.argmin(miss))
    return (f"closest: q = ({np.degrees(q[j, 0]):.4g}, {np.degrees(q[j, 1]):.4g}) deg needs "
            f"p1..p4 = {', '.join(f'{x / BAR:.3g}' for x in p[j])} bar")


def _pressure_slip(arm):
    """(pneumatics with the slip undone, the slip, holdable share) or None."""
    pnm = arm.pneumatics
    for factor, slip in _PRESSURE_SLIPS:
        for with_max in (False, True):
            try:
                fixed = replace(pnm, p_mean=tuple(v * factor for v in pnm.p_mean),
                                p_max=pnm.p_max * factor if with_max else pnm.p_max)
            except ValueError:
                continue
            share = _hold_share(arm.replace(pneumatics=fixed))[0]
            if share > 0:
                return fixed, slip, share
    return None


def _check_holds_itself(arm) -> None:
    """Refuse an arm that cannot hold itself anywhere in its working area (effects off)."""
    bare = arm if arm.effects == Effects() else arm.replace(effects=Effects())
    share, q, p, _ = _hold_share(bare)
    if share > 0:
        return
    pnm = bare.pneumatics
    what = (f"pneumatics.mean_pressure = {_bar(pnm.p_mean)} with pneumatics.max_pressure = "
            f"{_bar(pnm.p_max)}: the arm cannot hold itself anywhere in its working area (at "
            f"none of {HOLD_GRID} x {HOLD_GRID} poses do the static Delta-p pressures "
            f"(3.18)-(3.19) stay in [0, max_pressure]; {_closest_pose(bare, q, p)})")
    slip = _pressure_slip(bare)
    if slip is not None:
        fixed, name, share = slip
        also = (f" and max_pressure = {_bar(fixed.p_max)}" if fixed.p_max != pnm.p_max else "")
        raise ArmFileError(
            f"{what}.  Did you mean mean_pressure = {_bar(fixed.p_mean)}{also} (a unit slip: "
            f"{name})?  With it the arm holds itself in {100 * share:.0f} % of its working area.")
    raise ArmFileError(
        f"{what}.  Other mean pressures (pneumatics.mean_pressure), a higher "
        f"pneumatics.max_pressure, lighter links (links.m1, links.m2) or stronger muscles "
        f"(muscles.groupN.count, force_law) would let it hold itself.")


def check_arm(arm) -> None:
    """Refuse an arm whose physics cannot be right (what :func:`load_arm` adds to the data checks).

    * every muscle group's force law pulls within :data:`FORCE_LAW_FACTOR` of the theoretical
      PPAM of its size over the design contraction range (a force law in N/bar written as
      N/Pa is 1e5 times too strong);
    * the arm (its plant effects off) holds itself somewhere in its working area: at one pose
      at least of a :data:`HOLD_GRID` x :data:`HOLD_GRID` grid, the static Delta-p pressures
      (3.18)-(3.19) lie in [0, max_pressure] (``mean_pressure = [1.4, 1.5] Pa`` holds it
      nowhere: the likely unit slip is named).

    What is physically possible but likely a slip is listed by :func:`arm_notes` instead.  The
    cross-field checks that need no physics (a point of a link beyond 1.5 link lengths, ...)
    are made when the :class:`~ppamsafety.params.ArmParameters` is built.

    Parameters
    ----------
    arm : ArmParameters
        Any arm.

    Raises
    ------
    ppamsafety.params.arm_file.ArmFileError
        A ``ValueError`` naming the dotted keys of the arm file, the values and the likely
        slip.
    """
    arm = _arm(arm)
    _check_force_laws(arm)
    _check_holds_itself(arm)


def _model_note(arm):
    """The note on the plant's gravity moments against the controllers' model, or None."""
    plant = arm.plant_base
    gaps = []
    for label, attr in (("m2 L_G2", "m2LG2"), ("m1 L_G1 + m2 L1", "m1LG1_m2L1")):
        mine = getattr(plant, attr)
        theirs = [(t, getattr(getattr(arm, t), attr)) for t in ("model", "model_gravity")]
        off = [(t, v) for t, v in theirs
               if abs(v - mine) > MODEL_GAP * abs(mine) + MODEL_GAP_FLOOR]
        if off:
            listed = " and ".join(f"{v:.4g} kg m ({t}.{attr})" for t, v in off)
            gaps.append(f"{label} = {mine:.4g} kg m (links) against {listed}")
    for label, attr in (("I_zO,1 + m2 L1^2", "IO1_m2L1sq"), ("I_zS,2", "IS2")):
        mine = getattr(plant, attr)
        off = [(t, getattr(getattr(arm, t), attr)) for t in ("model", "model_gravity")]
        off = [(t, v) for t, v in off
               if not 1.0 / INERTIA_GAP_FACTOR <= v / mine <= INERTIA_GAP_FACTOR]
        if off:
            listed = " and ".join(f"{v:.4g} kg m^2 ({t}.{attr}, {v / mine:.3g} times)"
                                  for t, v in off)
            gaps.append(f"{label} = {mine:.4g} kg m^2 (links) against {listed}: more than "
                        f"{INERTIA_GAP_FACTOR:g} times off (an inertia in g m^2 written as "
                        f"kg m^2?)")
    if not gaps:
        return None
    believed, lg2 = arm.model.m2LG2, arm.links.LG2
    heavier = ""
    if abs(lg2) > 0.01 and (abs(plant.m2LG2 - believed)
                            > MODEL_GAP * abs(plant.m2LG2) + MODEL_GAP_FLOOR):
        dm = (plant.m2LG2 - believed) / lg2          # the forearm's mass at its own L_G2
        heavier = (f" (as if the forearm were {abs(dm):.3g} kg "
                   f"{'heavier' if dm > 0 else 'lighter'} than the controllers believe)")
    return (f"the plant's links differ from the controllers' identified model: "
            f"{'; '.join(gaps)}{heavier}.  The model-based controllers (gravity compensation "
            f"(3.18)-(3.19), the SMC's feedback linearisation) act on the model, not on the "
            f"plant: a re-identification of this arm would find the plant's values.  Update "
            f"[model] and [model_gravity], or keep the gap on purpose to study a model error.")


def arm_notes(arm) -> tuple:
    """What is physically possible in an arm but likely a slip: one line each.

    * the plant's gravity moments (links) differ from the controllers' identified model
      (``model``, ``model_gravity``) by more than :data:`MODEL_GAP`, or its inertias by more
      than :data:`INERTIA_GAP_FACTOR` times (one note: a warning, not an error; it is what a
      re-identification would find);
    * with its plant effects (a payload ...) the arm holds itself nowhere in its working area;
    * a valve time constant of :data:`SLOW_VALVE` or more (milliseconds written as seconds?);
    * a joint working range narrower than :data:`NARROW_RANGE` (radians written as degrees?);
    * an encoder coarser than :data:`COARSE_ENCODER` per count (degrees written as radians?),
      a timing clock slower than :data:`SLOW_CLOCK` (MHz written as Hz?).

    Parameters
    ----------
    arm : ArmParameters
        Any arm.

    Returns
    -------
    tuple of str
        The notes (empty for the thesis arm and the shipped example arm).
    """
    arm = _arm(arm)
    notes = []
    model = _model_note(arm)
    if model:
        notes.append(model)
    if arm.effects != Effects():
        share, q, p, _ = _hold_share(arm)
        bare = arm.replace(effects=Effects())
        if share == 0 and _hold_share(bare)[0] > 0:
            on = ", ".join(f"effects.{e}" for e in arm.effects.enabled())
            notes.append(f"with its plant effects ({on}) the arm "
                         f"cannot hold itself anywhere in its working area "
                         f"({_closest_pose(arm, q, p)}); without them it can")
    slow = [(f"valves.valve{i}.time_constant", v.time_constant)
            for i, v in enumerate(arm.valves.valves, start=1)]
    slow += [(f"effects.valve_time_constant[{i}]", t)
             for i, t in enumerate(arm.effects.valve_time_constant or ())]
    slow = [(k, t) for k, t in slow if np.isfinite(t) and t >= SLOW_VALVE]
    if slow:
        notes.append(f"{', '.join(f'{k} = {t:g} s' for k, t in slow)}: a valve this slow takes "
                     f"seconds to reach a set pressure (the thesis' valves: 45-60 ms); if these "
                     f"are milliseconds, write unit = \"ms\"")
    sen = arm.sensors
    if sen.encoder_resolution > COARSE_ENCODER:
        notes.append(f"sensors.encoder_resolution = {sen.encoder_resolution:.4g} rad "
                     f"({np.degrees(sen.encoder_resolution):.3g} deg per count) is coarser than "
                     f"a degree (the thesis' encoders: 0.045 deg); if {sen.encoder_resolution:g} "
                     f"is in degrees, write unit = \"deg\"")
    if sen.clock_hz < SLOW_CLOCK:
        notes.append(f"sensors.timing_clock = {sen.clock_hz:g} Hz is too slow to time encoder "
                     f"pulses within a 1 ms control period (the thesis' board: 2 MHz); if "
                     f"{sen.clock_hz:g} is in kHz or MHz, write that unit")
    g = arm.geometry
    for j in (1, 2):
        lo, hi = getattr(g, f"q{j}_min"), getattr(g, f"q{j}_max")
        if hi - lo < NARROW_RANGE:
            dlo, dhi = np.degrees(lo), np.degrees(hi)      # the numbers the file gave in deg
            as_rad = -np.pi < dlo and dhi < np.pi and dhi - dlo >= NARROW_RANGE
            hint = (f"; if {dlo:.4g} and {dhi:.4g} are radians, write unit = \"rad\""
                    if as_rad else "")
            notes.append(f"geometry.q{j}_min, geometry.q{j}_max: joint {j} moves over only "
                         f"{dhi - dlo:.3g} deg ({dlo:.4g} to {dhi:.4g} deg){hint}")
    return tuple(notes)


def load_arm(path) -> ArmParameters:
    """Read an arm file and check it: its data (``ArmParameters.from_file``) and physics
    (:func:`check_arm`).  Every command reads an arm file through this function.

    Parameters
    ----------
    path : path-like
        The ``.toml`` file (``docs/arm_files.md``; ``ppamsafety arm export`` writes a
        template).

    Returns
    -------
    ArmParameters
        The arm; :func:`arm_notes` lists what in it is possible but likely a slip.

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    ppamsafety.params.arm_file.ArmFileError
        A ``ValueError``: ``"<path>: <dotted key> = <value>: <what is allowed>"``.
    """
    arm = ArmParameters.from_file(path)
    try:
        check_arm(arm)
    except ArmFileError as exc:
        raise ArmFileError(f"{path}: {exc}") from None
    return arm
