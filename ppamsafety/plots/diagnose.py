"""Figures of the discrepancy diagnosis (pyplot-free ``matplotlib.figure.Figure``).

Each function takes computed data and returns a Figure; nothing here simulates.

* test-bench diagnoses: :func:`actuator_force_figure`, :func:`actuator_residual_figure`
  take the :class:`~ppamsafety.diagnose.diagnosis.Diagnosis` of an actuator record
  (``kind == "actuator"``) and draw from its ``replay`` and ``blocks`` data;
* the report section :mod:`ppamsafety.sections.diagnose_cases`:
  :func:`plot_summary_profiles`, :func:`plot_gap`, :func:`plot_confusion`;
* case study (a), :mod:`ppamsafety.sections.diagnose_sawtooth`:
  :func:`plot_sawtooth_diagnosis`;
* the as-built arm, :mod:`ppamsafety.sections.as_built`: :func:`plot_as_built`,
  :func:`plot_identifiability`; two effects of Table 5.2 together: :func:`plot_pair_fit`;
* trust in the diagnosis, :mod:`ppamsafety.sections.diagnose_trust`:
  :func:`plot_calibration`, :func:`plot_detection_curve`.
"""

from __future__ import annotations

import numpy as np

from .figure import new_figure


def _check(dg, kind: str = "actuator"):
    if not all(hasattr(dg, a) for a in ("kind", "replay", "blocks", "residual_rms", "names")):
        raise TypeError(f"dg must be a Diagnosis, got {type(dg).__name__}")
    if (dg.kind == "actuator") != (kind == "actuator"):
        raise ValueError(f"dg.kind = {dg.kind!r}: this figure is for {kind} diagnoses")


def arm_replay_figure(dg):
    """Measured vs before vs after (full simulation) for q, qd, p of an arm diagnosis.

    Parameters
    ----------
    dg : Diagnosis
        Diagnosis of an arm record (``replay`` holds ``t`` and the ``measured``,
        ``before`` and ``after`` arrays, one column per channel, the channel names
        ``channels`` and their SI ``units``; ``"Pa"`` is drawn in bar).

    Returns
    -------
    matplotlib.figure.Figure
    """
    _check(dg, "arm")
    r = dg.replay
    t, channels, units = r["t"], r["channels"], r["units"]
    step = max(1, t.size // 4000)
    fig, axs = new_figure(4, 2, figsize=(11, 9), layout="constrained", sharex=True)
    for k, ax in enumerate(axs.T.ravel()):
        scale = 1e-5 if units[k] == "Pa" else 1.0
        unit = "bar" if units[k] == "Pa" else units[k]
        mk = dict(marker="o", ms=3, ls="none") if r.get("static") else {}
        ax.plot(t[::step], r["measured"][::step, k] * scale, color="0.6", lw=0.8,
                label="measured", **mk)
        ax.plot(t[::step], r["before"][::step, k] * scale, "C3", lw=0.9,
                label="model before", **(dict(mk, marker="s", mfc="none") if mk else {}))
        ax.plot(t[::step], r["after"][::step, k] * scale, color="C0", lw=0.9,
                label="model after", **(dict(mk, marker="x") if mk else {"ls": "--"}))
        rr = dg.residual_rms.get(channels[k])
        if rr is not None:
            ax.set_title(f"{channels[k]}: RMS error {rr['before']:.3g} -> "
                         f"{rr['after']:.3g} {units[k]}", fontsize=8)
        ax.set_ylabel(f"{channels[k]} [{unit}]", fontsize=8)
    axs[0, 0].legend(fontsize=7)
    axs[-1, 0].set_xlabel("t [s]")
    axs[-1, 1].set_xlabel("t [s]")
    found = ", ".join(dg.names) or "nothing named"
    fig.suptitle(f"{dg.source}: {found}" + ("; UNEXPLAINED residual remains"
                                          if dg.unexplained else ""), fontsize=9)
    return fig


def arm_blocks_figure(dg):
    """Whitened block residuals per subsystem channel of an arm diagnosis, before and after.

    Parameters
    ----------
    dg : Diagnosis
        Diagnosis of an arm record (``blocks`` holds ``t``, the whitened
        ``before`` and ``after`` residuals, one column per channel, and the
        channel names ``channels``).

    Returns
    -------
    matplotlib.figure.Figure
    """
    _check(dg, "arm")
    b = dg.blocks
    channels = b["channels"]
    fig, axs = new_figure(3, 2, figsize=(11, 7), layout="constrained", sharex=True)
    for c, ax in enumerate(axs.T.ravel()):
        ax.plot(b["t"], b["before"][:, c], ".", ms=2, color="C3", label="before")
        ax.plot(b["t"], b["after"][:, c], ".", ms=2, color="C0", label="after")
        ax.axhspan(-2, 2, color="0.9", zorder=0)
        ax.set_ylabel(f"{channels[c]} / noise", fontsize=8)
    axs[0, 0].legend(fontsize=7)
    fig.suptitle("block residuals divided by their noise level (grey band: +-2)", fontsize=9)
    return fig


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
    _check(dg)
    r = dg.replay
    t, eps = r["t"], r["eps"] * 100.0
    step = max(1, t.size // 6000)
    fig, (ax1, ax2) = new_figure(2, 1, figsize=(11, 7.5), layout="constrained")
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
    _check(dg)
    b = dg.blocks
    d = dg.replay["direction"]
    step = max(1, b["t"].size // 6000)
    sl = slice(None, None, step)
    fig, axs = new_figure(2, 2, figsize=(11, 6), layout="constrained")
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


def plot_summary_profiles(fit, *, rank_tol: float):
    """chi2 profile along every effect axis and the singular values of the sensitivity.

    Parameters
    ----------
    fit : ppamsafety.thesis_fits.summary_fit.SummaryFit
        Result of :func:`~ppamsafety.thesis_fits.summary_fit.fit_summary`.
    rank_tol : float, keyword-only
        Singular values below this fraction of the largest do not count towards the rank
        (drawn as a dotted line; ``summary_fit.RANK_TOL``).

    Returns
    -------
    matplotlib.figure.Figure
        Left: chi2 / number of statistics against theta (0 = nominal plant,
        1 = largest plausible magnitude) per effect, the nominal level dashed.
        Right: singular values of the whitened sensitivity matrix (divided by
        the largest), the rank threshold dotted.
    """
    fig, (a, b) = new_figure(1, 2, figsize=(11, 4.2), gridspec_kw={"width_ratios": [2, 1]})
    prof = fit.profiles
    for k, (name, g) in enumerate(prof.groupby("effect", sort=False)):
        ls = "-" if k < 10 else "--"
        a.plot(g.theta, g.chi2 / fit.m, ls, lw=1.3, label=name)
    a.axhline(fit.nominal_chi2 / fit.m, color="k", ls="--", lw=0.8, label="nominal plant")
    a.axhline(1.0, color="0.5", ls=":", lw=0.8, label="data uncertainty")
    a.set_yscale("log")
    a.set_xlabel("theta (0: nominal, 1: largest plausible magnitude) [-]")
    a.set_ylabel("chi2 / statistic [-]")
    a.set_title("Table 5.2: fit of one effect at a time", fontsize=9)
    a.legend(fontsize=7, ncol=2)
    a.grid(alpha=0.3)
    sv = fit.singular_values
    b.semilogy(np.arange(1, sv.size + 1), sv, "o-")
    b.axhline(rank_tol, color="0.5", ls=":", lw=0.8)
    b.set_xlabel("singular value index [-]")
    b.set_ylabel("s_i / s_1 [-]")
    b.set_title(f"sensitivity: rank {fit.rank} of {sv.size}, condition {fit.condition:.3g}",
                fontsize=9)
    b.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def plot_gap(residual_rms: dict, *, title: str = ""):
    """Replay RMS error per channel before and after the diagnosis, relative to the noise.

    Parameters
    ----------
    residual_rms : dict
        ``Diagnosis.residual_rms`` (channels q1..p4 with before, after, noise).
    title : str
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        Bars of before / after RMS divided by the channel's noise level
        (log scale).
    """
    chans = [c for c in residual_rms if not c.startswith("block_")]
    before = np.array([residual_rms[c]["before"] / residual_rms[c]["noise"] for c in chans])
    after = np.array([residual_rms[c]["after"] / residual_rms[c]["noise"] for c in chans])
    fig, ax = new_figure(1, 1, figsize=(7, 3.5))
    x = np.arange(len(chans))
    ax.bar(x - 0.2, before, 0.4, color="C3", label="nominal model")
    ax.bar(x + 0.2, after, 0.4, color="C0", label="after the diagnosis")
    ax.axhline(1.0, color="k", lw=0.8, ls=":")
    ax.set_xticks(x, chans)
    ax.set_yscale("log")
    ax.set_ylabel("replay RMS error / noise [-]")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def plot_confusion(matrix):
    """The blind battery's confusion matrix (hidden effects x named effects).

    Parameters
    ----------
    matrix : pandas.DataFrame
        Counts; index: hidden case, columns: named set.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = new_figure(1, 1, figsize=(1.2 + 0.9 * matrix.shape[1], 1.0 + 0.45 * matrix.shape[0]))
    v = matrix.to_numpy(dtype=float)
    ax.imshow(v, cmap="Blues", vmin=0, vmax=max(v.max(), 1), aspect="auto")
    for i in range(v.shape[0]):
        for j in range(v.shape[1]):
            if v[i, j]:
                ax.text(j, i, f"{int(v[i, j])}", ha="center", va="center", fontsize=8)
    ax.set_xticks(range(v.shape[1]), [str(c) for c in matrix.columns], rotation=35,
                  ha="right", fontsize=7)
    ax.set_yticks(range(v.shape[0]), [str(c) for c in matrix.index], fontsize=7)
    ax.set_xlabel("named by the diagnosis")
    ax.set_ylabel("hidden in the record")
    fig.tight_layout()
    return fig


def plot_sawtooth_diagnosis(rest, metrics):
    """Measured vs model-before vs model-after rest angles, and the muscle-force residuals.

    Parameters
    ----------
    rest : pandas.DataFrame
        :attr:`ppamsafety.sections.diagnose_sawtooth.DiagnoseSawtoothFindings.rest_points`.
    metrics : dict
        The study's metrics (RMS numbers for the titles).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axs = new_figure(3, 1, figsize=(11, 8), layout="constrained", sharex=True)
    k = rest["rest point"].to_numpy()
    for j, ax in enumerate(axs[:2]):
        q = f"q{j + 1}"
        ax.plot(k, rest[f"{q}_set_deg"], "k:", marker="_", label="set angle")
        ax.plot(k, rest[f"{q}_measured_deg"], "o", color="0.4", ms=5, label="measured")
        ax.plot(k, rest[f"{q}_before_deg"], "s", mfc="none", color="C3", ms=7,
                label="model before")
        ax.plot(k, rest[f"{q}_after_deg"], "x", color="C0", ms=7, label="model after")
        ax.set_ylabel(f"{q} [deg]")
        ax.set_title(f"{q}: model vs measured RMS {metrics[f'rms_{q}_before_deg']:.3f} -> "
                     f"{metrics[f'rms_{q}_after_deg']:.3f} deg", fontsize=9)
    axs[0].legend(fontsize=7, ncol=4)
    ax = axs[2]
    w = 0.2
    for i in range(4):
        ax.bar(k + (i - 1.5) * w, rest[f"F{i + 1}_residual_before_N"], w, color=f"C{i}",
               alpha=0.5, label=f"F{i + 1} before")
        ax.plot(k + (i - 1.5) * w, rest[f"F{i + 1}_residual_after_N"], "_", color=f"C{i}", ms=8)
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_ylabel("measured - model force [N]")
    ax.set_xlabel("rest point [-]")
    ax.legend(fontsize=7, ncol=4)
    ax.set_title("muscle-force residual (bars: nominal model, dashes: with the fitted delta)",
                 fontsize=9)
    fig.suptitle(f"hidden hysteresis delta = {metrics['delta_hidden']:.3f}: named "
                 f"{metrics['named']}, delta = {metrics['delta_fit']:.4f}", fontsize=10)
    _ = np
    return fig


def plot_as_built(cells, effects, *, sources):
    """The as-built arm: every printed number against the nominal and the as-built simulation.

    Parameters
    ----------
    cells : pandas.DataFrame
        One row per printed number (``ppamsafety.thesis_fits.as_built.AsBuiltFit.cells``):
        ``source``, ``ratio_nominal``, ``ratio_as_built`` (simulated / printed) and
        ``sigma_log`` (standard uncertainty of ln ratio).
    effects : pandas.DataFrame
        One row per candidate (``AsBuiltFit.effects``): ``candidate``, ``fitted``,
        ``theta`` and its 95 % interval ``theta_low``, ``theta_high``.
    sources : sequence of str, keyword-only
        Sources in display order (``as_built.SOURCES``).

    Returns
    -------
    matplotlib.figure.Figure
        Left: ln(simulated / printed) per number, grouped by source, nominal (grey) and
        as-built (colour), the +-2 sigma band of each number as a bar.  Right: the fitted
        thetas with their 95 % intervals (0 = nominal arm, 1 = largest plausible magnitude).
    """
    fig, (a, b) = new_figure(1, 2, figsize=(12, 4.4), gridspec_kw={"width_ratios": [3, 1]})
    x0, ticks, labels = 0, [], []
    for k, src in enumerate(s for s in sources if (cells.source == s).any()):
        c = cells[cells.source == src]
        x = x0 + np.arange(len(c))
        sig = c.sigma_log.to_numpy(float)
        a.fill_between(x, -2 * sig, 2 * sig, color="0.9", step="mid")
        a.plot(x, np.log(c.ratio_nominal.to_numpy(float)), "o", ms=3, color="0.55",
               label="nominal" if k == 0 else None)
        a.plot(x, np.log(c.ratio_as_built.to_numpy(float)), "o", ms=3.5, color=f"C{k}",
               label=src)
        ticks.append(x0 + (len(c) - 1) / 2)
        labels.append(src.replace("Table ", "T").replace(" RMS", ""))
        x0 += len(c) + 3
    a.axhline(0.0, color="k", lw=0.8)
    a.set_xticks(ticks)
    a.set_xticklabels(labels, fontsize=8)
    a.set_ylabel("ln(simulated / printed) [-]")
    a.set_title("every printed number: nominal (grey) and as-built; band: ±2σ", fontsize=9)
    a.legend(fontsize=7, ncol=2)
    a.grid(alpha=0.3)
    fe = effects[effects.fitted]
    y = np.arange(len(effects))
    th = fe.theta.to_numpy(float)
    b.errorbar(th, [list(effects.candidate).index(n) for n in fe.candidate],
               xerr=[th - fe.theta_low.to_numpy(float), fe.theta_high.to_numpy(float) - th],
               fmt="o", capsize=3)
    nf = effects[~effects.fitted]
    b.plot(np.zeros(len(nf)), [list(effects.candidate).index(n) for n in nf.candidate], "x",
           color="0.5", label="not fitted (nominal)")
    b.set_yticks(y)
    b.set_yticklabels(effects.candidate, fontsize=7)
    b.axvline(0.0, color="k", lw=0.8)
    b.set_xlim(-1.05, 1.05)
    b.set_xlabel("theta (0 nominal, ±1 largest plausible) [-]", fontsize=8)
    b.set_title("fitted effects, 95 % intervals", fontsize=9)
    b.legend(fontsize=7)
    b.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def plot_identifiability(names, column_norm, cosines, selected, singular_values, *,
                         rank_tol: float):
    """What a sensitivity matrix can identify: column norms, singular values, |cos| map.

    Parameters
    ----------
    names : sequence of str
        Candidates (columns of the sensitivity matrix).
    column_norm : array_like, shape (K,)
        Change of the whitened residual vector per unit theta of each candidate [-].
    cosines : array_like or pandas.DataFrame, shape (K, K)
        |cos| between the columns [-].
    selected : collection of str
        The identifiable subset (drawn in colour, the others grey).
    singular_values : array_like
        Singular values divided by the largest [-].
    rank_tol : float, keyword-only
        Relative rank threshold (dotted line).

    Returns
    -------
    matplotlib.figure.Figure
        Left: column norm per candidate (log scale).  Middle: singular values relative to
        the largest, the rank threshold dotted.  Right: |cos| between the candidates.
    """
    names = list(names)
    norms = np.asarray(column_norm, float)
    cos = np.asarray(cosines, float)
    sv = np.asarray(singular_values, float)
    fig, (a, b, c) = new_figure(1, 3, figsize=(13, 4.2),
                                gridspec_kw={"width_ratios": [1.2, 0.8, 1.2]})
    y = np.arange(len(names))
    colours = ["C0" if n in selected else "0.6" for n in names]
    a.barh(y, np.maximum(norms, 1e-12), color=colours)
    a.set_yticks(y)
    a.set_yticklabels(names, fontsize=7)
    a.invert_yaxis()
    a.set_xscale("log")
    a.set_xlabel("|dr/dθ|: whitened residual per unit theta [-]", fontsize=8)
    a.set_title("sensitivity per candidate (colour: identifiable)", fontsize=9)
    a.grid(alpha=0.3)
    b.semilogy(np.arange(1, sv.size + 1), np.maximum(sv, 1e-16), "o-")
    b.axhline(rank_tol, color="0.5", ls=":", lw=0.8, label="rank threshold")
    b.set_xlabel("singular value index [-]")
    b.set_ylabel("s_i / s_1 [-]")
    b.set_title(f"rank {int(np.sum(sv > rank_tol))} of {sv.size}", fontsize=9)
    b.legend(fontsize=7)
    b.grid(alpha=0.3)
    im = c.imshow(cos, vmin=0.0, vmax=1.0, cmap="viridis")
    c.set_xticks(y)
    c.set_xticklabels(names, fontsize=6, rotation=60, ha="right")
    c.set_yticks(y)
    c.set_yticklabels(names, fontsize=6)
    c.set_title("|cos| between candidates", fontsize=9)
    fig.colorbar(im, ax=c, label="|cos| [-]")
    fig.tight_layout()
    return fig


def plot_pair_fit(grid, names, best_theta, *, statistics: int, chi2_single: float):
    """chi2 of two effects fitted together, over their theta plane.

    Parameters
    ----------
    grid : pandas.DataFrame
        ``theta_a``, ``theta_b``, ``chi2`` on a full rectangular grid
        (``ppamsafety.thesis_fits.summary_fit.PairFit.grid``).
    names : (str, str)
        The two effects (axes a and b).
    best_theta : (float, float)
        The best point (marked).
    statistics : int, keyword-only
        Number of statistics (chi2 is drawn per statistic).
    chi2_single : float, keyword-only
        Best chi2 of either effect alone (the contour where the pair does as well).

    Returns
    -------
    matplotlib.figure.Figure
        Filled contours of log10(chi2 / statistic) over (theta_a, theta_b), the best point
        and the contour of the best single effect.
    """
    ta = np.unique(grid.theta_a.to_numpy(float))
    tb = np.unique(grid.theta_b.to_numpy(float))
    g = grid.sort_values(["theta_a", "theta_b"])
    z = g.chi2.to_numpy(float).reshape(ta.size, tb.size) / statistics
    z = np.where(np.isfinite(z), z, np.nan)
    fig, ax = new_figure(1, 1, figsize=(6.4, 5.0))
    cs = ax.contourf(ta, tb, np.log10(np.maximum(z, 1e-12)).T, levels=20, cmap="viridis_r")
    fig.colorbar(cs, ax=ax, label="log10(chi2 / statistic) [-]")
    if np.nanmin(z) <= chi2_single / statistics <= np.nanmax(z):
        ax.contour(ta, tb, z.T, levels=[chi2_single / statistics], colors="w",
                   linestyles="--", linewidths=1.0)
    ax.plot(*best_theta, "r*", ms=12, label="best pair")
    ax.set_xlabel(f"theta of {names[0]} (0 nominal, 1 largest plausible) [-]", fontsize=8)
    ax.set_ylabel(f"theta of {names[1]} [-]", fontsize=8)
    ax.set_title("two effects together (dashed: as good as the best single effect)",
                 fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


__all__ = ["actuator_force_figure", "actuator_residual_figure", "plot_summary_profiles", "plot_gap",
           "plot_confusion", "plot_sawtooth_diagnosis", "plot_as_built", "plot_identifiability",
           "plot_pair_fit"]


def plot_calibration(table, *, required: float):
    """Precision of every claimed confidence level with its 95 % Wilson lower bound.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`ppamsafety.diagnose.scenarios.calibration_table` (``claimed``, ``names``,
        ``right``, ``precision``, ``wilson_low``; an optional ``battery`` column labels
        the bars of several batteries).
    required : float, keyword-only
        The promised precision of "high" (drawn as a line).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = new_figure(1, 1, figsize=(6.5 if len(table) <= 3 else 9.0, 3.6))
    x = np.arange(len(table))
    prec = table["precision"].to_numpy(dtype=float)
    low = table["wilson_low"].to_numpy(dtype=float)
    colors = [{"high": "tab:green", "low": "tab:orange"}.get(c, "tab:gray")
              for c in table["claimed"]]
    ax.bar(x, prec, color=colors, alpha=0.8)
    ax.errorbar(x, prec, yerr=[np.nan_to_num(prec - low), np.zeros_like(prec)], fmt="none",
                ecolor="k", capsize=4, lw=1)
    ax.axhline(required, color="tab:red", ls="--", lw=1, label=f"promised for 'high': "
               f"{required:.0%}")
    batteries = table["battery"] if "battery" in table else [""] * len(table)
    labels = [f"{b + ': ' if b else ''}{c}\n{int(n)} names"
              for b, c, n in zip(batteries, table["claimed"], table["names"])]
    ax.set_xticks(x, [lab.replace(" (group holds a hidden member)", "") for lab in labels],
                  fontsize=8)
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("share of names that were right [-]")
    ax.set_title("Calibration on unseen scenarios (bars: precision, whiskers down to the "
                 "95 % Wilson bound)", fontsize=8)
    ax.legend(fontsize=8, loc="lower left")
    ax.grid(alpha=0.3, axis="y")
    return fig


def plot_detection_curve(curve, *, power: float):
    """Named and "high" rate of hidden effects against their magnitude over the record's limit.

    Parameters
    ----------
    curve : pandas.DataFrame
        :func:`ppamsafety.diagnose.scenarios.detection_curve`.
    power : float, keyword-only
        The rate promised at the limit (drawn at ratio 1).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, ax = new_figure(1, 1, figsize=(6.5, 3.6))
    hi = curve["ratio_to"].to_numpy(dtype=float)
    lo = curve["ratio_from"].to_numpy(dtype=float)
    mid = np.where(np.isfinite(hi), np.sqrt(np.maximum(lo, 0.05) * hi), lo * 2)
    ax.semilogx(mid, curve["named_rate"], "o-", label="named (any confidence)")
    ax.semilogx(mid, curve["high_rate"], "s--", label="named with high confidence")
    ax.axvline(1.0, color="0.5", ls=":", lw=1)
    ax.axhline(power, color="tab:red", ls="--", lw=1, label=f"{power:.0%} promised at the limit")
    for x, n in zip(mid, curve["effects"]):
        ax.annotate(str(int(n)), (x, 0.02), ha="center", fontsize=7, color="0.4")
    ax.set_ylim(0, 1.05)
    ax.set_xlabel("hidden magnitude / the record's naming limit [-]")
    ax.set_ylabel("fraction of hidden effects [-]")
    ax.set_title("Detection limits kept (numbers: hidden effects per bin)", fontsize=8)
    ax.legend(fontsize=8, loc="center right")
    ax.grid(alpha=0.3)
    return fig
