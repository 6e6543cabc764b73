"""The replay's limit on a short record: the share of its noisy starting state.

The replay (:mod:`.pipeline`, step 7 of ``docs/diagnose.md``) simulates the fitted model from
the record's *first measured state*, which carries one sample of measurement noise.  The
simulated arm rings from that offset (an angle 1.6 mrad off makes the compliant forearm swing
at several times the velocity noise), and the energy of that transient does not grow with the
record: a correct model's replay RMS over the sample noise is about ``sqrt(1 + tau^2)`` with
``tau^2`` proportional to ``1 / T`` (measured: started from the true state instead, the
replay of a clean 1 s record is at 1.0-1.1 x the noise on every channel; from the measured
state up to 4.6 x on qd2).

:data:`~.pipeline.REPLAY_RHO` was calibrated on the batteries' records, at least
:data:`REPLAY_CALIBRATED_SECONDS` long, whose null statistic already holds their own
transient.  A shorter record widens the limit by the part of its transient those records did
not hold, computed for the record itself:

* the replay's response to each of the 8 starting values (q, qd, p) offset by one sample-noise
  standard deviation (8 more replays in the same batched call), ``S_k(t)``; the starting
  error is Gaussian and small, so the transient is ``sum_k S_k(t) z_k``, ``z ~ N(0, I)``;
* per channel ``c``, ``tau_c^2 = z' M_c z`` with ``M_c = S_c' S_c / (N sigma_c^2)``: a weighted
  sum of chi-square(1) variables (weights: the eigenvalues of ``M_c``), whose
  :data:`START_QUANTILE` quantile ``q_c`` is taken from :data:`START_DRAWS` seeded draws;
* records of length ``T' >= T_cal`` held at most ``q_c T / T_cal`` of it (``tau^2 ~ 1/T``),
  so the limit is ``sqrt(REPLAY_RHO^2 + q_c max(0, 1 - T / T_cal))``: the calibrated limit
  for every record at least ``T_cal`` long (the batteries' rows are unchanged), wider below.
"""

from __future__ import annotations

import math

import numpy as np

from .residuals import replay

#: The shortest record the replay's limit was calibrated on [s]: the batteries' open-loop
#: records are 8-40 s, their closed-loop records 10-30 s
#: (:func:`ppamsafety.diagnose.scenarios.random_scenario`).
REPLAY_CALIBRATED_SECONDS = 8.0
#: Quantile of the starting state's share of a correct model's replay statistic.
START_QUANTILE = 0.99
#: Monte-Carlo draws of that share (of 8 chi-square(1) variables; cheap).
START_DRAWS = 20000


def start_spread(rec, row, x0, sigma, *, measure=None, seed: int = 0,
                 quantile: float = START_QUANTILE) -> np.ndarray:
    """Per replay channel, the ``quantile`` of ``tau^2``: the replay's squared RMS error over
    the sample noise that the noise of its starting state alone causes (module docstring).

    Parameters
    ----------
    rec : ArmRecord
        The record (its set values and length).
    row : numpy.ndarray, shape (NP,)
        The packed plant row replayed.
    x0 : numpy.ndarray, shape (8,)
        The starting state [q (rad), qd (rad/s), p (Pa)] of the replay.
    sigma : numpy.ndarray, shape (8,)
        Sample noise of q1, q2 [rad], qd1, qd2 [rad/s], p1..p4 [Pa] (the starting state's
        error and the channels' scale).
    measure : callable, optional
        The replayed states as measured (the fitted sensor faults), (N, 8) -> (N, 8).
    seed : int, keyword-only
        Seed of the Monte-Carlo draws.
    quantile : float, keyword-only

    Returns
    -------
    numpy.ndarray, shape (8,)
        ``q_c`` per channel (dimensionless, a square of a ratio to the noise).
    """
    x0 = np.asarray(x0, dtype=float)
    sigma = np.asarray(sigma, dtype=float)
    starts = np.vstack([x0, x0 + np.diag(sigma)])
    X = replay(rec, np.repeat(np.asarray(row, dtype=float)[None, :], 9, axis=0),
               shifts=[0] * 9, x0=starts)
    if measure is not None:
        X = np.stack([measure(x) for x in X])
    S = X[1:] - X[0]                                  # (8 starting values, N, 8 channels)
    n = S.shape[1]
    z2 = np.random.default_rng(seed).standard_normal((START_DRAWS, 8)) ** 2
    out = np.zeros(8)
    for c in range(8):
        if not sigma[c] > 0:
            continue
        A = S[:, :, c].T / sigma[c]                   # (N, 8)
        lam = np.clip(np.linalg.eigvalsh(A.T @ A / n), 0.0, None)
        out[c] = float(np.quantile(z2 @ lam, quantile))
    return out


def widened_limit(limit: float, spread: float, seconds: float) -> float:
    """The replay limit of one channel of a record ``seconds`` long (module docstring).

    Parameters
    ----------
    limit : float
        The calibrated limit (:data:`~.pipeline.REPLAY_RHO`).
    spread : float
        ``q_c`` of :func:`start_spread`.
    seconds : float
        The record's length [s].

    Returns
    -------
    float
        ``sqrt(limit^2 + spread max(0, 1 - seconds / REPLAY_CALIBRATED_SECONDS))``.
    """
    share = max(0.0, 1.0 - seconds / REPLAY_CALIBRATED_SECONDS)
    return math.sqrt(limit ** 2 + max(float(spread), 0.0) * share)


__all__ = ["start_spread", "widened_limit", "REPLAY_CALIBRATED_SECONDS", "START_QUANTILE",
           "START_DRAWS"]
