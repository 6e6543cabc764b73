"""Figures of a test-bench diagnosis (pyplot-free ``matplotlib.figure.Figure``).

They take the :class:`~ppamsafety.diagnose.diagnosis.Diagnosis` of an
actuator record (``kind == "actuator"``) and draw from its ``replay`` and
``blocks`` data.
"""

from __future__ import annotations

import numpy as np


def _check(dg):
    from ..diagnose.diagnosis import Diagnosis

    if not isinstance(dg, Diagnosis):
        raise TypeError(f"dg must be a Diagnosis, got {type(dg).__name__}")
    if dg.kind != "actuator":
        raise ValueError(f"dg.kind = {dg.kind!r}: this figure is for actuator diagnoses")


def actuator_force_figure(dg):
    """Measured vs nominal vs diagnosed force, against contraction (loops) and time.

    Parameters
    ----------
    dg : Diagnosis
        Diagnosis of an actuator record.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    _check(dg)
    r = dg.replay
    t, eps = r["t"], r["eps"] * 100.0
    step = max(1, t.size // 6000)
    fig = Figure(figsize=(11, 7.5), layout="constrained")
    ax1, ax2 = fig.subplots(2, 1)
    sl = slice(None, None, step)
    ax1.plot(eps[sl], r["measured"][sl], ".", ms=1.5, color="0.55", label="measured")
    ax1.plot(eps[sl], r["before"][sl], "C3", lw=0.6, label="nominal law (3.9)")
    ax1.plot(eps[sl], r["after"][sl], "C0", lw=0.6, label="diagnosed")
    ax1.set_xlabel("contraction eps [%]")
    ax1.set_ylabel("force [N]")
    ax1.legend(fontsize=7)
    rr = dg.residual_rms["force"]
    ax1.set_title(f"force vs contraction: RMS error {rr['before']:.3g} -> {rr['after']:.3g} N "
                  f"(noise {rr['noise']:.3g} N)", fontsize=8)
    ax2.plot(t[sl], r["measured"][sl] - r["before"][sl], color="C3", lw=0.6,
             label="measured - nominal")
    ax2.plot(t[sl], r["measured"][sl] - r["after"][sl], color="C0", lw=0.6,
             label="measured - diagnosed")
    ax2.axhspan(-2 * rr["noise"], 2 * rr["noise"], color="0.9", zorder=0)
    ax2.set_xlabel("t [s]")
    ax2.set_ylabel("force residual [N]")
    ax2.legend(fontsize=7)
    found = ", ".join(dg.names) or "nothing named"
    fig.suptitle(f"{dg.source}: {found}" + ("; UNEXPLAINED residual remains"
                                            if dg.unexplained else ""), fontsize=9)
    return fig


def actuator_residual_figure(dg):
    """Residual divided by its noise level against time and contraction, before and after.

    Parameters
    ----------
    dg : Diagnosis
        Diagnosis of an actuator record.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    _check(dg)
    b = dg.blocks
    d = dg.replay["direction"]
    step = max(1, b["t"].size // 6000)
    sl = slice(None, None, step)
    fig = Figure(figsize=(11, 6), layout="constrained")
    axs = fig.subplots(2, 2)
    for j, key in enumerate(("before", "after")):
        e = b[key][:, 0]
        axs[0, j].plot(b["t"][sl], e[sl], ".", ms=1.5, color="C3" if j == 0 else "C0")
        axs[0, j].axhspan(-2, 2, color="0.9", zorder=0)
        axs[0, j].set_xlabel("t [s]")
        axs[0, j].set_ylabel(f"residual / noise ({key})", fontsize=8)
        for s, c, lab in ((1, "C1", "contracting"), (-1, "C2", "extending"),
                          (0, "0.5", "no motion yet")):
            m = (d == s)[sl]
            if np.any(m):
                axs[1, j].plot(b["eps"][sl][m] * 100, e[sl][m], ".", ms=1.5, color=c, label=lab)
        axs[1, j].axhspan(-2, 2, color="0.9", zorder=0)
        axs[1, j].set_xlabel("contraction eps [%]")
        axs[1, j].set_ylabel(f"residual / noise ({key})", fontsize=8)
    axs[1, 0].legend(fontsize=7)
    fig.suptitle("force residual divided by its noise level (grey band: +-2), by direction of "
                 "motion", fontsize=9)
    return fig


__all__ = ["actuator_force_figure", "actuator_residual_figure"]
