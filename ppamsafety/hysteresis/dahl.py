"""Dahl presliding friction: the rate-independent friction hysteresis along a sampled path.

The compiled recursion behind the synthetic cylinder campaigns
(:mod:`ppamsafety.diagnose.bench.cylinder_synth`). It is physics, not statistics,
so it lives here, below the diagnosis, among the kernel files of the compiled-kernel
cache key (:data:`ppamsafety._sourcehash.KERNEL_FILES`), not in the diagnosis package it
serves.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import kernel


@kernel
def dahl_path(x, target, x_d, phi0):  # pragma: no cover - compiled
    """Friction along a path: phi relaxes to s * target over the travel scale x_d.

    ``phi[k] = s_k target[k] + (phi[k-1] - s_k target[k]) exp(-|x[k] - x[k-1]| / x_d)``
    with ``s_k`` the sign of the step (kept through standstill): the exponential
    (Dahl, exponent 1) presliding law, exact within monotone pieces whatever
    the step.

    Parameters
    ----------
    x : numpy.ndarray, shape (N,)
        Position [m].
    target : numpy.ndarray, shape (N,)
        Steady sliding friction magnitude [N], >= 0.
    x_d : float
        Presliding length [m], > 0.
    phi0 : float
        Friction at the first sample [N].

    Returns
    -------
    numpy.ndarray, shape (N,)
        Friction opposing the motion, signed along +x [N].
    """
    n = x.size
    out = np.empty(n)
    out[0] = phi0
    s = 1.0 if phi0 >= 0 else -1.0
    for k in range(1, n):
        d = x[k] - x[k - 1]
        if d > 0:
            s = 1.0
        elif d < 0:
            s = -1.0
        a = s * target[k]
        out[k] = a + (out[k - 1] - a) * math.exp(-abs(d) / x_d)
    return out
