"""The naming rule of :mod:`ppamsafety.diagnose.selection` for any residual linear in its parameters.

The arm workflow ranks candidates on a block system (``y = X mu``) with its
own model vector; a test-bench record (one actuator) has one residual
channel and candidates that each add *columns* to it.  This module applies
the same statistics to that simpler structure, so both workflows name an
effect under identical rules (constants :data:`~.selection.ALPHA`,
:data:`~.selection.RHO_MAX`, :data:`~.selection.CV_SEGMENTS`; rows of
:class:`~.selection.Step` with the same keys, so
:meth:`~ppamsafety.diagnose.diagnosis.Diagnosis.ranking` and
``diagnosis.json`` read them unchanged):

* data: whitened residuals ``e0 = r / sigma`` (m equations, approximately
  independent N(0, 1) under a correct model) and, per candidate, whitened
  columns ``Z_c`` (m, k_c): the extension is ``e = e0 - [Z_c ...] phi``;
* fit: linear least squares (columns scaled to unit norm), covariance
  ``s^2 (A^T A)^-1`` with ``s^2 = chi2/(m - k)``;
* BIC = chi2 + k ln m; naming rule: BIC below the current model's,
  likelihood-ratio p < alpha/K (Bonferroni over the K candidates of the
  step), parameters determined and physically possible (a callable per
  candidate, see :func:`forward_selection_linear`), and a lower held-out
  chi2 under 2-fold cross-validation over alternating time segments;
* confidence: BIC weight among the current model and the admissible
  candidates; evidence ratio against the runner-up;
* optional rule 5 (``min_gain_per_equation``): the effect is not
  negligible.  On a long record (tens of thousands of independent samples)
  BIC resolves systematic structure far below the noise -- the small
  imperfections any real bench and any model have -- and naming it is not
  a diagnosis; the arm workflow does not use this rule.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .criteria import ALPHA, CV_SEGMENTS, Step, aicc, bic, _chi2_sf, rank_step


@dataclass(frozen=True, eq=False)
class LinearFit:
    """A fitted linear model (nominal + the columns of ``names``).

    Attributes
    ----------
    names : tuple of str
        Candidates in the model, in order.
    k : int
        Fitted parameters.
    m : int
        Equations used.
    chi2 : float
        Sum of squared whitened residuals over the equations used.
    phi : numpy.ndarray
        Coefficients, candidate blocks in the order of ``names``.
    cov : numpy.ndarray
        Covariance of phi (scaled by the residual variance).
    slices : dict
        Candidate name -> slice of phi.
    e : numpy.ndarray, shape (m_all,)
        Whitened residual of every equation under this fit.
    """

    names: tuple
    k: int
    m: int
    chi2: float
    phi: np.ndarray
    cov: np.ndarray
    slices: dict
    e: np.ndarray

    @property
    def bic(self) -> float:
        """chi2 + k ln m (:func:`~ppamsafety.diagnose.selection.bic`)."""
        return bic(self.chi2, self.k, self.m)

    @property
    def aicc(self) -> float:
        """Small-sample AIC (:func:`~ppamsafety.diagnose.selection.aicc`)."""
        return aicc(self.chi2, self.k, self.m)

    def rho(self) -> float:
        """Residual-to-noise RMS ratio (all equations)."""
        return float(np.sqrt(np.mean(self.e ** 2)))


def fold_of(m: int, segments: int = CV_SEGMENTS) -> np.ndarray:
    """Cross-validation fold (0/1) of m equations in time order: alternating segments.

    Parameters
    ----------
    m : int
        Number of equations.
    segments : int
        Number of equal time segments alternated between the folds.
    """
    seg = np.minimum((np.arange(m) * segments) // max(m, 1), segments - 1)
    return seg % 2


def fit_linear(e0, columns: dict, names, mask=None) -> LinearFit:
    """Least-squares fit of the nominal residual ``e0`` by the columns of ``names``.

    Parameters
    ----------
    e0 : numpy.ndarray, shape (m,)
        Whitened nominal residual.
    columns : dict
        Candidate name -> whitened columns (m, k_c).
    names : sequence of str
        Candidates of the model (may be empty).
    mask : numpy.ndarray of bool, shape (m,), optional
        Equations to fit on (default all); ``e`` is returned for all.

    Returns
    -------
    LinearFit
    """
    names = tuple(names)
    m_all = e0.size
    mask = np.ones(m_all, bool) if mask is None else np.asarray(mask, bool)
    blocks, slices, j = [], {}, 0
    for n in names:
        Z = columns[n]
        blocks.append(Z)
        slices[n] = slice(j, j + Z.shape[1])
        j += Z.shape[1]
    Z = np.concatenate(blocks, axis=1) if blocks else np.zeros((m_all, 0))
    b = e0[mask]
    A = Z[mask]
    k = Z.shape[1]
    if k:
        scale = np.sqrt(np.sum(A ** 2, axis=0))
        scale[scale == 0] = 1.0
        sol, *_ = np.linalg.lstsq(A / scale, b, rcond=None)
        phi = sol / scale
    else:
        phi = np.zeros(0)
    r = b - A @ phi
    chi2 = float(r @ r)
    m = b.size
    if k:
        s2 = chi2 / max(m - k, 1)
        An = A / scale
        cov = s2 * np.linalg.pinv(An.T @ An) / np.outer(scale, scale)
    else:
        cov = np.zeros((0, 0))
    return LinearFit(names=names, k=k, m=m, chi2=chi2, phi=phi, cov=cov, slices=slices,
                     e=e0 - Z @ phi)


def cv_chi2_linear(e0, columns: dict, names, fold) -> float:
    """Held-out chi2 of 2-fold cross-validation (fit on one fold, chi2 on the other, and back).

    Parameters
    ----------
    e0 : numpy.ndarray, shape (m,)
        Whitened nominal residual.
    columns : dict
        Candidate name -> whitened columns (m, k_c).
    names : sequence of str
        Candidates of the model.
    fold : numpy.ndarray of int, shape (m,)
        Fold 0/1 of every equation (:func:`fold_of`).
    """
    total = 0.0
    for f in (0, 1):
        fit = fit_linear(e0, columns, names, mask=fold != f)
        total += float(np.sum(fit.e[fold == f] ** 2))
    return total


def forward_selection_linear(e0, columns: dict, admissible, *, alpha: float = ALPHA,
                             max_effects: int = 3, fold=None,
                             min_gain_per_equation: float = 0.0) -> tuple:
    """Forward selection with refit under the naming rule of :mod:`.selection`.

    Parameters
    ----------
    e0 : numpy.ndarray, shape (m,)
        Whitened nominal residual.
    columns : dict
        Candidate name -> whitened columns (m, k_c), in the order tried.
    admissible : callable
        ``admissible(fit, name) -> bool``: the fitted parameters of ``name``
        in ``fit`` are determined and physically possible (rule 3).
    alpha : float, keyword-only
        Level of the likelihood-ratio test before the Bonferroni division.
    max_effects : int, keyword-only
        Largest number of effects named.
    fold : numpy.ndarray of int, optional, keyword-only
        Cross-validation folds (default :func:`fold_of`).
    min_gain_per_equation : float, keyword-only
        Rule 5 (0 = off, as the arm): the chi2 decrease per equation must
        reach this (an effect whose fitted contribution has an RMS of g x the
        noise level decreases chi2 by about g^2 per equation).

    Returns
    -------
    LinearFit
        The final model.
    list of Step
        The ranking at every step.
    """
    e0 = np.asarray(e0, float)
    fold = fold_of(e0.size) if fold is None else np.asarray(fold)
    names = list(columns)
    selected: list = []
    current = fit_linear(e0, columns, selected)
    cur_cv = cv_chi2_linear(e0, columns, selected, fold)
    steps = []
    while len(selected) < max_effects:
        rest = [n for n in names if n not in selected]
        if not rest:
            break
        rows, fits = [], {}
        for n in rest:
            f = fit_linear(e0, columns, selected + [n])
            fits[n] = f
            d = current.chi2 - f.chi2
            df = max(f.k - current.k, 1)
            cv = cv_chi2_linear(e0, columns, selected + [n], fold)
            rows.append({"name": n, "k": f.k - current.k, "chi2": f.chi2, "bic": f.bic,
                         "aicc": f.aicc, "delta_bic": f.bic - current.bic, "lr_stat": d,
                         "lr_df": df, "p_value": _chi2_sf(max(d, 0.0), df),
                         "cv_chi2": cv, "cv_gain": cur_cv - cv,
                         "gain_per_equation": d / max(f.m, 1)})
        for r in rows:
            r["in_bounds"] = bool(admissible(fits[r["name"]], r["name"]))
        chosen, w0 = rank_step(rows, current.bic, alpha=alpha, n_candidates=len(rest),
                               extra_rule=lambda r: r["gain_per_equation"]
                               >= min_gain_per_equation)
        steps.append(Step(tuple(selected), rows, chosen, current.bic, cur_cv, w0))
        if chosen is None:
            break
        selected.append(chosen)
        current = fits[chosen]
        cur_cv = cv_chi2_linear(e0, columns, selected, fold)
    return current, steps


__all__ = ["LinearFit", "fit_linear", "cv_chi2_linear", "forward_selection_linear", "fold_of"]
