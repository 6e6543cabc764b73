"""Ranking, evidence and forward selection with refit.

Statistics (the choices a reviewer will ask about)
--------------------------------------------------
*Data.*  The block residuals of :mod:`ppamsafety.diagnose.arm.residuals`
(channels p1..p4, tau1, tau2), each divided by its **noise level** sigma_c:
the standard deviation the measurement noise alone gives that channel
(:func:`~ppamsafety.diagnose.arm.residuals.block_noise`, from the noise
estimated in the data).  Blocks do not share samples, so under a correct
model the whitened residuals e are approximately independent N(0, 1) and
-2 log L = chi2 = sum e^2 (+ const) with the noise level *known*.

*Fit.*  A model = the nominal model plus a set of candidate extensions;
its coefficients phi are found by linear least squares on e (the
extensions are linear in phi), a dead time by profiling chi2 over a grid
of one-sample steps.  Covariance of phi: s^2 (A^T A)^-1 with
s^2 = chi2/(m - k) of the subsystem the parameter acts in, the Jacobian of the least-squares fit scaled by the
residual variance; parameter intervals by the delta method (dead time:
the profile-likelihood interval chi2 - chi2_min <= s^2 chi2_1(95 %)).

*Criterion.*  BIC = chi2 + k ln m (k fitted parameters including a dead
time, m equations).  BIC rather than AICc because it is consistent (the
chance of adding a spurious effect vanishes as the record grows) and
conservative -- naming an effect that is not there is the error to avoid;
AICc is reported too.  **Confidence** of a choice: its BIC weight
exp(-BIC/2) / sum over {current model, every candidate}, the approximate
posterior probability with equal priors; the **evidence ratio** against
the runner-up is exp((BIC_2 - BIC_1)/2).

*Naming rule* (all must hold for the best candidate by BIC):

1. BIC below the current model's;
2. significant: likelihood-ratio test against the noise level, Delta chi2
   ~ chi2(Delta k), p < alpha / K (alpha = 0.01, Bonferroni over the K
   candidates tried at the step);
3. its fitted parameters are determined and physically possible: every
   parameter's confidence interval lies inside the candidate's bounds
   widened by half their width on each side (an exponent n = 3, or one
   known only to +-4, or a
   negative mass is a sign that the candidate is absorbing another effect
   it is nearly collinear with, e.g. a valve lag and the polytropic volume
   term on a slow excitation);
4. it predicts held-out data: 2-fold cross-validation over alternating
   time segments (fit on half of the segments, chi2 on the other half, and
   the reverse) lowers the held-out chi2.

Admissibility (rule 3) also needs the fitted *value* inside the physical
range of every parameter (``Parameter.phys_lo``/``phys_hi``: a mass >= 0, a
friction >= 0, 1 <= n <= 1.4): a fit outside it is a symptom of something
else, not an effect.

*Confounded* (:func:`confounded_with`): when another candidate that passes
the rule alone explains the same part of the residual -- neither adds
significantly (LR test at alpha/K) to a model holding the other -- the record
cannot tell them apart.  The chosen one enters the model (the fit moves on)
but the step reports the group, and the pipeline names none of them.

Forward selection repeats this with every earlier effect refitted together
with each new candidate, until no candidate passes.  The fits run on
per-chunk Gram matrices (:mod:`.gram`): every candidate is linear in its
coefficients at a fixed dead time, so a fit is a k x k solve; the dead-time
candidate is profiled on the full design (:func:`fit_model`), and once
chosen its shift fixes the design of the later steps.  Finally the residual
ratio rho_c = RMS(e_c) of every channel is compared with ``rho_max`` (1.5:
under a correct model rho is 1 within a few per cent for a few hundred
blocks, so 1.5 leaves room for a noise estimate that is somewhat off but
not for a model error as large as the noise).  An effect is **named** only
if every channel of its subsystem then has rho <= rho_max; a significant
effect that leaves its subsystem far above the noise is reported as
*partial* (fitted, not named) and the diagnosis as unexplained.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import stats

from ..._validation import check_int, check_seed
from ..core.criteria import (ALPHA, CV_SEGMENTS, RHO_MAX, Step, _chi2_sf, _normal_quantile, aicc,
                             bic, false_selection_bound, rank_step)
from ..core.gates import CONSTANCY_ALPHA
from ..core.omitted import widened_interval
from ..core.result import Estimate
from ...lstsq import step_scores
from .candidates import DEAD_TIME_MAX, REGISTRY, identity_values, library
from ..core.solve import lstsq, pinv_psd
from ..core.gram import Gram, chi2_at, solve
from .gram import chunk_layout
from .residuals import SUBSYSTEM, BlockSystem, block_noise

#: 95 % quantile of chi2 with one degree of freedom (the dead-time profile interval).
_CHI2_95_1 = float(stats.chi2.ppf(0.95, 1))
#: The two disjoint subsystems (a parameter's variance is scaled by its own subsystem's).
_SUBSYSTEMS = (SUBSYSTEM["pressure"], SUBSYSTEM["torque"])


@dataclass(frozen=True, eq=False)
class Problem:
    """A block system with its noise levels, nominal model and fold assignment.

    Attributes
    ----------
    bs : BlockSystem
    mu0 : numpy.ndarray
        Nominal model vector.
    sigma : numpy.ndarray, shape (6,)
        Noise level of each block channel (at the model it was evaluated at).
    arm : ArmParameters
    fold : numpy.ndarray of int
        Cross-validation fold (0/1) of every block (that of its chunk).
    max_shift : int
        Largest increase of the dead time searched [samples].
    noise : tuple
        Noise draws (dY, dX) of :func:`~ppamsafety.diagnose.arm.residuals.noise_draws`.
    floor : numpy.ndarray or None
        Lower bound of the noise level per channel (rest-point records:
        :data:`ppamsafety.diagnose.arm.static.RESOLUTION`), None for none.
    shift_grid : tuple of int or None
        Changes of the dead time from the model's profiled [samples] (None:
        ``bs.shift_grid(max_shift)``, every one from no delay to ``max_shift`` more;
        the resampling schemes fix the full record's best shift).
    chunk : numpy.ndarray of int
        Chunk (run of consecutive blocks, :func:`~.gram.chunk_layout`) of every block.
    chunk_fold : numpy.ndarray of int
        Cross-validation fold of every chunk.
    mu_ref : numpy.ndarray or None
        Model vector at which the model-dependent columns of the sensor faults are
        evaluated (:class:`~.residuals.Columns`; None: ``mu0``).  The selection moves it
        to the current model after every step (:func:`at_model`).
    _xcache : dict
        Designs per dead-time shift (internal cache, shared with :func:`at_model`'s copies).
    _memo : dict
        Candidate directions, Gram sets and whitened nominal residuals of this problem
        (internal cache).
    """

    bs: BlockSystem
    mu0: np.ndarray
    sigma: np.ndarray
    arm: object
    fold: np.ndarray
    max_shift: int
    noise: tuple = ()
    floor: np.ndarray | None = None
    shift_grid: tuple | None = None
    chunk: np.ndarray | None = None
    chunk_fold: np.ndarray | None = None
    mu_ref: np.ndarray | None = None
    _xcache: dict = field(default_factory=dict, repr=False)
    _memo: dict = field(default_factory=dict, repr=False)

    def X(self, shift: int) -> np.ndarray:
        """The design for a dead time of ``shift`` samples (cached).

        Parameters
        ----------
        shift : int
        """
        if shift not in self._xcache:
            self._xcache[shift] = self.bs.with_dead_time(shift)
        return self._xcache[shift]

    @property
    def nchunk(self) -> int:
        """Number of chunks."""
        return int(self.chunk_fold.size)

    @property
    def mu_columns(self) -> np.ndarray:
        """The model vector the model-dependent columns are evaluated at."""
        return self.mu0 if self.mu_ref is None else self.mu_ref


def _floored(sig, floor):
    return sig if floor is None else np.maximum(sig, floor)


def make_problem(bs: BlockSystem, mu0, noise, arm, *, floor=None) -> Problem:
    """Bundle a block system for selection (chunks and folds: :func:`~.gram.chunk_layout`).

    Parameters
    ----------
    bs : BlockSystem
    mu0 : numpy.ndarray, shape (NMU,)
        Nominal model vector.
    noise : tuple (dY, dX)
        Noise draws of :func:`~ppamsafety.diagnose.arm.residuals.noise_draws`; the
        noise level of each channel is evaluated at the current model.
    arm : ArmParameters
    floor : array_like, shape (6,), optional, keyword-only
        Lower bound of the noise level per channel (see :class:`Problem`).
    """
    chunk, cfold = chunk_layout(bs.nb)
    max_shift = max(1, int(round(DEAD_TIME_MAX / bs.dt)))
    mu0 = np.asarray(mu0, float)
    floor = None if floor is None else np.asarray(floor, dtype=float)
    return Problem(bs=bs, mu0=mu0, sigma=_floored(block_noise(*noise, mu0), floor), arm=arm,
                   fold=cfold[chunk], max_shift=max_shift, noise=tuple(noise), floor=floor,
                   chunk=chunk, chunk_fold=cfold)


def at_model(prob: Problem, mu) -> Problem:
    """``prob`` at a model vector: noise levels re-evaluated there, model-dependent columns
    moved there (same design caches).

    Parameters
    ----------
    prob : Problem
    mu : numpy.ndarray, shape (NMU,)
    """
    mu = np.asarray(mu, dtype=float)
    moves = any(c.X is not None for c in prob.bs.extra.values()) and not np.array_equal(
        mu, prob.mu_columns)
    keep = () if moves else ("directions", "gram")
    memo = {k: v for k, v in prob._memo.items() if k[0] in keep}
    return replace(prob, sigma=_floored(block_noise(*prob.noise, mu), prob.floor),
                   mu_ref=mu if moves else prob.mu_ref, _xcache=prob._xcache, _memo=memo)


@dataclass(frozen=True, eq=False)
class _Fit:
    """A fitted model (nominal + extensions ``names``).

    An engine intermediate (the selection makes thousands per diagnosis), never handed to a
    user: what a user receives is the :class:`~ppamsafety.diagnose.core.result.Diagnosis`.
    So it is private and not a result object (no table, no figure of its own).

    Attributes
    ----------
    names : tuple of str
    k : int
        Fitted parameters (linear coefficients + a dead time).
    m : int
        Equations used.
    chi2 : float
        Sum of squared whitened residuals over the equations used.
    phi : numpy.ndarray
        Linear coefficients, candidate blocks in the order of ``names``.
    cov : numpy.ndarray
        Covariance of phi (scaled by the residual variance of each parameter's subsystem).
    slices : dict
        Candidate name -> slice of phi.
    shift : int
        Dead time in samples (0: none).
    shift_ci : tuple of int
        Profile interval of the shift.
    mu : numpy.ndarray
        Fitted model vector.
    e : numpy.ndarray or None, shape (nb, 6)
        Whitened residuals of every block under this fit (None for a fit from Gram
        matrices, which never forms them).
    chi2_channel : numpy.ndarray or None, shape (6,)
        chi2 per channel over the equations used.
    """

    names: tuple
    k: int
    m: int
    chi2: float
    phi: np.ndarray
    cov: np.ndarray
    slices: dict
    shift: int
    shift_ci: tuple
    mu: np.ndarray
    e: np.ndarray | None
    chi2_channel: np.ndarray | None = None

    @property
    def bic(self) -> float:
        """chi2 + k ln m (:func:`bic`)."""
        return bic(self.chi2, self.k, self.m)

    @property
    def aicc(self) -> float:
        """Small-sample AIC (:func:`aicc`)."""
        return aicc(self.chi2, self.k, self.m)

    def rho(self) -> np.ndarray:
        """Residual-to-noise RMS ratio per channel (all blocks)."""
        return np.sqrt(np.mean(self.e ** 2, axis=0))


def _directions(prob: Problem, names):
    """Directions D (NMU, K) in mu, extra prediction columns E (nb, 6, K) or None, the
    candidate slices of phi and whether a dead time is profiled (remembered per problem)."""
    key = ("directions", tuple(names))
    if key not in prob._memo:
        prob._memo[key] = _directions_of(prob, names)
    D, slices, grid, E = prob._memo[key]
    return D, dict(slices), grid, E


def _directions_of(prob: Problem, names):
    cands = library(names)
    Ds, Es, slices, j = [], [], {}, 0
    nb = prob.bs.nb
    for c in cands:
        if c.columns is not None:
            E = prob.bs.extra[c.columns].at(prob.mu_columns)
            D = np.zeros((prob.mu0.size, E.shape[2]))
        elif c.directions is None:
            slices[c.name] = slice(j, j)
            continue
        else:
            D = c.directions(prob.mu0, prob.arm)
            E = None
        Ds.append(D)
        Es.append(np.zeros((nb, prob.bs.y.shape[1], D.shape[1])) if E is None else E)
        slices[c.name] = slice(j, j + D.shape[1])
        j += D.shape[1]
    D = np.concatenate(Ds, axis=1) if Ds else np.zeros((prob.mu0.size, 0))
    E = None
    if any(c.columns is not None for c in cands):
        E = np.concatenate(Es, axis=2)
    grid = any(c.grid for c in cands)
    return D, slices, grid, E


def _solve(prob, D, shift, mask, E=None):
    X = prob.X(shift)
    nb, nc, nm = X.shape
    Xf = X.reshape(nb * nc, nm)                 # BLAS products (einsum does not use BLAS here)
    key = ("base", shift)
    if key not in prob._memo:                   # whitened residual of the nominal model
        prob._memo[key] = (prob.bs.y - (Xf @ prob.mu0).reshape(nb, nc)) / prob.sigma
    base = prob._memo[key]
    P = (Xf @ D).reshape(nb, nc, D.shape[1])
    if E is not None:
        P = P + E
    Z = P / prob.sigma[None, :, None]
    k = D.shape[1]
    b = base[mask].ravel()
    A = Z[mask].reshape(b.size, k)
    phi = lstsq(A, b)
    r = b - A @ phi
    return phi, float(r @ r), A, base, Z


def _scaled_cov(A_normal, chi2_channel, Zdiag_channels, m_per_channel):
    """Covariance of phi: A^-1 scaled per column by the residual variance of its subsystem.

    An unexplained torque residual must not inflate the intervals of a valve parameter,
    nor hide behind them; a column acting in both subsystems (a sensor fault) takes the
    variance of both.
    """
    k = A_normal.shape[0]
    if k == 0:
        return np.zeros((0, 0))
    acts = Zdiag_channels > 0                               # (nch, k)
    chi2_of = acts.T.astype(float) @ chi2_channel           # (k,)
    nch_of = acts.sum(axis=0)                               # (k,)
    # columns sharing a channel set with column j (the parameters charged to its variance)
    ksub = (acts.T.astype(int) @ acts.astype(int) > 0).sum(axis=1)
    dof = np.maximum(m_per_channel * nch_of - ksub, 1)
    # never below the noise model: a residual under the stated noise (the resolution floor of
    # rest points) does not make a parameter better known than the noise allows
    sd = np.where(nch_of > 0, np.sqrt(np.maximum(chi2_of / dof, 1.0)), 1.0)
    return sd[:, None] * pinv_psd(A_normal) * sd[None, :]


def fit_model(prob: Problem, names, mask=None) -> _Fit:
    """Fit the nominal model extended by the candidates ``names`` on the full design.

    The dead time (if among ``names``) is profiled over every shift of the
    grid; every whitened block residual is formed (``_Fit.e``).

    Parameters
    ----------
    prob : Problem
    names : sequence of str
        Candidate names (may be empty: the nominal model).
    mask : numpy.ndarray of bool, shape (nb,), optional
        Blocks to fit on (default all).

    Returns
    -------
    _Fit
    """
    names = tuple(names)
    nb = prob.bs.nb
    mask = np.ones(nb, bool) if mask is None else np.asarray(mask, bool)
    D, slices, grid, E = _directions(prob, names)
    shifts = ((prob.bs.shift_grid(prob.max_shift) if prob.shift_grid is None
               else prob.shift_grid) if grid else (0,))
    best, prof = None, []
    for s in shifts:
        phi, chi2, A, base, Z = _solve(prob, D, s, mask, E)
        prof.append(chi2)
        if best is None or chi2 < best[1]:
            best = (phi, chi2, A, base, Z, s)
    phi, chi2, A, base, Z, shift = best
    m = A.shape[0]
    k = D.shape[1] + (1 if grid else 0)
    s2 = chi2 / max(m - k, 1)
    e = base - Z @ phi
    chi2_c = np.sum(e[mask] ** 2, axis=0)
    if D.shape[1]:
        zd = np.sum(Z[mask] ** 2, axis=0)                     # (6, k)
        cov = _scaled_cov(A.T @ A, chi2_c, zd, int(mask.sum()))
    else:
        cov = np.zeros((0, 0))
    if grid:
        prof = np.array(prof)
        ok = np.nonzero(prof - prof.min() <= s2 * _CHI2_95_1)[0]
        grid_shifts = np.asarray(list(shifts))
        shift_ci = (int(grid_shifts[ok].min()), int(grid_shifts[ok].max()))
    else:
        shift_ci = (0, 0)
    return _Fit(names=names, k=k, m=m, chi2=chi2, phi=phi, cov=cov, slices=slices, shift=shift,
               shift_ci=shift_ci, mu=prob.mu0 + D @ phi, e=e, chi2_channel=chi2_c)


def cv_chi2(prob: Problem, names) -> float:
    """Held-out chi2 of 2-fold cross-validation over alternating time segments (full design).

    Parameters
    ----------
    prob : Problem
    names : sequence of str
        Candidate names of the model.
    """
    total = 0.0
    for f in (0, 1):
        fit = fit_model(prob, names, mask=prob.fold != f)
        total += float(np.sum(fit.e[prob.fold == f] ** 2))
    return total


# ----------------------------------------------------------------------------- Gram path

def _grid_name(names) -> str | None:
    return next((c.name for c in library(names) if c.grid), None)


def _gram_set(prob: Problem, names, shift: int) -> Gram:
    """The Gram set of every linear candidate of ``names`` at dead time ``shift`` (cached)."""
    lin = tuple(n for n in names if not REGISTRY[n].grid)
    key = ("gram", lin, int(shift))
    if key not in prob._memo:
        D, slices, _, E = _directions(prob, lin)
        X = prob.X(shift)
        nb, nc, nm = X.shape
        Xf = X.reshape(nb * nc, nm)
        P = (Xf @ D).reshape(nb, nc, D.shape[1])
        if E is not None:
            P = P + E
        base = prob.bs.y - (Xf @ prob.mu0).reshape(nb, nc)
        prob._memo[key] = (Gram.from_blocks(P, base, prob.chunk, slices, shift), D)
    return prob._memo[key]


def gram_fit(prob: Problem, names, *, universe, shift: int = 0, chunks=None,
             cov: bool = True) -> _Fit:
    """Fit ``names`` from the Gram matrices (no block residuals formed).

    Parameters
    ----------
    prob : Problem
    names : sequence of str
        Candidates of the model; the dead-time candidate among them is held at ``shift``
        (counted as one fitted parameter).
    universe : sequence of str
        The candidates the Gram set is built for (a superset of ``names``).
    shift : int, keyword-only
        Dead time [samples] of the design (0 unless the model holds the dead time).
    chunks : numpy.ndarray of bool, shape (nchunk,), optional, keyword-only
        Chunks to fit on (default all).
    cov : bool, keyword-only
        Also the covariance and the chi2 per channel (else ``cov`` is empty and
        ``chi2_channel`` None: enough to rank).

    Returns
    -------
    _Fit
        With ``e = None``.
    """
    names = tuple(names)
    grid = any(REGISTRY[n].grid for n in names)
    gs, D_all = _gram_set(prob, universe, shift if grid else 0)
    lin = [n for n in names if not REGISTRY[n].grid]
    cols = gs.columns(lin)
    Gs, Aw = gs.weighted(chunks, prob.sigma)
    gf = solve(Gs, cols, prob.sigma, Aw, per_channel=cov)
    nblocks = int(prob.bs.nb if chunks is None else np.asarray(chunks, bool)[prob.chunk].sum())
    m = nblocks * prob.bs.y.shape[1]
    k = cols.size + (1 if grid else 0)
    if cov:
        w = 1.0 / prob.sigma ** 2
        zd = (Gs[:, cols, cols] * w[:, None]) if cols.size else np.zeros((Gs.shape[0], 0))
        cmat = _scaled_cov(gf.A, gf.chi2_channel, zd, nblocks)
    else:
        cmat = np.zeros((0, 0))
    slices, j = {}, 0
    for n in names:
        c = REGISTRY[n]
        width = 0 if c.grid else gs.slices[n].stop - gs.slices[n].start
        slices[n] = slice(j, j + width)
        j += width
    mu = prob.mu0 + D_all[:, cols] @ gf.phi
    return _Fit(names=names, k=k, m=m, chi2=gf.chi2, phi=gf.phi, cov=cmat, slices=slices,
               shift=shift if grid else 0, shift_ci=(shift, shift) if grid else (0, 0), mu=mu,
               e=None, chi2_channel=gf.chi2_channel)


def gram_cv(prob: Problem, names, *, universe, shift: int = 0, chunks=None) -> float:
    """Held-out chi2 of 2-fold cross-validation from the Gram matrices (see :func:`cv_chi2`).

    Parameters
    ----------
    prob : Problem
    names : sequence of str
    universe : sequence of str
    shift : int, keyword-only
    chunks : numpy.ndarray of bool, optional, keyword-only
        Restrict both folds to these chunks.
    """
    names = tuple(names)
    grid = any(REGISTRY[n].grid for n in names)
    gs, _ = _gram_set(prob, universe, shift if grid else 0)
    cols = gs.columns([n for n in names if not REGISTRY[n].grid])
    use = np.ones(prob.nchunk, bool) if chunks is None else np.asarray(chunks, bool)
    total = 0.0
    for f in (0, 1):
        train = use & (prob.chunk_fold != f)
        test = use & (prob.chunk_fold == f)
        Gtr, Atr = gs.weighted(train, prob.sigma)
        gf = solve(Gtr, cols, prob.sigma, Atr)
        total += chi2_at(None, cols, gf.phi, prob.sigma, gs.weighted(test, prob.sigma)[1])
    return total


def forward_selection(prob: Problem, candidates=None, *, alpha: float = ALPHA,
                      max_effects: int = 5, chunks=None, fixed_shift: int | None = None,
                      confounding: bool = True, move_columns: bool = True) -> tuple:
    """Forward selection with refit (module docstring).

    Returns the final fit (full design, every block residual formed; on the
    chunks selected), the list of Step and the Problem with the noise levels
    of the final model.  A backward pass at the end drops an effect that the
    later ones made redundant (no longer significant, or no longer lowering
    the BIC); the final fit's names are then a subset of the steps' choices.

    Parameters
    ----------
    prob : Problem
    candidates : sequence of str, optional
        Names to consider (default the whole library).
    alpha : float, keyword-only
        Level of the likelihood-ratio test before the Bonferroni division.
    max_effects : int, keyword-only
        Largest number of effects selected.
    chunks : numpy.ndarray of bool, shape (nchunk,), optional, keyword-only
        Run on these chunks only (a half of the record: stability selection).
    fixed_shift : int, optional, keyword-only
        Hold the dead time at this shift instead of profiling it (resampling schemes).
    confounding : bool, keyword-only
        Check the chosen candidate for confounded alternatives (:func:`confounded_with`).
    move_columns : bool, keyword-only
        Move the model-dependent columns to every new model (False: keep them where
        ``prob`` has them; the resampling schemes start from the full record's final model
        and save rebuilding the Gram matrices at every step of every half).
    """
    universe = tuple(c.name for c in library(candidates))
    grid_name = _grid_name(universe)
    selected: list = []
    prob0 = prob
    shift = 0
    current = gram_fit(prob, selected, universe=universe, chunks=chunks, cov=False)
    cur_cv = gram_cv(prob, selected, universe=universe, chunks=chunks)
    steps = []
    while len(selected) < max_effects:
        rest = [n for n in universe if n not in selected]
        if not rest:
            break
        rows, fits = [], {}
        lin_rest = [n for n in rest if not REGISTRY[n].grid]
        fast = _step_scores(prob, selected, lin_rest, universe=universe, shift=shift,
                            chunks=chunks, m=current.m)
        for n in rest:
            if n == grid_name and fixed_shift is None:
                mask = None if chunks is None else np.asarray(chunks, bool)[prob.chunk]
                f = fit_model(prob, selected + [n], mask=mask)
                cv = _cv_direct(prob, selected + [n], chunks)
            elif n == grid_name:
                f = gram_fit(prob, selected + [n], universe=universe, shift=fixed_shift,
                             chunks=chunks, cov=False)
                cv = gram_cv(prob, selected + [n], universe=universe, shift=fixed_shift,
                             chunks=chunks)
            else:
                f, cv = fast[n]
            fits[n] = f
            d = current.chi2 - f.chi2
            df = max(f.k - current.k, 1)
            rows.append({"name": n, "k": f.k - current.k, "chi2": f.chi2, "bic": f.bic,
                         "aicc": f.aicc, "delta_bic": f.bic - current.bic, "lr_stat": d,
                         "lr_df": df, "p_value": _chi2_sf(max(d, 0.0), df),
                         "cv_chi2": cv, "cv_gain": cur_cv - cv})
        # admissibility (a parameter table) is checked lazily, in order of BIC, only for
        # candidates that pass the other tests, until one is eligible: only those can be
        # chosen; the rest count as admissible, which can only lower the winner's weight
        level = alpha / len(rest)
        for r in sorted(rows, key=lambda r: r["bic"]):
            r["in_bounds"] = True
        for r in sorted(rows, key=lambda r: r["bic"]):
            if not (r["delta_bic"] < 0 and r["p_value"] < level and r["cv_gain"] > 0):
                continue
            n = r["name"]
            has_cov = isinstance(fits[n], _Fit) and (fits[n].e is not None
                                                    or fits[n].chi2_channel is not None)
            if not has_cov:
                fits[n] = gram_fit(prob, selected + [n], universe=universe,
                                   shift=fits[n].shift if n == grid_name else shift,
                                   chunks=chunks)
            r["in_bounds"] = in_bounds(prob, fits[n], n)
            if r["in_bounds"]:
                break
        chosen, w0 = rank_step(rows, current.bic, alpha=alpha, n_candidates=len(rest))
        group = ()
        if chosen is not None and confounding:
            group = confounded_with(prob, chosen, rows, fits, selected, universe=universe,
                                    shift=shift, alpha=alpha, n_candidates=len(rest),
                                    chunks=chunks, fixed_shift=fixed_shift)
        steps.append(Step(tuple(selected), rows, chosen, current.bic, cur_cv, w0, group))
        if chosen is None:
            break
        selected.append(chosen)
        if chosen == grid_name:
            shift = fits[chosen].shift
        # the noise level depends on the model (velocity noise enters through H qd):
        # re-evaluate it at the new model, refit, and compare the next step on that footing
        if not isinstance(fits[chosen], _Fit):
            fits[chosen] = gram_fit(prob, selected, universe=universe, shift=shift,
                                    chunks=chunks, cov=False)
        prob = _at(prob0, fits[chosen].mu, move_columns)
        current = gram_fit(prob, selected, universe=universe, shift=shift, chunks=chunks,
                           cov=False)
        cur_cv = gram_cv(prob, selected, universe=universe, shift=shift, chunks=chunks)
    # backward pass: an effect chosen early may be redundant once later ones are in (a
    # valve offset absorbing the valve part of a pressure-sensor gain before the gain
    # itself was chosen); drop the least significant one while any is not significant
    # (LR p >= alpha/K) or does not lower the BIC, then refit
    n_all = len(universe)
    while len(selected) > 1:
        worst, worst_p = None, -1.0
        for c in selected:
            rest = [n for n in selected if n != c]
            sh = shift if grid_name in rest else 0
            fw = gram_fit(prob, rest, universe=universe, shift=sh, chunks=chunks, cov=False)
            d = max(fw.chi2 - current.chi2, 0.0)
            p = _chi2_sf(d, max(current.k - fw.k, 1))
            if (p >= alpha / n_all or fw.bic <= current.bic) and p > worst_p:
                worst, worst_p = c, p
        if worst is None:
            break
        selected.remove(worst)
        if worst == grid_name:
            shift = 0
        mu = gram_fit(prob, selected, universe=universe, shift=shift, chunks=chunks,
                      cov=False).mu
        prob = _at(prob0, mu, move_columns)
        current = gram_fit(prob, selected, universe=universe, shift=shift, chunks=chunks,
                           cov=False)
    if chunks is None:
        final, prob = refit(prob0, selected, prob=prob,
                            shift=shift if fixed_shift is not None else None)
    else:
        final = current
    return final, steps, prob


def _at(prob0, mu, move_columns):
    if move_columns:
        return at_model(prob0, mu)
    return replace(prob0, sigma=_floored(block_noise(*prob0.noise, mu), prob0.floor),
                   _xcache=prob0._xcache, _memo=prob0._memo)


def refit(prob0: Problem, names, *, prob: Problem | None = None, shift: int | None = None):
    """The full-design fit of ``names`` at its own model (fixed point of the noise levels and
    of the model-dependent columns).

    Parameters
    ----------
    prob0 : Problem
        At the nominal model.
    names : sequence of str
    prob : Problem, optional, keyword-only
        A starting point nearer the answer (default ``prob0``).
    shift : int, optional, keyword-only
        Hold the dead time at this shift (default: profile it).

    Returns
    -------
    (_Fit, Problem)
    """
    names = list(names)
    prob = prob0 if prob is None else prob
    grid = any(REGISTRY[n].grid for n in names)
    for _ in range(3):
        final = fit_model(replace(prob, shift_grid=(shift,)) if shift is not None and grid
                          else prob, names)
        nxt = at_model(prob0, final.mu)
        if nxt.mu_ref is prob.mu_ref or not names:
            break
        prob = nxt
    return final, prob


@dataclass(frozen=True)
class _Score:
    """chi2 and size of a candidate model scored by :func:`_step_scores` (no coefficients)."""

    k: int
    m: int
    chi2: float
    shift: int = 0

    @property
    def bic(self) -> float:
        return bic(self.chi2, self.k, self.m)

    @property
    def aicc(self) -> float:
        return aicc(self.chi2, self.k, self.m)


def _step_scores(prob, selected, rest, *, universe, shift, chunks, m):
    """chi2 and 2-fold held-out chi2 of ``selected`` + each linear candidate of ``rest`` (one
    compiled call, :func:`ppamsafety.lstsq.step_scores`)."""
    if not rest:
        return {}
    grid = any(REGISTRY[n].grid for n in selected)
    gs, _ = _gram_set(prob, universe, shift if grid else 0)
    use = np.ones(prob.nchunk, bool) if chunks is None else np.asarray(chunks, bool)
    A = gs.weighted(None if chunks is None else use, prob.sigma)[1]
    A_tr = np.stack([gs.weighted(use & (prob.chunk_fold != f), prob.sigma)[1] for f in (0, 1)])
    A_te = np.stack([gs.weighted(use & (prob.chunk_fold == f), prob.sigma)[1] for f in (0, 1)])
    cur = gs.columns([n for n in selected if not REGISTRY[n].grid]).astype(np.int64)
    cols = [gs.columns([n]).astype(np.int64) for n in rest]
    ptr = np.concatenate([[0], np.cumsum([c.size for c in cols])]).astype(np.int64)
    chi2 = np.empty(len(rest))
    cv = np.empty(len(rest))
    step_scores(A, A_tr, A_te, cur, np.concatenate(cols), ptr, chi2, cv)
    k0 = cur.size + (1 if grid else 0)
    return {n: (_Score(k=k0 + c.size, m=m, chi2=float(x), shift=shift if grid else 0), float(v))
            for n, c, x, v in zip(rest, cols, chi2, cv)}


def _cv_direct(prob, names, chunks):
    total = 0.0
    use = np.ones(prob.nchunk, bool) if chunks is None else np.asarray(chunks, bool)
    for f in (0, 1):
        train = (use & (prob.chunk_fold != f))[prob.chunk]
        test = (use & (prob.chunk_fold == f))[prob.chunk]
        fit = fit_model(prob, names, mask=train)
        total += float(np.sum(fit.e[test] ** 2))
    return total


def confounded_with(prob: Problem, chosen: str, rows, fits, selected, *, universe, shift: int,
                    alpha: float, n_candidates: int, chunks=None,
                    fixed_shift: int | None = None) -> tuple:
    """Candidates the record cannot tell from ``chosen`` at this step.

    A candidate c is confounded with the chosen one when it passes the
    naming rule's evidence tests on its own (delta BIC < 0, LR p < alpha/K,
    admissible) and neither adds significantly to a model that holds the
    other: the LR test of ``selected + {chosen, c}`` against ``selected +
    {chosen}`` *and* against ``selected + {c}`` gives p >= alpha/K.  Both then
    explain the same part of the residual.

    Parameters
    ----------
    prob : Problem
    chosen : str
    rows : list of dict
        The step's ranking rows (with ``delta_bic``, ``p_value``, ``in_bounds``).
    fits : dict
        Candidate -> _Fit of ``selected + [candidate]``.
    selected : list of str
        Effects already in the model.
    universe : sequence of str, keyword-only
    shift : int, keyword-only
        Dead time of the current design [samples].
    alpha : float, keyword-only
    n_candidates : int, keyword-only
        Bonferroni divisor.
    chunks : numpy.ndarray of bool, optional, keyword-only
    fixed_shift : int, optional, keyword-only

    Returns
    -------
    tuple of str
        The confounded candidates (without ``chosen``), by BIC.
    """
    grid_name = _grid_name(universe)
    level = alpha / n_candidates
    out = []
    fc = fits[chosen]
    for r in sorted(rows, key=lambda r: r["bic"]):
        c = r["name"]
        if c == chosen or not (r["delta_bic"] < 0 and r["p_value"] < level and r["in_bounds"]):
            continue
        both = selected + [chosen, c]
        has_grid = grid_name in both
        sh = (fixed_shift if fixed_shift is not None else
              (fits[grid_name].shift if grid_name in (chosen, c) else shift)) if has_grid else 0
        fb = gram_fit(prob, both, universe=universe, shift=sh, chunks=chunks, cov=False)
        fo = fits[c]
        p1 = _chi2_sf(max(fc.chi2 - fb.chi2, 0.0), max(fb.k - fc.k, 1))
        p2 = _chi2_sf(max(fo.chi2 - fb.chi2, 0.0), max(fb.k - fo.k, 1))
        if p1 >= level and p2 >= level:
            out.append(c)
    return tuple(out)


# ----------------------------------------------------------------------------- resampling

def resample(prob: Problem, idx, *, shift_grid=None) -> Problem:
    """``prob`` restricted to the blocks ``idx`` (in that order, repeats allowed).

    The noise levels stay those of ``prob``; the chunks and cross-validation
    folds are re-assigned by position in the new order.

    Parameters
    ----------
    prob : Problem
    idx : numpy.ndarray of int
        Block indices.
    shift_grid : tuple of int, optional, keyword-only
        Dead-time shifts to profile in the resampled problem.
    """
    idx = np.asarray(idx, dtype=int)
    bs = prob.bs
    nbs = replace(bs, y=bs.y[idx], X=bs.X[idx], starts=bs.starts[idx], stops=bs.stops[idx],
                  features={k: v[idx] for k, v in bs.features.items()},
                  extra={k: v.take(idx) for k, v in bs.extra.items()})
    n = idx.size
    chunk, cfold = chunk_layout(n)
    noise = tuple(a[:, idx] for a in prob.noise) if prob.noise else ()
    # the dead-time designs of the blocks are rows of the parent's: take them from its cache
    # (rebuilding one integrates the whole delayed input again)
    keep = prob._xcache.keys() if shift_grid is None else set(shift_grid) | {0}
    cache = {s: X[idx] for s, X in prob._xcache.items() if s in keep}
    return Problem(bs=nbs, mu0=prob.mu0, sigma=prob.sigma, arm=prob.arm, fold=cfold[chunk],
                   max_shift=prob.max_shift, noise=noise, floor=prob.floor,
                   shift_grid=shift_grid, chunk=chunk, chunk_fold=cfold, mu_ref=prob.mu_ref,
                   _xcache=cache)


#: Default number of bootstrap replicates of :func:`bootstrap_frequency` (0: the pipeline's
#: confidence uses the stability selection instead).
BOOTSTRAP_REPLICATES = 0
#: Default number of complementary pairs of :func:`stability_selection` (50 halves).
STABILITY_PAIRS = 25
#: Selection frequency at or above which a name counts as stable (the threshold pi_thr of
#: the error bound of :func:`stability_selection`).
STABILITY_THRESHOLD = 0.8


def profiled_shift(prob: Problem, candidates) -> int | None:
    """The dead time of the full record (profiled once), or None without the candidate.

    Parameters
    ----------
    prob : Problem
    candidates : sequence of str or None
        The library (the dead-time candidate among them is profiled alone).
    """
    lib = library(candidates)
    if not any(c.grid for c in lib):
        return None
    return int(fit_model(prob, [c.name for c in lib if c.grid]).shift)


def bootstrap_frequency(prob: Problem, candidates=None, *, replicates: int = 40,
                        seed: int = 0, block_length: int | None = None, alpha: float = ALPHA,
                        max_effects: int = 5) -> tuple:
    """How often the forward selection picks each effect on moving-block bootstrap resamples.

    The blocks (time-ordered rows of the block system) are resampled with
    the moving-block bootstrap (Kuensch 1989): runs of ``block_length``
    consecutive blocks starting at uniformly drawn positions, concatenated
    to the original length, so a model error correlated over neighbouring
    blocks stays together.  Every replicate re-runs
    :func:`forward_selection` on its regressions (no re-simulation; the
    noise levels are those of the full record).  The valve dead time is
    profiled once on the whole record and held at that shift in the
    replicates (its linear parameters are refitted).

    Parameters
    ----------
    prob : Problem
    candidates : sequence of str, optional
        As in :func:`forward_selection`.
    replicates : int, keyword-only
        Number of bootstrap replicates B.
    seed : int, keyword-only
        Seed of the resampling.
    block_length : int, optional, keyword-only
        Run length in blocks; default ceil(nb^(1/3)) (the usual rate).
    alpha : float, keyword-only
        Level of the likelihood-ratio test.
    max_effects : int, keyword-only
        Largest number of effects selected per replicate.

    Returns
    -------
    frequency : dict
        Candidate name -> fraction of replicates selecting it, in [0, 1].
    info : dict
        ``replicates``, ``block_length``, ``seed``, ``method``.
    """
    replicates = check_int("replicates", replicates, 1, 10000)
    seed = check_seed("seed", seed)
    nb = prob.bs.nb
    L = (max(1, int(math.ceil(nb ** (1.0 / 3.0)))) if block_length is None
         else check_int("block_length", block_length, 1, nb))
    rng = np.random.default_rng(seed)
    names = [c.name for c in library(candidates)]
    counts = dict.fromkeys(names, 0)
    runs = int(math.ceil(nb / L))
    s = profiled_shift(prob, candidates)
    grid = None if s is None else (s,)
    if grid:
        prob.X(grid[0])
    prob.X(0)
    for _ in range(replicates):
        st = rng.integers(0, nb - L + 1, size=runs)
        idx = (st[:, None] + np.arange(L)[None, :]).ravel()[:nb]
        _, steps, _ = forward_selection(resample(prob, idx, shift_grid=grid), candidates,
                                        alpha=alpha, max_effects=max_effects,
                                        fixed_shift=s, confounding=False)
        for st_ in steps:
            if st_.chosen is not None:
                counts[st_.chosen] += 1
    return ({n: counts[n] / replicates for n in names},
            {"replicates": replicates, "block_length": L, "seed": seed,
             "method": "moving-block bootstrap over the time-ordered blocks; forward selection "
                       "re-run on each replicate"})


@dataclass(frozen=True)
class Stability:
    """Complementary-pairs stability selection of the forward selection (Shah & Samworth 2013).

    Attributes
    ----------
    frequency : dict
        Candidate -> fraction of the 2B halves that selected it.
    pairs : int
        B, the number of complementary pairs.
    threshold : float
        pi_thr: a name is *stable* when its frequency reaches it.
    q : float
        Mean number of candidates selected per half.
    p : int
        Number of candidates.
    expected_false_bound : float or None
        Upper bound on the expected number of stable names that are false selections,
        q^2 / ((2 pi_thr - 1) p) (Meinshausen & Buehlmann 2010, Theorem 1; Shah & Samworth
        2013 show it holds for complementary pairs under the same exchangeability
        assumption); None when pi_thr <= 0.5.
    seed : int
    chunk_blocks : float
        Mean blocks per chunk (the unit the record is halved by).
    """

    frequency: dict
    pairs: int
    threshold: float
    q: float
    p: int
    expected_false_bound: float | None
    seed: int
    chunk_blocks: float

    def to_dict(self) -> dict:
        """JSON-ready form (``diagnosis.json`` key ``stability``)."""
        return {"method": "complementary-pairs stability selection (Shah & Samworth 2013): the "
                          "forward selection re-run on both halves of B random splits of the "
                          "record's chunks (runs of consecutive blocks)",
                "pairs": self.pairs, "halves": 2 * self.pairs, "threshold": self.threshold,
                "mean_selected_per_half": self.q, "candidates": self.p,
                "expected_false_selections_bound": self.expected_false_bound,
                "bound": "E[V] <= q^2 / ((2 pi_thr - 1) p) (Meinshausen & Buehlmann 2010, "
                         "Theorem 1)",
                "seed": self.seed, "chunk_blocks": self.chunk_blocks,
                "frequency": dict(self.frequency)}


def stability_selection(prob: Problem, candidates=None, *, pairs: int = STABILITY_PAIRS,
                        seed: int = 0, alpha: float = ALPHA, max_effects: int = 5,
                        threshold: float = STABILITY_THRESHOLD,
                        reference=None) -> Stability:
    """Selection frequencies over complementary halves of the record.

    B times, the chunks (runs of consecutive blocks, :func:`~.gram.chunk_layout`) are split
    at random into two halves of equal size, and :func:`forward_selection` (same rule,
    Gram fits, confounding not checked) runs on each half.  A name's frequency is the
    fraction of the 2B halves that select it.  With a threshold pi_thr > 1/2 the expected
    number of false selections among the names with frequency >= pi_thr is bounded by
    q^2 / ((2 pi_thr - 1) p) (q the mean number selected per half, p the number of
    candidates): the error control of Meinshausen & Buehlmann (2010), which Shah &
    Samworth (2013) show holds for complementary pairs.  The dead time is profiled once
    on the whole record and held at that shift in the halves.

    Parameters
    ----------
    prob : Problem
    candidates : sequence of str, optional
    pairs : int, keyword-only
        B (>= 1).
    seed : int, keyword-only
        Seed of the splits.
    alpha : float, keyword-only
    max_effects : int, keyword-only
    threshold : float, keyword-only
        pi_thr in (0.5, 1].
    reference : numpy.ndarray, shape (NMU,), optional, keyword-only
        Model vector at which the model-dependent columns (sensor faults) are held in the
        halves (default: where ``prob`` has them); the pipeline passes the full record's
        final model.

    Returns
    -------
    Stability
    """
    pairs = check_int("pairs", pairs, 1, 10000)
    seed = check_seed("seed", seed)
    names = [c.name for c in library(candidates)]
    counts = dict.fromkeys(names, 0)
    s = profiled_shift(prob, candidates)
    if reference is not None:
        prob = at_model(prob, reference)
        prob = replace(prob, sigma=_floored(block_noise(*prob.noise, prob.mu0), prob.floor))
    rng = np.random.default_rng(seed)
    C = prob.nchunk
    total = 0
    for _ in range(pairs):
        perm = rng.permutation(C)
        half = np.zeros(C, bool)
        half[perm[:C // 2]] = True
        for h in (half, ~half):
            _, steps, _ = forward_selection(prob, candidates, alpha=alpha,
                                            max_effects=max_effects, chunks=h,
                                            fixed_shift=s, confounding=False,
                                            move_columns=False)
            for st in steps:
                if st.chosen is not None:
                    counts[st.chosen] += 1
                    total += 1
    halves = 2 * pairs
    q = total / halves
    p = len(names)
    bound = false_selection_bound(q, threshold, p)
    return Stability(frequency={n: counts[n] / halves for n in names}, pairs=pairs,
                     threshold=threshold, q=q, p=p, expected_false_bound=bound, seed=seed,
                     chunk_blocks=prob.bs.nb / max(C, 1))


# ----------------------------------------------------------------------------- consistency

def region_consistency(prob: Problem, fit: _Fit, name: str) -> dict:
    """Are the parameters of effect ``name`` the same in different parts of the arm's motion?

    A real effect has one value wherever the arm moves; an effect that is standing in for
    something else (an encoder gain taken for an offset, a heavier link taken for a
    payload, a nonlinearity taken for a gain) fits different values in different regions.
    For each joint, the final model is refitted on the blocks of the lowest and of the
    highest third of that joint's angle (disjoint, so independent), and the Wald statistic
    ``(phi_lo - phi_hi)^T (C_lo + C_hi)^+ (phi_lo - phi_hi)`` of the effect's coefficients
    is referred to chi2 with k degrees of freedom (a Chow test).

    Parameters
    ----------
    prob : Problem
        At the final model.
    fit : _Fit
        The final fit (full design).
    name : str
        One of ``fit.names``.

    Returns
    -------
    dict
        ``{"q1": p_value, "q2": p_value}`` (1.0 where a region is too small to fit).
    """
    q = prob.bs.features["q"]
    fixed = replace(prob, shift_grid=(fit.shift,)) if REGISTRY.get(name) is not None and any(
        REGISTRY[n].grid for n in fit.names) else prob
    out = {}
    D, slices, _, _ = _directions(prob, fit.names)
    sl = slices[name]
    if sl.stop == sl.start:                       # the dead time: no linear coefficients
        return {"q1": 1.0, "q2": 1.0}
    for j in range(2):
        lo_t, hi_t = np.quantile(q[:, j], [1 / 3, 2 / 3])
        masks = (q[:, j] <= lo_t, q[:, j] >= hi_t)
        if min(int(m.sum()) for m in masks) < 3 * max(len(fit.phi), 1):
            out[f"q{j + 1}"] = 1.0
            continue
        fa, fb = (fit_model(fixed, fit.names, mask=m) for m in masks)
        d = fa.phi[sl] - fb.phi[sl]
        C = fa.cov[sl, sl] + fb.cov[sl, sl]
        T = float(d @ pinv_psd(C) @ d)
        out[f"q{j + 1}"] = _chi2_sf(max(T, 0.0), sl.stop - sl.start)
    return out


def compensating(prob: Problem, fit: _Fit, *, ratio: float = None) -> dict:
    """Pairs of effects of ``fit`` that cancel each other in some channel.

    A model that explains a residual by two large contributions of opposite sign (a
    pressure-sensor offset whose pressure signature a valve offset cancels, leaving a torque
    error proportional to one muscle's lever arm) is fitting something neither effect is:
    here a muscle's geometry or force law, outside the library.  For every pair (a, b) and
    every block channel c, with a's and b's whitened contributions v_a, v_b on c: they
    compensate when the cosine of the two is <= :data:`COMPENSATION_COS` (they point
    against each other) and both have an RMS of at least one noise level.

    Parameters
    ----------
    prob : Problem
    fit : _Fit
        The final fit.
    ratio : float, optional, keyword-only
        The cosine threshold (default :data:`COMPENSATION_COS`).

    Returns
    -------
    dict
        Effect name -> tuple of the effects it compensates with.
    """
    ratio = COMPENSATION_COS if ratio is None else ratio
    names = [n for n in fit.names if not REGISTRY[n].grid]
    if len(names) < 2:
        return {}
    D, slices, _, E = _directions(prob, fit.names)
    X = prob.X(fit.shift)
    nb, nc, nm = X.shape
    P = (X.reshape(nb * nc, nm) @ D).reshape(nb, nc, D.shape[1])
    if E is not None:
        P = P + E
    Z = P / prob.sigma[None, :, None]
    v = {n: Z[:, :, slices[n]] @ fit.phi[slices[n]] for n in names}     # (nb, nc) each
    floor = math.sqrt(nb)
    out = {n: [] for n in names}
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            na = np.linalg.norm(v[a], axis=0)
            nbb = np.linalg.norm(v[b], axis=0)
            cos = np.sum(v[a] * v[b], axis=0) / np.maximum(na * nbb, 1e-300)
            if np.any((cos <= ratio) & (na > floor) & (nbb > floor)):
                out[a].append(b)
                out[b].append(a)
    return {n: tuple(o) for n, o in out.items() if o}


#: Two contributions compensate in a channel when their cosine is at most this.
COMPENSATION_COS = -0.8


# ----------------------------------------------------------------------------- parameters

def in_bounds(prob: Problem, fit: _Fit, name: str) -> bool:
    """True if effect ``name`` of ``fit`` is admissible: no parameter significantly outside its
    physical range (its 95 % interval reaches into the range: a negative mass of -0.3 +- 0.05
    kg is a symptom, a viscous friction of -0.002 +- 0.01 N m s/rad is a zero) and every
    interval inside the plausible bounds widened by half their width.

    Parameters
    ----------
    prob : Problem
    fit : _Fit
    name : str
        One of ``fit.names``.
    """
    tab = parameter_table(prob, fit, truncate=False)[name]
    return all(tab[p.name].ci_high >= p.phys_lo and tab[p.name].ci_low <= p.phys_hi
               and tab[p.name].ci_low >= p.lo - 0.5 * (p.hi - p.lo)
               and tab[p.name].ci_high <= p.hi + 0.5 * (p.hi - p.lo)
               for p in REGISTRY[name].parameters)


def hac_covariance(prob: Problem, fit: _Fit, *, lags: int | None = None) -> np.ndarray:
    """Heteroskedasticity- and autocorrelation-consistent covariance of ``fit.phi``.

    The sandwich ``B^-1 M B^-1`` with ``B = Z^T Z`` (whitened columns) and the
    Newey-West meat ``M = sum_|l|<=L w_l sum_b s_b s_(b-l)^T``, Bartlett
    weights ``w_l = 1 - |l|/(L+1)``, block scores ``s_b = Z_b^T e_b`` (the six
    channels of a block together, so correlated channels are accounted for),
    times nb/(nb - k).  Residuals correlated over neighbouring blocks (a model
    error, coloured noise) widen the intervals; white residuals at the noise
    level give the ordinary covariance, and no variance is taken below it (per
    parameter, at least the noise model's ``B^-1``).

    Parameters
    ----------
    prob : Problem
    fit : _Fit
        A full-design fit (``fit.e`` formed).
    lags : int, optional, keyword-only
        L; default the chunk length (ceil(nb^(1/3))).

    Returns
    -------
    numpy.ndarray, shape (k, k)
    """
    D, _, _, E = _directions(prob, fit.names)
    k = D.shape[1]
    if k == 0:
        return np.zeros((0, 0))
    X = prob.X(fit.shift)
    nb, nc, nm = X.shape
    P = (X.reshape(nb * nc, nm) @ D).reshape(nb, nc, k)
    if E is not None:
        P = P + E
    Z = P / prob.sigma[None, :, None]
    S = np.einsum("bck,bc->bk", Z, fit.e)
    B = np.einsum("bci,bcj->ij", Z, Z)
    L = int(math.ceil(nb ** (1.0 / 3.0))) if lags is None else int(lags)
    M = S.T @ S
    for lag in range(1, min(L, nb - 1) + 1):
        w = 1.0 - lag / (L + 1.0)
        G = S[lag:].T @ S[:-lag]
        M += w * (G + G.T)
    Bi = pinv_psd(B)
    hac = Bi @ M @ Bi * nb / max(nb - k, 1)
    # never below the covariance of the noise model itself (Bi): residuals under the stated
    # noise (the resolution floor of rest points) do not make a parameter better known
    d = np.sqrt(np.maximum(np.diag(Bi) / np.maximum(np.diag(hac), 1e-300), 1.0))
    return d[:, None] * hac * d[None, :]


def parameter_table(prob: Problem, fit: _Fit, confidence: float = 0.95, *,
                    cov: np.ndarray | None = None, truncate: bool = True,
                    omitted: dict | None = None) -> dict:
    """Reported parameters of every effect of ``fit`` with delta-method intervals.

    Parameters
    ----------
    prob : Problem
    fit : _Fit
    confidence : float
        Level of the intervals.
    cov : numpy.ndarray, optional, keyword-only
        Covariance of ``fit.phi`` (default ``fit.cov``; the pipeline passes
        :func:`hac_covariance`).
    truncate : bool, keyword-only
        Intersect every interval with the parameter's physical range (the
        physical range is prior knowledge); the raw interval is kept as
        ``ci_low_raw``/``ci_high_raw``.
    omitted : dict, optional, keyword-only
        Candidate -> :class:`~ppamsafety.diagnose.core.omitted.OmittedEffect`
        (:func:`.detection.omitted`): the effects not named.  Each interval is then the union
        of the fit's and that of the fit plus each candidate the record holds a hint of
        (:func:`~ppamsafety.diagnose.core.omitted.widened_interval`); the fit's own is kept
        as ``ci_low_noise``/``ci_high_noise`` (cut at the physical range like the reported
        one) and ``widened_by`` names the candidates that widened it, farthest first.

    Returns
    -------
    dict
        name -> {parameter: :class:`~ppamsafety.diagnose.core.result.Estimate`}.
    """
    D, slices, _, _ = _directions(prob, fit.names)
    z = _normal_quantile(0.5 + confidence / 2)
    dt = prob.bs.dt
    cov = fit.cov if cov is None else cov
    nominal_fit_phi = np.zeros_like(fit.phi)
    out = {}
    for n in fit.names:
        c = REGISTRY[n]
        sl = slices[n]

        def val(phi, shift=fit.shift):
            mu = prob.mu0 + D @ phi
            return c.values(mu, phi[sl], shift * dt, prob.arm, dt)

        v = val(fit.phi)
        v_nom = val(nominal_fit_phi, 0)
        if c.grid:
            # the profile interval on the one-sample grid, widened by half a sample on each
            # side: a true delay between two grid points is profiled to the nearer one
            lo = np.maximum(val(nominal_fit_phi, fit.shift_ci[0] - 0.5), 0.0)
            hi = val(nominal_fit_phi, fit.shift_ci[1] + 0.5)
            se = (hi - lo) / (2 * z)
        elif c.physical is identity_values:
            # the values are the coefficients themselves
            J = np.zeros((v.size, fit.phi.size))
            J[np.arange(v.size), np.arange(sl.start, sl.stop)] = 1.0
            se = np.sqrt(np.maximum(np.diag(J @ cov @ J.T), 0.0))
            lo, hi = v - z * se, v + z * se
        else:
            J = np.zeros((v.size, fit.phi.size))
            sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
            for j in range(fit.phi.size):
                h = sd[j] * 1e-3 if sd[j] > 0 else 1e-9 * max(abs(fit.phi[j]), 1.0)
                p1 = fit.phi.copy()
                p1[j] += h
                J[:, j] = (val(p1) - v) / h
            se = np.sqrt(np.maximum(np.diag(J @ cov @ J.T), 0.0))
            lo, hi = v - z * se, v + z * se
        entry = {}
        for i, p in enumerate(c.parameters):
            est = Estimate(value=float(v[i]), unit=p.unit, ci_low=float(lo[i]),
                           ci_high=float(hi[i]), std_error=float(se[i]),
                           nominal=float(v_nom[i]))
            if omitted is not None and not c.grid:
                # the dead time keeps its profile interval, as it is
                w_lo, w_hi, by = widened_interval(v[i], se[i], J[i], omitted,
                                                  confidence=confidence)
                est = est.widened(w_lo, w_hi, by)
            elif omitted is not None:
                est = est.widened(est.ci_low, est.ci_high, ())
            entry[p.name] = est.cut(p.phys_lo, p.phys_hi) if truncate else est
        out[n] = entry
    return out


def subsystem_channels(name: str) -> tuple:
    """Block-residual channel indices of the subsystem of a candidate.

    Parameters
    ----------
    name : str
        Candidate name.
    """
    return SUBSYSTEM[REGISTRY[name].subsystem]


__all__ = ["Problem", "make_problem", "at_model", "resample", "bootstrap_frequency",
           "BOOTSTRAP_REPLICATES", "fit_model", "cv_chi2", "gram_fit", "gram_cv", "Step",
           "forward_selection", "refit", "confounded_with", "rank_step", "bic", "aicc",
           "parameter_table", "in_bounds", "hac_covariance", "Stability",
           "stability_selection", "STABILITY_PAIRS", "STABILITY_THRESHOLD",
           "region_consistency", "CONSTANCY_ALPHA", "profiled_shift", "compensating",
           "COMPENSATION_COS",
           "subsystem_channels", "ALPHA", "RHO_MAX", "CV_SEGMENTS"]
