"""Figures of the discrepancy-workflow case studies (pyplot-free)."""

from __future__ import annotations

import numpy as np


def plot_sawtooth_diagnosis(rest, metrics):
    """Measured vs model-before vs model-after rest angles, and the muscle-force residuals.

    Parameters
    ----------
    rest : pandas.DataFrame
        :attr:`ppamsafety.studies.diagnose_sawtooth.DiagnoseSawtoothStudy.rest_points`.
    metrics : dict
        The study's metrics (RMS numbers for the titles).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 8), layout="constrained")
    axs = fig.subplots(3, 1, sharex=True)
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
    ax.set_xlabel("rest point")
    ax.legend(fontsize=7, ncol=4)
    ax.set_title("muscle-force residual (bars: nominal model, dashes: with the fitted delta)",
                 fontsize=9)
    fig.suptitle(f"hidden hysteresis delta = {metrics['delta_hidden']:.3f}: named "
                 f"{metrics['named']}, delta = {metrics['delta_fit']:.4f}", fontsize=10)
    _ = np
    return fig


__all__ = ["plot_sawtooth_diagnosis"]
