"""Hysteretic force factor of the PPAM (thesis §3.6.4, eqs. (3.34)-(3.35)).

::

    F_hyst = p l0^2 f_fit(eps) (1 + delta (W[eps_s] - W_fit(eps_s)))      (3.35)
    eps_s  = 2 eps / eps_max - 1,  eps_max = 0.35                          (3.34)

The plant multiplies its nominal muscle force p f(eps) by
:func:`hysteresis_factor`; ``delta`` is a per-muscle scale, fitted by least
squares from a tensile test (:mod:`.tensile`).
"""

from __future__ import annotations

import numpy as np

from .._jit import leaf
from .._validation import as_float_array, check_range

#: eps_max of (3.34): the contraction mapped to eps_s = +1 (thesis §3.6.4: "35%").
EPS_MAX = 0.35

#: delta for the 25-fibre muscles of the arm, fitted at 1.5 bar (thesis §3.6.5, "delta ~ 0.139").
DELTA_25_FIBRES = 0.139
#: delta for the 40-fibre test muscle, fitted at 1.5 bar (thesis §3.6.5, "delta ~ 0.299").
DELTA_40_FIBRES = 0.299


@leaf
def scaled_contraction(eps, eps_max):
    """eps_s = 2 eps/eps_max - 1 (3.34), clipped to [-1, 1] (dimensionless).

    Parameters
    ----------
    eps : float
        Muscle contraction [-] (0.1 = 10 %).
    eps_max : float
        Contraction mapped to eps_s = +1 [-] (:data:`EPS_MAX` = 0.35 in the
        thesis, §3.6.4); must be nonzero.
    """
    e = 2.0 * eps / eps_max - 1.0
    if e > 1.0:
        return 1.0
    if e < -1.0:
        return -1.0
    return e


@leaf
def hysteresis_factor(delta, w, eps_s, wfit_a, wfit_b):
    """1 + delta (W - W_fit(eps_s)), the factor of (3.35) on p l0^2 f_fit(eps).

    ``w`` is the Preisach output W[eps_s], ``wfit_a``/``wfit_b`` the slope and
    intercept of W_fit (:func:`~.preisach.w_fit`).  Dimensionless.

    Parameters
    ----------
    delta : float
        Per-muscle hysteresis scale delta of (3.35) [-] (e.g.
        :data:`DELTA_25_FIBRES`).
    w : float
        Preisach output W[eps_s] in [-1, 1] [-], e.g. from
        :func:`~.memory.preisach_peek`.
    eps_s : float
        Scaled contraction of (3.34) in [-1, 1] [-]
        (:func:`scaled_contraction`).
    wfit_a, wfit_b : float
        Slope and intercept of the straight line W_fit(eps_s) = a eps_s + b
        [-].
    """
    return 1.0 + delta * (w - (wfit_a * eps_s + wfit_b))


def scaled_input(eps, eps_max: float = EPS_MAX) -> np.ndarray:
    """eps_s of (3.34) for an array of contractions, clipped to [-1, 1].

    Parameters
    ----------
    eps : array_like
        Muscle contraction, dimensionless (0.1 = 10 %).
    eps_max : float
        Contraction mapped to +1, in (0, 1]; default 0.35 (§3.6.4).

    Returns
    -------
    numpy.ndarray
        eps_s in [-1, 1]; contractions below 0 or above ``eps_max`` saturate.
    """
    e = as_float_array("eps", eps)
    em = check_range("eps_max", eps_max, 0.0, 1.0, lo_open=True)
    return np.clip(2.0 * e / em - 1.0, -1.0, 1.0)


__all__ = ["DELTA_25_FIBRES", "DELTA_40_FIBRES", "EPS_MAX", "hysteresis_factor",
           "scaled_contraction", "scaled_input"]
