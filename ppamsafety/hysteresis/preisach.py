"""The discrete Preisach operator on sampled inputs: response, major loop, W_fit.

Thesis §3.6.3-3.6.4: W[u] = integral over P of mu-tilde(alpha, beta)
gamma_{alpha beta}[u], input u in [-1, 1], output W in [-1, 1], weight (3.33)
(:mod:`.everett`), staircase memory (:mod:`.memory`).  The major loop
(fig. 3.12) is the response to one period of a sine from -1 up to 1 and back;
W_fit is the least-squares straight line through both of its branches.
"""

from __future__ import annotations

import functools

import numpy as np
import pandas as pd

from .._validation import as_float_array, check_int
from .everett import THESIS_WEIGHT, PreisachWeight, check_weight
from .memory import MAX_DEPTH, N_, initial_memory, run, state_length

#: Samples per period used for the thesis W_fit line (see :func:`w_fit`).
W_FIT_SAMPLES = 4000


def preisach_response(u, *, initial="negative", weight: PreisachWeight = THESIS_WEIGHT,
                      capacity: int = MAX_DEPTH, clip: bool = False,
                      state=None, return_state: bool = False):
    """Output W of the Preisach operator for a sampled input sequence.

    Only the sequence of values matters, not their timing (the operator is
    rate independent); between two samples the input is taken monotone.

    Parameters
    ----------
    u : array_like, 1-D
        Scaled input samples, dimensionless, in [-1, 1] (e.g. eps_s of (3.34)).
    initial : {"negative", "positive"} or sequence of float, keyword-only
        Initial memory: negative saturation (default, the thesis' choice),
        positive saturation, or a past input history starting at -1 or +1
        (see :func:`~.memory.initial_memory`).  Ignored when ``state`` is given.
    weight : PreisachWeight, keyword-only
        Weight function (default: thesis (3.33), c = -0.1, d = -1).
    capacity : int, keyword-only
        Maximum stack depth (default :data:`~.memory.MAX_DEPTH`, the plant's).
    clip : bool, keyword-only
        If True, inputs outside [-1, 1] are clipped (the physical meaning:
        contraction beyond the range mapped by (3.34) saturates the model);
        if False (default) they raise ValueError.
    state : numpy.ndarray, optional, keyword-only
        A memory row to start from (e.g. returned earlier with
        ``return_state=True``, same ``weight`` and ``capacity``); it is copied.
    return_state : bool, keyword-only
        Also return the memory row after the last sample.

    Returns
    -------
    numpy.ndarray
        W for every sample, dimensionless, in [-1, 1].
    numpy.ndarray
        The final memory row (only with ``return_state=True``).

    Raises
    ------
    ValueError
        For NaN/inf input, input outside [-1, 1] without ``clip``, or a bad
        ``initial``.
    TypeError
        If ``weight`` is not a :class:`~.everett.PreisachWeight`.
    """
    w = check_weight(weight)
    x = as_float_array("u", u)
    if x.ndim != 1:
        raise ValueError(f"u must be 1-D, got shape {x.shape}")
    if x.size and (x.min() < -1.0 or x.max() > 1.0):
        if not clip:
            raise ValueError(f"u must lie in [-1, 1] (pass clip=True to saturate), got values "
                             f"in [{x.min():g}, {x.max():g}]")
        x = np.clip(x, -1.0, 1.0)
    cap = check_int("capacity", capacity, 2, 10000)
    if state is not None:
        z = as_float_array("state", state).copy()
        if z.shape != (state_length(cap),):
            raise ValueError(f"state must have shape ({state_length(cap)},) for capacity "
                             f"{cap}, got {z.shape}")
        n = z[N_]
        if not (n == int(n) and 1 <= n <= cap):
            raise ValueError(f"state is not a memory row: depth {n!r} outside 1..{cap}")
    else:
        z = initial_memory(initial, weight=w, capacity=cap)
    out = np.empty(x.size)
    run(np.ascontiguousarray(x), z, cap, w.c, w.d, w.inv_z, out)
    return (out, z) if return_state else out


def sine_period(n: int) -> np.ndarray:
    """One period of the major-loop input, u_k = -cos(2 pi k / n), k = 0..n.

    Starts and ends at -1 and passes +1 at k = n/2 (for even n).

    Parameters
    ----------
    n : int
        Samples per period, even, 4..10^7.
    """
    n = check_int("n", n, 4, 10_000_000)
    if n % 2:
        raise ValueError(f"n must be even (so the sine passes +1), got {n}")
    return -np.cos(2.0 * np.pi * np.arange(n + 1) / n)


def major_loop(n: int = 2000, *, weight: PreisachWeight = THESIS_WEIGHT):
    """The major hysteresis loop of fig. 3.12 as a DataFrame.

    Input: one period of a sine, u_k = -cos(2 pi k/n), k = 0..n, from negative
    saturation (-1 up to +1 and back to -1).

    Parameters
    ----------
    n : int
        Samples per period (even), default 2000.
    weight : PreisachWeight, keyword-only
        Weight function (default: thesis (3.33)).

    Returns
    -------
    pandas.DataFrame
        Columns ``phase`` (k/n, fraction of the period), ``u`` (input),
        ``W`` (output), ``branch`` ("ascending" for k <= n/2, else
        "descending") and ``W_fit`` (the line of :func:`w_fit` for the same
        n and weight), all dimensionless.
    """
    u = sine_period(n)
    wv = preisach_response(u, weight=weight)
    slope, intercept = w_fit(n, weight=weight)
    k = np.arange(u.size)
    return pd.DataFrame({"phase": k / n, "u": u, "W": wv,
                         "branch": np.where(k <= n // 2, "ascending", "descending"),
                         "W_fit": slope * u + intercept})


@functools.lru_cache(maxsize=32)
def _w_fit_cached(n: int, weight: PreisachWeight) -> tuple:
    u = sine_period(n)[:-1]        # one full period, each phase once
    wv = preisach_response(u, weight=weight)
    a = np.column_stack([u, np.ones_like(u)])
    (slope, intercept), *_ = np.linalg.lstsq(a, wv, rcond=None)
    return float(slope), float(intercept)


def w_fit(n: int = W_FIT_SAMPLES, *, weight: PreisachWeight = THESIS_WEIGHT) -> tuple:
    """W_fit of (3.35): least-squares straight line through the major loop.

    Both branches of the response to one period of u = -cos(2 pi k/n),
    k = 0..n-1 (uniform in time, as a sampled sine record; §3.6.4: "fitting
    the two major loops generated by W").

    Parameters
    ----------
    n : int
        Samples per period (even), default :data:`W_FIT_SAMPLES`.
    weight : PreisachWeight, keyword-only
        Weight function (default: thesis (3.33)).

    Returns
    -------
    (float, float)
        ``(slope, intercept)``: W_fit(u) = slope * u + intercept, dimensionless.
        For the symmetric weight (3.33) the intercept is 0 up to rounding.
    """
    n = check_int("n", n, 4, 10_000_000)
    return _w_fit_cached(n, check_weight(weight))


__all__ = ["W_FIT_SAMPLES", "major_loop", "preisach_response", "sine_period", "w_fit"]
