"""The naming rule of :mod:`~ppamsafety.diagnose.arm.selection` for any residual linear in
its parameters.

The arm workflow ranks candidates on a block system (``y = X mu``) with its
own model vector; a test-bench record (one actuator) has one residual
channel and candidates that each add *columns* to it.  This module applies
the same statistics to that simpler structure, so both workflows name an
effect under identical rules (constants :data:`~ppamsafety.diagnose.core.criteria.ALPHA`,
:data:`~ppamsafety.diagnose.core.criteria.RHO_MAX`,
:data:`~ppamsafety.diagnose.core.criteria.CV_SEGMENTS`; rows of
:class:`~ppamsafety.diagnose.core.criteria.Step` with the same keys, so
:meth:`~ppamsafety.diagnose.diagnosis.Diagnosis.ranking` and
``diagnosis.json`` read them unchanged):

* data: whitened residuals ``e0 = r / sigma`` (m equations, approximately
  independent N(0, 1) under a correct model) and, per candidate, whitened
  columns ``Z_c`` (m, k_c): the extension is ``e = e0 - [Z_c ...] phi``;
* fit: linear least squares from the Gram matrices of the columns
  (:class:`LinearGram`, columns scaled to unit norm, a pseudo-inverse for
  nested candidates), covariance ``s^2 (A^T A)^-1`` with ``s^2 = chi2/(m - k)``;
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

import itertools
import math
from dataclasses import dataclass

import numpy as np

from .criteria import ALPHA, CV_SEGMENTS, Step, aicc, bic, _chi2_sf, rank_step
from .gram import Gram
from .solve import pinv_psd, solve_normal


@dataclass(frozen=True, eq=False)
class _LinearFit:
    """A fitted linear model (nominal + the columns of ``names``).

    An engine intermediate (the selection makes thousands per diagnosis), never handed to a
    user: what a user receives is the :class:`~ppamsafety.diagnose.core.result.Diagnosis`.
    So it is private and not a result object (no table, no figure of its own).

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
        """chi2 + k ln m (:func:`~ppamsafety.diagnose.core.criteria.bic`)."""
        return bic(self.chi2, self.k, self.m)

    @property
    def aicc(self) -> float:
        """Small-sample AIC (:func:`~ppamsafety.diagnose.core.criteria.aicc`)."""
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


class LinearGram:
    """Per-fold Gram matrices of the whitened columns and residual: each fit is a k x k solve
    (the engine's :class:`~.gram.Gram`, one group per fold).

    ``[Z e0]^T [Z e0]`` summed over the equations of each cross-validation fold (and of
    ``mask``).  A fit of any subset of the candidates, its covariance and its held-out chi2
    follow from these small matrices, so a forward selection over K candidates costs two
    products of the data instead of one least-squares problem per candidate, step and fold.
    The solve is the diagnosis's one rank rule (:mod:`ppamsafety.diagnose.core.solve`): the
    minimum-norm solution when candidates are nested (a force gain inside a refitted force
    law).

    Parameters
    ----------
    e0 : numpy.ndarray, shape (m,)
        Whitened nominal residual.
    columns : dict
        Candidate name -> whitened columns (m, k_c).
    fold : numpy.ndarray of int, shape (m,), optional
        Cross-validation fold 0/1 of every equation (default :func:`fold_of` of the
        equations used).
    mask : numpy.ndarray of bool, shape (m,), optional
        Equations to fit on (default all); residuals are returned for all.
    """

    def __init__(self, e0, columns: dict, fold=None, mask=None):
        self.e0 = np.asarray(e0, float)
        m_all = self.e0.size
        self.mask = np.ones(m_all, bool) if mask is None else np.asarray(mask, bool)
        self.slices, j, blocks = {}, 0, []
        for n, Z in columns.items():
            blocks.append(Z)
            self.slices[n] = slice(j, j + Z.shape[1])
            j += Z.shape[1]
        self.Z = np.concatenate(blocks, axis=1) if blocks else np.zeros((m_all, 0))
        used = np.flatnonzero(self.mask)
        self.m = int(used.size)
        if fold is None:
            fold_used = fold_of(self.m)
        else:
            fold_used = np.asarray(fold)[used] if np.asarray(fold).size == m_all else \
                np.asarray(fold)
        gram = Gram.from_samples(self.Z[used], self.e0[used], np.ones(self.m), fold_used,
                                 groups=2)
        self.G = [gram.G[0, 0], gram.G[1, 0]]
        self.G_all = self.G[0] + self.G[1]

    def _index(self, names):
        if not names:
            return np.zeros(0, dtype=int)
        return np.concatenate([np.arange(self.slices[n].start, self.slices[n].stop)
                               for n in names])

    @staticmethod
    def _solve(G, idx):
        """Coefficients, chi2 and unscaled covariance of the columns ``idx`` on Gram ``G``."""
        yy = float(G[-1, -1])
        if idx.size == 0:
            return np.zeros(0), max(yy, 0.0), np.zeros((0, 0))
        A = G[np.ix_(idx, idx)]
        b = G[idx, -1]
        phi = solve_normal(A, b)
        chi2 = max(yy - 2.0 * float(phi @ b) + float(phi @ A @ phi), 0.0)
        return phi, chi2, pinv_psd(A)

    @staticmethod
    def _chi2(G, idx, phi):
        if idx.size == 0:
            return max(float(G[-1, -1]), 0.0)
        A = G[np.ix_(idx, idx)]
        b = G[idx, -1]
        return max(float(G[-1, -1]) - 2.0 * float(phi @ b) + float(phi @ A @ phi), 0.0)

    def fit(self, names) -> _LinearFit:
        """Least-squares fit of the residual by the columns of ``names`` (on ``mask``).

        Parameters
        ----------
        names : sequence of str

        Returns
        -------
        _LinearFit
        """
        names = tuple(names)
        idx = self._index(names)
        phi, chi2, cu = self._solve(self.G_all, idx)
        k = idx.size
        cov = chi2 / max(self.m - k, 1) * cu
        slices, j = {}, 0
        for n in names:
            w = self.slices[n].stop - self.slices[n].start
            slices[n] = slice(j, j + w)
            j += w
        e = self.e0 - self.Z[:, idx] @ phi if k else self.e0.copy()
        return _LinearFit(names=names, k=int(k), m=self.m, chi2=chi2, phi=phi, cov=cov,
                         slices=slices, e=e)

    def cv_chi2(self, names) -> float:
        """Held-out chi2 of 2-fold cross-validation (fit on one fold, chi2 on the other, and back).

        Parameters
        ----------
        names : sequence of str
        """
        idx = self._index(tuple(names))
        total = 0.0
        for f in (0, 1):
            phi, _, _ = self._solve(self.G[1 - f], idx)
            total += self._chi2(self.G[f], idx, phi)
        return total


def fit_linear(e0, columns: dict, names, mask=None) -> _LinearFit:
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
    _LinearFit
    """
    names = tuple(names)
    return LinearGram(e0, {n: columns[n] for n in names}, mask=mask).fit(names)


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
    names = tuple(names)
    return LinearGram(e0, {n: columns[n] for n in names}, fold=fold).cv_chi2(names)


def forward_selection_linear(e0, columns: dict, admissible, *, alpha: float = ALPHA,
                             max_effects: int = 3, fold=None,
                             min_gain_per_equation: float = 0.0) -> tuple:
    """Forward selection with refit under the naming rule of
    :mod:`~ppamsafety.diagnose.core.criteria`.

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
    _LinearFit
        The final model.
    list of Step
        The ranking at every step.
    """
    e0 = np.asarray(e0, float)
    fold = fold_of(e0.size) if fold is None else np.asarray(fold)
    gram = LinearGram(e0, columns, fold=fold)
    names = list(columns)
    selected: list = []
    current = gram.fit(selected)
    cur_cv = gram.cv_chi2(selected)
    steps = []
    while len(selected) < max_effects:
        rest = [n for n in names if n not in selected]
        if not rest:
            break
        rows, fits = [], {}
        for n in rest:
            f = gram.fit(selected + [n])
            fits[n] = f
            d = current.chi2 - f.chi2
            df = max(f.k - current.k, 1)
            cv = gram.cv_chi2(selected + [n])
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
        cur_cv = gram.cv_chi2(selected)
    return current, steps


#: Subsets within this BIC of the best carry its inclusion probabilities and are checked for
#: admissibility (the weights of the others are below exp(-15) relative to the best), every
#: record kind.
CHECK_BIC = 30.0


@dataclass(frozen=True)
class SubsetChoice:
    """Result of :func:`subset_search_linear`.

    Attributes
    ----------
    names : tuple of str
        The best subset whose members each pass the naming rule given the others.
    inclusion : dict
        Candidate -> inclusion probability (the BIC weights of the admissible subsets
        near the best that hold it).
    evidence : dict
        Member -> {lr_stat, lr_df, p_value, delta_bic, cv_gain, gain_per_equation}: the
        member against the best subset without it.
    evaluated : int
        Subsets fitted.
    ranking : list of dict
        The 20 best subsets by BIC (``subset``, ``k``, ``chi2``, ``bic``, ``admissible``).
    """

    names: tuple
    inclusion: dict
    evidence: dict
    evaluated: int
    ranking: list


def subset_search_linear(e0, columns: dict, admissible, *, alpha: float = ALPHA,
                         max_k: int, min_gain_per_equation: float = 0.0,
                         fold=None) -> SubsetChoice:
    """Every subset of the candidates with at most ``max_k`` coefficients, ranked by BIC.

    Forward selection is greedy: a first step that takes a candidate explaining parts of
    two effects (a refitted law taking a force gain and the branch-average of a small
    hysteresis) can block the right pair.  Here every subset is fitted (from the Gram
    matrices: a k x k solve each), and the best one by BIC whose members each pass the
    naming rule given the others -- LR p < alpha/K, a lower BIC, a positive held-out gain,
    rule 5 and admissible parameters -- is chosen; no subset has more coefficients than
    the forward path's model (the search guards against wrong turns, it is no licence for
    bigger models; the arm's :mod:`ppamsafety.diagnose.arm.subsets`).  A candidate's
    inclusion probability is the sum of the BIC weights ``exp(-BIC/2)`` of the admissible
    subsets within :data:`CHECK_BIC` of the chosen one that hold it.

    Parameters
    ----------
    e0 : numpy.ndarray, shape (m,)
        Whitened nominal residual.
    columns : dict
        Candidate name -> whitened columns (m, k_c).
    admissible : callable
        ``admissible(fit, name) -> bool`` (rule 3).
    alpha : float, keyword-only
        Level of the LR test before the Bonferroni division (over every candidate).
    max_k : int, keyword-only
        Largest number of coefficients of a subset.
    min_gain_per_equation : float, keyword-only
        Rule 5.
    fold : numpy.ndarray of int, optional, keyword-only
        Cross-validation folds (default :func:`fold_of`).

    Returns
    -------
    SubsetChoice
    """
    e0 = np.asarray(e0, float)
    gram = LinearGram(e0, columns, fold=fold_of(e0.size) if fold is None else fold)
    names = list(columns)
    K = max(len(names), 1)
    width = {n: columns[n].shape[1] for n in names}
    subsets = [()]
    for r in range(1, len(names) + 1):
        for c in itertools.combinations(names, r):
            if sum(width[n] for n in c) <= max_k:
                subsets.append(c)
    fits = {c: gram.fit(c) for c in subsets}
    order = sorted(subsets, key=lambda c: fits[c].bic)
    cv = {}

    def cv_of(c):
        if c not in cv:
            cv[c] = gram.cv_chi2(c)
        return cv[c]

    ok_memo = {}

    def member_evidence(c, n):
        rest = tuple(x for x in c if x != n)
        full, fr = fits[c], fits.get(rest) or gram.fit(rest)
        d = max(fr.chi2 - full.chi2, 0.0)
        df = max(full.k - fr.k, 1)
        return {"lr_stat": d, "lr_df": df, "p_value": _chi2_sf(d, df),
                "delta_bic": full.bic - fr.bic, "cv_gain": cv_of(rest) - cv_of(c),
                "gain_per_equation": d / max(full.m, 1)}

    def ok(c):
        if c not in ok_memo:
            good = True
            for n in c:
                ev = member_evidence(c, n)
                if not (ev["p_value"] < alpha / K and ev["delta_bic"] < 0 and ev["cv_gain"] > 0
                        and ev["gain_per_equation"] >= min_gain_per_equation
                        and admissible(fits[c], n)):
                    good = False
                    break
            ok_memo[c] = good
        return ok_memo[c]

    best = next((c for c in order if ok(c)), ())
    b0 = fits[best].bic
    near = [c for c in order if fits[c].bic - b0 <= CHECK_BIC and ok(c)]
    if best not in near:
        near.insert(0, best)
    w = np.exp(-(np.array([fits[c].bic for c in near]) - b0) / 2.0)
    w /= w.sum()
    inclusion = {n: float(sum(wi for c, wi in zip(near, w) if n in c)) for n in names}
    evidence = {n: member_evidence(best, n) for n in best}
    ranking = [{"subset": "+".join(c) or "nominal", "k": int(fits[c].k), "chi2": fits[c].chi2,
                "bic": fits[c].bic, "admissible": ok_memo.get(c)} for c in order[:20]]
    return SubsetChoice(names=tuple(best), inclusion=inclusion, evidence=evidence,
                        evaluated=len(subsets), ranking=ranking)


def hac_covariance_linear(Z, e, *, lags: int | None = None) -> np.ndarray:
    """Heteroskedasticity- and autocorrelation-consistent covariance of a linear fit.

    The sandwich ``B^+ M B^+`` with ``B = Z^T Z`` (whitened columns) and the Newey-West
    meat ``M = sum_|l|<=L w_l sum_i s_i s_(i-l)^T``, Bartlett weights ``w_l = 1 - |l|/(L+1)``,
    scores ``s_i = Z_i e_i``, times m/(m - k): the arm's
    :func:`ppamsafety.diagnose.arm.selection.hac_covariance` on equations in time order.
    A residual correlated over neighbouring equations (a model that is slightly off, coloured
    noise) widens the intervals; white residuals at the noise level give the ordinary
    covariance.

    Parameters
    ----------
    Z : numpy.ndarray, shape (m, k)
        Whitened columns of the fitted model, equations in time order.
    e : numpy.ndarray, shape (m,)
        Whitened residual of the fit.
    lags : int, optional, keyword-only
        L; default ceil(m^(1/3)).

    Returns
    -------
    numpy.ndarray, shape (k, k)
    """
    Z = np.asarray(Z, float)
    e = np.asarray(e, float)
    m, k = Z.shape
    if k == 0:
        return np.zeros((0, 0))
    S = Z * e[:, None]
    L = int(math.ceil(m ** (1.0 / 3.0))) if lags is None else int(lags)
    M = S.T @ S
    for lag in range(1, min(L, m - 1) + 1):
        G = S[lag:].T @ S[:-lag]
        M += (1.0 - lag / (L + 1.0)) * (G + G.T)
    Bi = pinv_psd(Z.T @ Z)
    return Bi @ M @ Bi * m / max(m - k, 1)


def backward_pass_linear(e0, columns: dict, names, *, alpha: float = ALPHA,
                         n_candidates: int | None = None,
                         min_gain_per_equation: float = 0.0) -> tuple:
    """Drop, one at a time, the members of a model that no longer pass the naming rule given
    the others.

    Forward selection adds an effect given the effects before it; a later effect may explain
    its part as well (a force gain chosen first, then a refitted law that contains it).  A
    member is kept when, against the model without it, its likelihood-ratio test gives
    p < alpha / n_candidates, it lowers the BIC and (rule 5) it lowers chi2 by at least
    ``min_gain_per_equation`` per equation.  The weakest failing member (largest p-value) is
    dropped and the rest refitted, until every member passes.

    Parameters
    ----------
    e0 : numpy.ndarray, shape (m,)
        Whitened nominal residual.
    columns : dict
        Candidate name -> whitened columns (m, k_c).
    names : sequence of str
        The model.
    alpha : float, keyword-only
        Level of the LR test before the Bonferroni division.
    n_candidates : int, optional, keyword-only
        Bonferroni divisor (default the number of candidates in ``columns``).
    min_gain_per_equation : float, keyword-only
        Rule 5 (0 = off).

    Returns
    -------
    _LinearFit
        The model after the pass.
    list of dict
        The members dropped, in order: ``name``, ``lr_stat``, ``lr_df``, ``p_value``,
        ``delta_bic`` (with it minus without it), ``gain_per_equation``.
    """
    K = len(columns) if n_candidates is None else int(n_candidates)
    gram = LinearGram(e0, columns)
    names = list(names)
    dropped = []
    while names:
        full = gram.fit(names)
        worst = None
        for n in names:
            fr = gram.fit([x for x in names if x != n])
            d = max(fr.chi2 - full.chi2, 0.0)
            df = max(full.k - fr.k, 1)
            row = {"name": n, "lr_stat": d, "lr_df": df, "p_value": _chi2_sf(d, df),
                   "delta_bic": full.bic - fr.bic, "gain_per_equation": d / max(full.m, 1)}
            keep = (row["p_value"] < alpha / max(K, 1) and row["delta_bic"] < 0
                    and row["gain_per_equation"] >= min_gain_per_equation)
            if not keep and (worst is None or row["p_value"] > worst["p_value"]):
                worst = row
        if worst is None:
            return full, dropped
        dropped.append(worst)
        names.remove(worst["name"])
    return gram.fit([]), dropped


__all__ = ["LinearGram", "fit_linear", "cv_chi2_linear", "forward_selection_linear",
           "backward_pass_linear", "hac_covariance_linear", "subset_search_linear",
           "SubsetChoice", "CHECK_BIC", "fold_of"]
