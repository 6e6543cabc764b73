"""The motion of a bench record: smoothed position, speed, reversals, strokes and cycles.

Friction candidates of a cylinder (:mod:`.friction`) need, for every sample,
the direction of motion ``s`` (+1 while the rod extends, -1 while it is pushed
in), the speed ``v`` [m/s], the travel since the last reversal ``dx`` [m] (the
presliding state) and the stroke and cycle it belongs to (the clusters of the
statistics and the folds of the cross-validation).  :func:`stroke_state`
computes them from the measured position:

* a time-aware local quadratic fit over +-h samples gives the smoothed
  position and the speed (the sampling of a software-timed logger is not
  uniform: the fit uses the actual times), h chosen so that the window
  spans about 40 position noise levels of travel;
* the direction comes from a dead-band reversal detector on the smoothed
  position (:func:`~.pipeline.motion_direction`, dead band 12 noise levels),
  switching exactly at the position extremum; samples within 3 noise
  levels of a turning point have an ambiguous direction and are flagged;
* a stroke runs from one reversal to the next; a cycle is two strokes; the
  samples before the first reversal of a record (whose presliding state is
  unknown) are flagged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.noise import interpolation_sigma
from .design import motion_direction

#: Dead band of the reversal detector, in position noise levels.
REVERSAL_SIGMAS = 12.0
#: Travel across the smoothing window, in position noise levels.
WINDOW_SIGMAS = 40.0
#: Samples within this many position noise levels of a turning point have an ambiguous
#: direction of motion (left out of the statistics).
AMBIGUOUS_SIGMAS = 3.0


@dataclass(frozen=True, eq=False)
class StrokeState:
    """Per-sample motion of one record (module docstring).

    Attributes
    ----------
    x : numpy.ndarray
        Smoothed position [m].
    v : numpy.ndarray
        Speed [m/s].
    s : numpy.ndarray of int
        Direction of motion (+1 the working coordinate grows, -1 it falls, 0
        before any motion).
    dx : numpy.ndarray
        Travel since the last reversal [m] (inf before the first).
    stroke : numpy.ndarray of int
        Stroke index within the record (-1 before the first reversal).
    cycle : numpy.ndarray of int
        Cycle index (stroke // 2; -1 before the first reversal).
    sigma_x : float
        Position noise [m].
    reversals : int
        Reversals detected.
    half_window : int
        Half-width of the smoothing window [samples].
    ambiguous : numpy.ndarray of bool
        Samples within :data:`AMBIGUOUS_SIGMAS` position noise levels of a
        turning point (direction ambiguous).
    """

    x: np.ndarray
    v: np.ndarray
    s: np.ndarray
    dx: np.ndarray
    stroke: np.ndarray
    cycle: np.ndarray
    sigma_x: float
    reversals: int
    half_window: int
    ambiguous: np.ndarray = None


def local_quadratic(t, x, h: int) -> tuple:
    """Value and slope of a least-squares quadratic over samples k-h..k+h (actual times).

    The window is shifted inward at the ends.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Strictly increasing times [s].
    x : numpy.ndarray, shape (N,)
        The signal.
    h : int
        Half-width [samples], >= 1; N >= 2h + 1.

    Returns
    -------
    value, slope : numpy.ndarray, shape (N,)
    """
    n = x.size
    lo = np.clip(np.arange(n) - h, 0, max(n - 2 * h - 1, 0))
    idx = lo[:, None] + np.arange(min(2 * h + 1, n))[None, :]
    tt = t[idx] - t[:, None]
    sc = float(np.max(np.abs(tt))) or 1.0
    tt = tt / sc
    P = np.stack([np.ones_like(tt), tt, tt * tt], axis=2)
    A = np.einsum("nwi,nwj->nij", P, P)
    b = np.einsum("nwi,nw->ni", P, x[idx])
    c = np.linalg.solve(A + 1e-12 * np.eye(3), b[..., None])[..., 0]
    return c[:, 0], c[:, 1] / sc


def stroke_state(t, x, segments) -> StrokeState:
    """The motion of one record (module docstring).

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        Times [s] (gaps allowed between segments).
    x : numpy.ndarray, shape (N,)
        Measured position along the working stroke [m] (despiked).
    segments : sequence of (int, int)
        Gap-free row ranges; smoothing never crosses a gap.

    Returns
    -------
    StrokeState
    """
    n = x.size
    sig = np.median([interpolation_sigma(t[a:b], x[a:b]) for a, b in segments if b - a >= 5])
    sig = max(float(sig), 1e-9 * max(float(np.ptp(x)), 1e-6))
    inc = float(np.median(np.abs(np.diff(x)))) if n > 1 else 0.0
    inc = max(inc, 1e-300)
    h = int(np.clip(math.ceil(0.5 * WINDOW_SIGMAS * sig / inc), 2, 25))
    xs, v = np.array(x, float), np.zeros(n)
    for a, b in segments:
        if b - a >= 2 * h + 1:
            xs[a:b], v[a:b] = local_quadratic(t[a:b], x[a:b], h)
        elif b - a >= 3:
            v[a:b] = np.gradient(x[a:b], t[a:b])
    thr = REVERSAL_SIGMAS * sig
    s = motion_direction(xs, thr, 0.5 * thr)
    turns = np.flatnonzero((s[1:] != s[:-1]) & (s[1:] != 0) & (s[:-1] != 0))
    dx = np.full(n, np.inf)
    to_next = np.full(n, np.inf)
    stroke = np.full(n, -1)
    prev = 0
    for i, k in enumerate(turns):                  # k: the extremum (last of the old direction)
        end = turns[i + 1] + 1 if i + 1 < turns.size else n
        dx[k + 1:end] = np.abs(xs[k + 1:end] - xs[k])
        stroke[k + 1:end] = i
        to_next[prev:k + 1] = np.abs(xs[prev:k + 1] - xs[k])
        prev = k + 1
    cycle = np.where(stroke >= 0, stroke // 2, -1)
    # the direction of the samples within a few noise levels of a turning point is ambiguous
    # (the extremum of the smoothed position is known to about its noise)
    band = AMBIGUOUS_SIGMAS * sig
    ambiguous = (dx < band) | (to_next < band)
    return StrokeState(x=xs, v=v, s=s, dx=dx, stroke=stroke, cycle=cycle, sigma_x=sig,
                       reversals=int(turns.size), half_window=h, ambiguous=ambiguous)


__all__ = ["StrokeState", "stroke_state", "local_quadratic", "REVERSAL_SIGMAS", "WINDOW_SIGMAS",
           "AMBIGUOUS_SIGMAS"]
