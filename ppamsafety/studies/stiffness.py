"""Influence of the joint stiffness on the impact force (thesis §6.3.4, fig. 6.3)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..control import PID
from ..experiments.catalog import run_thesis_experiment
from ..impact.instants import heuristic_instants, impact_states
from ..impact.model import effective_mass, simulate_impacts
from ..impact.thesis_data import FIG_6_3
from ..impact.twobody import two_body_impact
from ..params.head import head_model
from ..plant import dynamics as dyn
from ..plant import geometry as geo
from ..report.tables import markdown_table
from . import Section, resolve_arm


@dataclass
class StiffnessStudy:
    """Result of :func:`compute`: F_max of one impact against the joint stiffness.

    Attributes
    ----------
    quick : bool
        9 stiffness values instead of 31.
    instant : pandas.Series
        Impact state (row of :func:`~ppamsafety.impact.instants.impact_states`)
        at the PID step's instant of largest TCP speed.
    tool_speed : float
        Tool speed at that instant [m/s].
    sweep : pandas.DataFrame
        ``k`` [Nm/rad], ``F_max`` [N], ``HIC36``, ``dF vs k=1 [N]``.
    m_eff, m_link2 : float
        Effective mass at the tool along the impact direction, and that of
        the forearm alone (joint 1 locked) [kg].
    f_two_body : float
        Two-body F_max with ``m_eff`` [N].
    contact : float
        Contact duration at the experiment's stiffness [s].
    periods : dict
        Joint stiffness [Nm/rad] -> shortest vibration period of the arm [s].
    k_5N : float
        Smallest stiffness where F_max differs from k = 1 by more than the
        thesis' 5 N [Nm/rad] (inf if never).
    metrics : dict
        Headline numbers.
    """

    quick: bool
    instant: pd.Series
    tool_speed: float
    sweep: pd.DataFrame
    m_eff: float
    m_link2: float
    f_two_body: float
    contact: float
    periods: dict
    k_5N: float
    metrics: dict = field(default_factory=dict)

    def to_pandas(self) -> pd.DataFrame:
        """The stiffness sweep."""
        return self.sweep.copy()

    def plot(self) -> dict:
        """The study's figures, ``{file name: Figure}``."""
        from ..report.impact_figures import plot_stiffness_sweep

        return {"stiffness_sweep.png": plot_stiffness_sweep(
            self.sweep, reference=tuple(self.instant[["K1", "K2"]]), two_body=self.f_two_body)}


def compute(*, quick: bool = False, arm=None) -> StiffnessStudy:
    """Sweep both joint stiffnesses from 1 to 6000 Nm/rad for the step-response impact.

    Parameters
    ----------
    quick : bool
        9 stiffness values instead of 31.
    arm : ppamsafety.params.ArmParameters, optional
        Arm (default: the thesis arm).

    Returns
    -------
    StiffnessStudy
        Sweep table, effective masses, time scales and metrics.
    """
    arm = resolve_arm(arm)
    head = head_model()
    res = run_thesis_experiment(arm, "step", [("PID", PID())])[0]
    st = impact_states(res, arm)
    row = st.iloc[heuristic_instants(st)["max TCP speed"]]
    q = row[["q1", "q2"]].to_numpy(float)
    qd = row[["qd1", "qd2"]].to_numpy(float)
    k = np.geomspace(FIG_6_3["k_min"], FIG_6_3["k_max"], 9 if quick else 31)
    sw = simulate_impacts(arm, np.tile(q, (k.size, 1)), np.tile(qd, (k.size, 1)),
                          np.stack([k, k], 1), head=head).summary
    own = simulate_impacts(arm, q, qd, row[["K1", "K2"]].to_numpy(float), head=head,
                           history=True)
    df = pd.DataFrame({"k": k, "F_max": sw.F_max, "HIC36": sw.HIC36,
                       "dF vs k=1 [N]": sw.F_max - sw.F_max.iloc[0]})
    v = geo.jacobian(q, arm) @ qd
    u = v / np.linalg.norm(v)
    m_eff = float(effective_mass(q, u, arm))
    tb = two_body_impact([np.linalg.norm(v)], arm_mass=m_eff, head_mass=head.mass,
                         stiffness=head.stiffness, exponent=head.exponent, damping=head.damping)
    f_two = float(tb["F_max"][0])
    # link-2-only apparent mass (joint 1 locked) and the springs' time scales
    J = geo.jacobian(q, arm)
    H = dyn.inertia_matrix(q, arm)
    m_link2 = float(1.0 / (u @ np.outer(J[:, 1], J[:, 1]) @ u / H[1, 1]))
    contact = float(own.summary.contact_time.iloc[0])
    periods = {kk: 2 * math.pi * math.sqrt(min(np.linalg.eigvalsh(H)) / kk) for kk in (43.0, 6000.0)}
    dF = float(df["F_max"].max() - df["F_max"].min())
    small = df[df.k <= 500]
    dF_small = float(small["F_max"].max() - small["F_max"].min())
    beyond = (df["F_max"] - df["F_max"].iloc[0]).abs() > FIG_6_3["max_change_N"]
    k_5N = float(df.k[beyond].min()) if beyond.any() else float("inf")
    metrics = {"dF_total_N": dF, "dF_upto500_N": dF_small, "m_eff": m_eff, "F_two_body": f_two,
               "F_full_k1": float(df.F_max.iloc[0]), "contact_ms": 1e3 * contact}
    return StiffnessStudy(quick=quick, instant=row, tool_speed=float(np.linalg.norm(v)), sweep=df,
                          m_eff=m_eff, m_link2=m_link2, f_two_body=f_two, contact=contact,
                          periods=periods, k_5N=k_5N, metrics=metrics)


def render(study: StiffnessStudy) -> Section:
    """The report section of the stiffness study (formatting only).

    Parameters
    ----------
    study : StiffnessStudy
        Output of :func:`compute`.

    Returns
    -------
    Section
        Markdown and artifacts (figure, ``stiffness_sweep.csv``).
    """
    quick, row, df, periods = study.quick, study.instant, study.sweep, study.periods
    m_eff, m_link2, f_two, contact = study.m_eff, study.m_link2, study.f_two_body, study.contact
    dF, dF_small, k_5N = study.metrics["dF_total_N"], study.metrics["dF_upto500_N"], study.k_5N
    md = f"""The PID step-response impact (instant of largest TCP speed, t0 = {row.t:.3f} s, tool speed
{study.tool_speed:.2f} m/s) repeated with both joint stiffnesses set to k from 1 to 6000 Nm/rad (fig. 6.3).

{markdown_table(df.iloc[::3 if not quick else 1], digits=2)}

* Over the whole range F_max changes by {dF:.1f} N ({100 * dF / df.F_max.max():.2f} %); the thesis reports
  less than 5 N (0.33 %). Up to 500 Nm/rad the change is {dF_small:.2f} N; the 5 N mark is passed at
  k = {k_5N:.0f} Nm/rad.
* **Why it is nearly independent:** the impact lasts {1e3 * contact:.1f} ms, far shorter than the
  arm's vibration on its joint springs (smallest period {1e3 * periods[43.0]:.0f} ms at the experiment's
  43 Nm/rad), so during the impact the springs barely act and the tool behaves like a free mass:
  the links' effective mass at the tool along the impact direction, m_eff = 1/(u^T J H^-1 J^T u) =
  {m_eff:.3f} kg (the forearm alone, joint 1 locked: {m_link2:.3f} kg). A two-body impact of that mass with
  the head gives F_max = {f_two:.1f} N, against {df.F_max.iloc[0]:.1f} N for the full model at k = 1 Nm/rad.
* **Where it stops holding:** at 6000 Nm/rad the shortest period is {1e3 * periods[6000.0]:.0f} ms, comparable
  to the contact, so the springs start to decelerate the links during the impact and F_max drops. The
  thesis' smaller change suggests a shorter contact than our reconstructed (damped, soft) head model
  gives; the conclusion that the link inertia decides holds for every stiffness a PPAM can produce.

![stiffness sweep](stiffness_sweep.png)
"""
    arts = [("stiffness_sweep.csv", df), *study.plot().items()]
    return Section("Joint stiffness and the impacting link's inertia (thesis §6.3.4)", md, arts,
                   dict(study.metrics))
