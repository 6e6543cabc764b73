"""Are a named effect's parameters the same early and late in a muscle record?

A real effect has one value for the whole record; an effect standing in for
something that changes with time does not.  The commonest case on a bench is
a load cell whose zero drifts while it warms up: when the pressure levels are
visited in increasing order, a force growing with time also grows with the
pressure, and a refitted force law (or a pressure-sensor offset) takes it.
The final model is refitted on the first and on the second half of the
equations in time (disjoint, so independent), and the Wald statistic
``(phi_1 - phi_2)^T (C_1 + C_2)^+ (phi_1 - phi_2)`` of the effect's
coefficients is referred to chi2 with as many degrees of freedom as the rank of
``C_1 + C_2`` (a Chow test; the arm's region-consistency test,
:func:`ppamsafety.diagnose.arm.selection.region_consistency`, across time
instead of across the arm's poses).  The gate ``consistent`` of :mod:`.gates`
needs p >= :data:`CONSTANCY_ALPHA`.
"""

from __future__ import annotations

import numpy as np

from ..core.criteria import _chi2_sf
from ..core.gates import CONSTANCY_ALPHA
from ..core.linear_selection import LinearGram
from ..core.solve import pinv_psd



def time_consistency(design, names, name: str) -> float:
    """p-value of the equality of ``name``'s coefficients in the two halves of the record.

    Parameters
    ----------
    design : ActuatorDesign
    names : sequence of str
        The final model.
    name : str
        One of ``names``.

    Returns
    -------
    float
        1.0 where a half is too small to fit the model.
    """
    names = list(names)
    m = design.m
    k = sum(design.columns[n].shape[1] for n in names)
    half = np.arange(m) < m // 2
    if min(int(half.sum()), int((~half).sum())) < 3 * max(k, 1):
        return 1.0
    cols = {n: design.columns[n] for n in names}
    fits = [LinearGram(design.e0, cols, mask=h).fit(names) for h in (half, ~half)]
    sl = fits[0].slices[name]
    d = fits[0].phi[sl] - fits[1].phi[sl]
    Ci, rank = pinv_psd(fits[0].cov[sl, sl] + fits[1].cov[sl, sl], rank=True)
    if rank == 0:
        return 1.0
    return _chi2_sf(max(float(d @ Ci @ d), 0.0), rank)


__all__ = ["time_consistency", "CONSTANCY_ALPHA"]
