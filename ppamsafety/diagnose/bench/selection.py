"""The naming rule on a muscle record: forward selection with refit, then a backward pass.

Applies the arm's statistics (:mod:`ppamsafety.diagnose.core.linear_selection`)
to the whitened design of :mod:`.design`:

* **forward**: at each step the candidate with the lowest BIC among the
  eligible ones is added -- eligible: BIC below the current model's,
  likelihood-ratio p < alpha/K (Bonferroni over the K candidates of the step),
  a lower held-out chi2 under 2-fold cross-validation over alternating time
  segments, parameters inside their widened plausible bounds (rule 3), and
  **rule 5**: the chi2 decrease per equation reaches :data:`MIN_EFFECT_RMS`
  squared (the effect's fitted contribution has an RMS of at least 0.2 x the
  noise).  On long records (10^4-10^5 independent samples) BIC resolves
  structure far below the noise -- the small imperfections of any bench and
  any model -- and naming it is not a diagnosis;
* **backward** (:func:`~ppamsafety.diagnose.core.linear_selection.backward_pass_linear`):
  a member that no longer passes the rule given the later ones is dropped
  (a force-sensor gain chosen first, then a refitted law that contains it);
* **every subset** (:func:`~ppamsafety.diagnose.core.linear_selection.subset_search_linear`)
  with no more coefficients than the forward path's model: the best by BIC
  whose members each pass the rule given the others is the final model (the
  greedy path can take a wrong turn: a refitted law taking a force gain and the
  branch-average of a small hysteresis); each candidate's *inclusion
  probability* (BIC weights of the admissible subsets near the best) is its
  confidence.

:func:`select` runs on all the equations or on a subset of them (the halves of
the stability check, :mod:`.stability`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..core.linear_selection import (backward_pass_linear, fit_linear,
                                     forward_selection_linear, subset_search_linear)

#: Rule 5 of the naming rule: an effect is named only if its fitted contribution has an
#: RMS of at least this many noise levels (chi2 falls by >= its square per sample).
MIN_EFFECT_RMS = 0.2


@dataclass(frozen=True, eq=False)
class Selection:
    """Result of :func:`select`.

    Attributes
    ----------
    fit : _LinearFit
        The final model (after the backward pass).
    nominal : _LinearFit
        The nominal model (no candidate).
    steps : list of Step
        The forward ranking at every step.
    pruned : list of dict
        Members dropped by the backward pass (:func:`backward_pass_linear`).
    forward : tuple of str
        The forward path's model after the backward pass.
    subsets : SubsetChoice or None
        The search over every subset (None when nothing was selected).
    """

    fit: object
    nominal: object
    steps: list = field(repr=False)
    pruned: list = field(default_factory=list)
    forward: tuple = ()
    subsets: object = field(default=None, repr=False)

    @property
    def names(self) -> tuple:
        """The selected candidates, in the order found."""
        return tuple(self.fit.names)


#: Candidates that change the law the muscle's force follows (as the record reads it).
LAW_TERMS = ("force_law_refit", "force_sensor_gain")


def fitted_law(design, fit) -> np.ndarray:
    """The muscle's force as fitted: the nominal law with the fitted law and gain terms [N].

    Parameters
    ----------
    design : ActuatorDesign
    fit : _LinearFit
    """
    force = np.array(design.ctx["f_smooth"], dtype=float)
    for n in fit.names:
        if n in LAW_TERMS:
            force += design.extensions[n].columns @ fit.phi[fit.slices[n]]
    return force


def relinearised(design, fit, *, rounds: int = 2) -> tuple:
    """The design and fit with the hysteresis column rebuilt on the fitted law.

    The true term is ``delta F_law (W - W_fit)``: with a refitted law or a gain in the
    model, the column built on the nominal law misses the product (a 5 % law change is a
    5 % error of delta).  Rebuilt on :func:`fitted_law` and refitted, ``rounds`` times.

    Parameters
    ----------
    design : ActuatorDesign
    fit : _LinearFit
    rounds : int, keyword-only

    Returns
    -------
    (ActuatorDesign, _LinearFit)
        Unchanged when the model holds no hysteresis or no law term.
    """
    if "hysteresis" not in fit.names or not set(LAW_TERMS) & set(fit.names):
        return design, fit
    for _ in range(rounds):
        design = design.on_force(fitted_law(design, fit))
        fit = fit_linear(design.e0, design.columns, fit.names)
    return design, fit


def masked(design, mask=None) -> tuple:
    """The whitened residual and columns of ``design`` on the equations of ``mask``.

    Parameters
    ----------
    design : ActuatorDesign
    mask : numpy.ndarray of bool, shape (m,), optional
        Default: every equation.

    Returns
    -------
    (numpy.ndarray, dict)
    """
    if mask is None:
        return design.e0, design.columns
    mask = np.asarray(mask, bool)
    if mask.shape != design.e0.shape:
        raise ValueError(f"mask must have shape {design.e0.shape}, got {mask.shape}")
    return design.e0[mask], {n: c[mask] for n, c in design.columns.items()}


def admissible_in(design):
    """``admissible(fit, name)``: rule 3 for candidate ``name`` inside a fitted model.

    Parameters
    ----------
    design : ActuatorDesign
        The record's design (its extensions' physical ranges decide).

    Returns
    -------
    callable
    """
    def admissible(fit, name):
        sl = fit.slices[name]
        return design.extensions[name].admissible(fit.phi[sl], fit.cov[sl, sl])
    return admissible


def select(design, *, alpha: float, mask=None) -> Selection:
    """Forward selection then the backward pass (module docstring).

    Parameters
    ----------
    design : ActuatorDesign
    alpha : float, keyword-only
        Level of the likelihood-ratio test before the Bonferroni division.
    mask : numpy.ndarray of bool, shape (m,), optional, keyword-only
        Equations to use (default all).

    Returns
    -------
    Selection
    """
    e0, cols = masked(design, mask)
    nominal = fit_linear(e0, cols, [])
    fit, steps = forward_selection_linear(e0, cols, admissible_in(design), alpha=alpha,
                                          max_effects=len(cols),
                                          min_gain_per_equation=MIN_EFFECT_RMS ** 2)
    pruned = []
    if len(fit.names) > 1:
        fit, pruned = backward_pass_linear(e0, cols, fit.names, alpha=alpha,
                                           n_candidates=len(cols),
                                           min_gain_per_equation=MIN_EFFECT_RMS ** 2)
    forward = tuple(fit.names)
    sub = None
    if fit.names:
        sub = subset_search_linear(e0, cols, admissible_in(design), alpha=alpha, max_k=fit.k,
                                   min_gain_per_equation=MIN_EFFECT_RMS ** 2)
        if set(sub.names) != set(fit.names):
            keep = [n for n in fit.names if n in sub.names]
            fit = fit_linear(e0, cols, keep + [n for n in sub.names if n not in keep])
    return Selection(fit=fit, nominal=nominal, steps=steps, pruned=pruned, forward=forward,
                     subsets=sub)


__all__ = ["Selection", "select", "masked", "admissible_in", "fitted_law", "relinearised",
           "LAW_TERMS", "MIN_EFFECT_RMS"]
