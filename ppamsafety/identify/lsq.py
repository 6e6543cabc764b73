"""Linear least squares with its statistics, and the result object every estimator returns.

The thesis solves every identification problem of §3.5 as an ordinary (or
weighted) linear least-squares problem ``A theta = y`` (Eykhoff 1979)::

    theta_hat = (A^T W A)^-1 A^T W y

:func:`solve` does that with an orthogonal factorisation (``numpy.linalg.lstsq``
on the row-scaled system, never the normal equations) and adds the classical
statistics under the assumption of independent, zero-mean errors in ``y`` with
variance sigma^2 / w_i:

* sigma^2 estimated from the weighted residuals, s^2 = r^T W r / (n - p);
* covariance s^2 (A^T W A)^-1, standard errors its diagonal roots;
* two-sided confidence intervals theta_hat +- t_{1-alpha/2, n-p} SE
  (Student t with n - p degrees of freedom);
* the 2-norm condition number of the column-normalised (scaled) regressor,
  the identifiability measure also used for excitation design (§3.5.2.4).

:class:`LSQResult` carries estimates, standard errors, intervals, covariance,
residuals and units; ``.to_pandas()`` gives one row per parameter, ``.plot()``
(:mod:`ppamsafety.plots.identify`) shows measured vs predicted and the residuals.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from ..results import Result
from .._validation import check_range
from ..plots.identify import plot_fit


def as_samples(name: str, value, *, ncols: int | None = None, ndim: int = 1) -> np.ndarray:
    """Float array of samples with a fixed layout; raise naming ``name`` otherwise.

    Parameters
    ----------
    name : str
        Argument name used in error messages.
    value : array_like
        Input.
    ncols : int, optional
        Required number of columns (``ndim == 2``).
    ndim : int
        Required number of dimensions (1 or 2).

    Returns
    -------
    numpy.ndarray
    """
    if isinstance(value, (str, bytes, dict)) or value is None:
        raise TypeError(f"{name} must be an array of numbers, got {type(value).__name__}")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be an array of numbers, got {type(value).__name__}") from None
    if arr.ndim != ndim:
        want = "(N,)" if ndim == 1 else f"(N, {ncols})"
        raise ValueError(f"{name} must have shape {want}, got {arr.shape}")
    if ndim == 2 and ncols is not None and arr.shape[1] != ncols:
        raise ValueError(f"{name} must have shape (N, {ncols}), got {arr.shape}")
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = np.argwhere(bad)[0]
        raise ValueError(f"{name} contains NaN or inf (first at index {tuple(int(i) for i in idx)})")
    return arr


def same_length(**arrays) -> int:
    """Common first dimension of ``arrays``; ValueError naming the mismatch otherwise.

    Parameters
    ----------
    **arrays : numpy.ndarray
        Arrays by name (the names appear in the error message); at least one.
    """
    items = list(arrays.items())
    n = items[0][1].shape[0]
    for name, a in items[1:]:
        if a.shape[0] != n:
            raise ValueError(f"{name} has {a.shape[0]} samples but {items[0][0]} has {n}")
    return n


@dataclass(frozen=True)
class LSQResult(Result):
    """Estimates of one linear least-squares identification with their statistics.

    Attributes
    ----------
    names : tuple of str
        Parameter names.
    units : tuple of str
        SI unit of each parameter.
    estimates : numpy.ndarray, shape (p,)
        theta_hat.
    std_errors : numpy.ndarray, shape (p,)
        Standard errors sqrt(diag(covariance)).
    covariance : numpy.ndarray, shape (p, p)
        s^2 (A^T W A)^-1.
    ci_low, ci_high : numpy.ndarray, shape (p,)
        Bounds of the two-sided ``confidence`` interval (Student t, n - p dof).
    confidence : float
        Confidence level of the interval (0.95 by default).
    sigma : float
        Estimated standard deviation of a unit-weight equation error, in the
        unit of ``measured``.
    residual_rms : float
        Root mean square of the unweighted residuals ``measured - predicted``.
    condition_number : float
        2-norm condition number of the weighted regressor with columns scaled
        to unit norm.
    dof : int
        Degrees of freedom n - p.
    measured, predicted : numpy.ndarray, shape (n,)
        Right-hand side y and A theta_hat.
    method : str
        ``"LS"`` or ``"WLS"`` plus context.
    quantity : str
        Name and unit of ``measured`` (for plots).
    weights : numpy.ndarray or None, shape (n,)
        Row weights w_i used (None for ordinary LS).
    """

    names: tuple
    units: tuple
    estimates: np.ndarray
    std_errors: np.ndarray
    covariance: np.ndarray
    ci_low: np.ndarray
    ci_high: np.ndarray
    confidence: float
    sigma: float
    residual_rms: float
    condition_number: float
    dof: int
    measured: np.ndarray = field(repr=False)
    predicted: np.ndarray = field(repr=False)
    method: str = "LS"
    quantity: str = "y"
    weights: np.ndarray | None = field(default=None, repr=False)

    @property
    def residuals(self) -> np.ndarray:
        """measured - predicted, unweighted."""
        return self.measured - self.predicted

    @property
    def ci(self) -> np.ndarray:
        """Confidence intervals as an array of shape (p, 2)."""
        return np.stack([self.ci_low, self.ci_high], axis=-1)

    def __getitem__(self, name: str) -> float:
        """Estimate of the parameter called ``name``."""
        try:
            return float(self.estimates[self.names.index(name)])
        except ValueError:
            raise KeyError(f"no parameter {name!r}; parameters are {', '.join(self.names)}") from None

    def as_dict(self) -> dict:
        """{name: estimate}."""
        return {n: float(v) for n, v in zip(self.names, self.estimates)}

    def covers(self, true_values) -> np.ndarray:
        """Boolean per parameter: does its confidence interval contain the true value?

        Parameters
        ----------
        true_values : array_like, shape like ``estimates``
            True parameter values, in the order and units of ``names``/``units``.

        Raises
        ------
        ValueError
            If the shape differs from that of ``estimates``.
        """
        t = np.asarray(true_values, dtype=float)
        if t.shape != self.estimates.shape:
            raise ValueError(f"true_values must have shape {self.estimates.shape}, got {t.shape}")
        return (self.ci_low <= t) & (t <= self.ci_high)

    def to_pandas(self) -> pd.DataFrame:
        """One row per parameter: estimate, std_error, ci_low, ci_high, unit (SI)."""
        pct = f"{100 * self.confidence:g}%"
        df = pd.DataFrame({"estimate": self.estimates, "std_error": self.std_errors,
                           "ci_low": self.ci_low, "ci_high": self.ci_high,
                           "unit": list(self.units)}, index=pd.Index(self.names, name="parameter"))
        df.attrs.update(method=self.method, confidence=pct, sigma=self.sigma,
                        residual_rms=self.residual_rms, condition_number=self.condition_number,
                        dof=self.dof)
        return df

    def plot(self, *, max_points: int = 20000):
        """Measured vs predicted and residuals; returns a matplotlib Figure.

        Parameters
        ----------
        max_points : int, keyword-only
            At most this many (evenly strided) samples are drawn.
        """
        return plot_fit(self, max_points=max_points)


def solve(A, y, *, names, units, weights=None, confidence: float = 0.95,
          method: str = "LS", quantity: str = "y", what: str = "regressor") -> LSQResult:
    """Weighted linear least squares ``A theta = y`` with statistics.

    Parameters
    ----------
    A : numpy.ndarray, shape (n, p)
        Regressor (observation matrix), finite.
    y : numpy.ndarray, shape (n,)
        Right-hand side, finite.
    names, units : sequence of str, keyword-only
        Parameter names and SI units (length p).
    weights : numpy.ndarray, shape (n,), optional
        Positive row weights (inverse error variances up to a common factor).
    confidence : float, keyword-only
        Level of the confidence intervals, in (0, 1).
    method, quantity : str, keyword-only
        Labels stored in the result.
    what : str, keyword-only
        What ``A`` was built from, for error messages.

    Returns
    -------
    LSQResult

    Raises
    ------
    ValueError
        Fewer equations than parameters + 1 or a rank-deficient regressor.
    """
    from scipy import stats

    check_range("confidence", confidence, 0.0, 1.0, lo_open=True, hi_open=True)
    A = np.asarray(A, dtype=float)
    y = np.asarray(y, dtype=float)
    n, p = A.shape
    if n <= p:
        raise ValueError(f"{what}: {n} equations are too few for {p} parameters (need at least {p + 1})")
    if weights is None:
        sw = None
        Aw, yw = A, y
    else:
        weights = np.asarray(weights, dtype=float)
        if weights.shape != (n,) or not np.all(np.isfinite(weights)) or np.any(weights <= 0):
            raise ValueError("weights must be finite and positive, one per equation")
        sw = np.sqrt(weights)
        Aw, yw = A * sw[:, None], y * sw
    scale = np.linalg.norm(Aw, axis=0)
    if np.any(scale == 0.0):
        zero = [names[i] for i in np.flatnonzero(scale == 0.0)]
        raise ValueError(f"{what}: the data do not excite parameter(s) {', '.join(zero)} "
                         "(their regressor column is zero)")
    An = Aw / scale
    U, s, Vt = np.linalg.svd(An, full_matrices=False)
    cond = float(s[0] / s[-1]) if s[-1] > 0 else np.inf
    if not np.isfinite(cond) or cond > 1e12:
        raise ValueError(f"{what}: the regressor is rank deficient (condition number {cond:.3g}); "
                         "the data do not identify all parameters")
    theta_n = Vt.T @ ((U.T @ yw) / s)
    theta = theta_n / scale
    resid_w = yw - Aw @ theta
    dof = n - p
    s2 = float(resid_w @ resid_w) / dof
    inv_n = (Vt.T / s ** 2) @ Vt                   # (An^T An)^-1
    cov = s2 * inv_n / np.outer(scale, scale)
    se = np.sqrt(np.diag(cov))
    tq = float(stats.t.ppf(0.5 + 0.5 * confidence, dof))
    pred = A @ theta
    return LSQResult(names=tuple(names), units=tuple(units), estimates=theta, std_errors=se,
                     covariance=cov, ci_low=theta - tq * se, ci_high=theta + tq * se,
                     confidence=float(confidence), sigma=float(np.sqrt(s2)),
                     residual_rms=float(np.sqrt(np.mean((y - pred) ** 2))),
                     condition_number=cond, dof=dof, measured=y, predicted=pred, method=method,
                     quantity=quantity, weights=weights)


__all__ = ["LSQResult", "solve", "as_samples", "same_length"]
