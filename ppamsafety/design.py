"""Design-level analysis of the arm: torque functions, stiffness, maximum load.

Reproduces the design figures of thesis chapter 2 as data:

* torque functions m_tau,i over the working area (fig. 2.11);
* joint stiffness (2.18) over the working area with static Delta-p pressures;
* the maximum load the arm can hold anywhere (fig. 2.15, Appendix A.4).

All functions return result objects holding pandas DataFrames; plotting lives
in :mod:`ppamsafety.plots.design` (``result.plot()`` delegates there).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from ._validation import check_instance, check_int, check_range
from .params import ArmParameters
from .params.inertia import LINK_PRIORS, RADIUS_OF_GYRATION, LinkInertia
from .plant import geometry as geo
from .plant import pneumatics as pn
from .plant import torque
from .plots.design import plot_torque_functions, plot_stiffness_map, plot_max_load
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
class TorqueFunctions:
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
        """Plot with :mod:`ppamsafety.report`; returns a matplotlib Figure.

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
class StiffnessMap:
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

    def plot(self, **kwargs):
        """Plot with :mod:`ppamsafety.report`; returns a matplotlib Figure.

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
class MaxLoadMap:
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

    def plot(self, **kwargs):
        """Plot with :mod:`ppamsafety.report`; returns a matplotlib Figure.

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
    p = pn.static_pressures(q, arm)
    pmax = arm.pneumatics.p_max
    pc = np.clip(p, 0.0, pmax)
    return p, pc, np.all((p >= 0) & (p <= pmax), axis=-1), pn.joint_stiffness(q, pc, arm)


#: Pose at which :func:`arm_summary` reports the stiffness when none is given: the
#: step-response impact configuration of thesis §6.3.3, q = (50, -80) deg (if it lies in
#: the arm's working area; else the centre of the working area).
SUMMARY_POSE = (50.0 * DEG, -80.0 * DEG)


@dataclass(frozen=True)
class ArmSummary:
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
    """

    name: str
    pose: tuple
    pose_pressures: tuple
    pose_holdable: bool
    stiffness: tuple
    data: pd.DataFrame

    def to_pandas(self) -> pd.DataFrame:
        """The numbers: ``quantity``, ``value``, ``unit``."""
        return self.data.copy()

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


def arm_summary(arm, *, q=None, n: int = 61) -> ArmSummary:
    """An arm's key design numbers: stiffness at a pose, maximum load, working area.

    Parameters
    ----------
    arm : ArmParameters
        Any valid arm.
    q : sequence of 2 float, optional, keyword-only
        Pose of the stiffness numbers [rad] (default :data:`SUMMARY_POSE` if in the
        working area, else its centre); must lie in the working area.
    n : int, keyword-only
        Grid points per joint for the maps, in [5, 2000].

    Returns
    -------
    ArmSummary
    """
    arm = _arm(arm)
    n = check_int("n", n, 5, 2000)
    g = arm.geometry
    if q is None:
        q = np.array(SUMMARY_POSE)
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
    sm = stiffness_map(arm, n1=n, n2=n).data
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
        ("maximum load (min over the working area)", ml.minimum, "kg"),
        ("  where (q1, q2)", ", ".join(f"{np.degrees(v):.4g}" for v in ml.argmin), "deg"),
        ("maximum load, median over the working area", float(ml.data.M_max_kg.median()), "kg"),
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
                      stiffness=(float(K[0]), float(K[1])), data=df)
