"""Noise level of measured channels, estimated from the data.

Estimator: the **second difference** of a sampled channel,
``d[k] = x[k+1] - 2 x[k] + x[k-1]``, removes a smooth signal (its contribution
is ``x'' dt^2``, a few Pa or micro-radians at 1 kHz for this arm) and
multiplies white measurement noise of variance sigma^2 by 6 (1 + 4 + 1).
The scale of ``d`` is taken robustly as 1.4826 x the median absolute
deviation (MAD, insensitive to the few large second differences at steps of
the signal), so

    sigma_hat = 1.4826 MAD(d) / sqrt(6).

Assumptions a reviewer should know: the noise is white over three samples
and the signal is smooth at the sampling rate (true for q, qd, p of an arm
sampled at 1 kHz: its bandwidth is a few Hz).  Correlated (filtered) sensor
noise is underestimated; quantisation below the noise is ignored.  A
noise-free record gives sigma_hat = 0; callers floor it
(:func:`noise_floor`).
"""

from __future__ import annotations

import numpy as np

from ..._validation import as_float_array

#: Consistency factor of the MAD for a Gaussian.
MAD_GAUSS = 1.4826


def second_difference_sigma(x) -> np.ndarray:
    """Robust white-noise standard deviation of each column of ``x`` (see module docstring).

    Parameters
    ----------
    x : array_like, shape (N,) or (N, k)
        Uniformly sampled channel(s), N >= 5.

    Returns
    -------
    numpy.ndarray, shape () or (k,)
        sigma_hat in the unit of ``x``.
    """
    x = as_float_array("x", x)
    if x.ndim not in (1, 2) or x.shape[0] < 5:
        raise ValueError(f"x must have shape (N,) or (N, k) with N >= 5, got {x.shape}")
    d = x[2:] - 2.0 * x[1:-1] + x[:-2]
    mad = np.median(np.abs(d - np.median(d, axis=0)), axis=0)
    return MAD_GAUSS * mad / np.sqrt(6.0)


def noise_floor(sigma, scale, rel: float = 1e-9) -> np.ndarray:
    """``sigma`` floored at ``rel`` x ``scale`` (a noise-free record must not divide by zero).

    Parameters
    ----------
    sigma : array_like
        Estimated noise standard deviations.
    scale : array_like
        A typical magnitude of each channel (same unit).
    rel : float
        Relative floor.
    """
    sigma = np.asarray(sigma, dtype=float)
    return np.maximum(sigma, rel * np.maximum(np.abs(np.asarray(scale, dtype=float)), 1e-300))


def interpolation_sigma(t, x) -> float:
    """Robust white-noise standard deviation of a channel sampled at arbitrary times.

    The generalisation of :func:`second_difference_sigma` to non-uniform
    sampling: each interior sample is compared with the straight line
    through its two neighbours,
    ``d[k] = x[k] - (w x[k-1] + (1 - w) x[k+1])``, ``w = (t[k+1] - t[k]) /
    (t[k+1] - t[k-1])``, which removes any signal linear in t exactly; white
    noise of variance sigma^2 gives ``var d[k] = sigma^2 (1 + w^2 + (1 - w)^2)``.
    The scale is 1.4826 MAD of ``d[k] / sqrt(1 + w^2 + (1 - w)^2)``.  With
    uniform sampling (w = 1/2) it equals :func:`second_difference_sigma`.

    Parameters
    ----------
    t : array_like, shape (N,)
        Strictly increasing sample times [s], N >= 5.
    x : array_like, shape (N,)
        The channel (any unit).

    Returns
    -------
    float
        sigma_hat in the unit of ``x``.
    """
    t = as_float_array("t", t)
    x = as_float_array("x", x)
    if t.ndim != 1 or t.size < 5 or x.shape != t.shape:
        raise ValueError(f"t and x must be 1-D of equal length >= 5, got shapes {t.shape} "
                         f"and {x.shape}")
    if np.any(np.diff(t) <= 0):
        raise ValueError("t must increase strictly")
    w = (t[2:] - t[1:-1]) / (t[2:] - t[:-2])
    d = (x[1:-1] - (w * x[:-2] + (1.0 - w) * x[2:])) / np.sqrt(1.0 + w ** 2 + (1.0 - w) ** 2)
    return float(MAD_GAUSS * np.median(np.abs(d - np.median(d))))


__all__ = ["second_difference_sigma", "interpolation_sigma", "noise_floor", "MAD_GAUSS"]
