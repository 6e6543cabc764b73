"""Static gravity compensation (thesis §3.5.1.5, eqs. (3.18)-(3.19)).

Delta p_gc makes the muscle torques (Delta-p approach with the mean
pressures p_m) balance the *identified* gravity torques K(q) theta_hat
(Table 3.1) through the identified torque functions (B.2).  The runner then
turns the desired pressures into valve set values with the inverse of the
static valve model (3.12), as the thesis does.

It is a feedforward term evaluated at the **desired** angles q_d (§3.5.1.5
validates it by stepping the *set* angles; chapter 5 uses it "as a
feedforward term").  Evaluated at the measured angles it would make every
configuration a neutral equilibrium, and any model error a slow drift.
"""

from __future__ import annotations

import numpy as np

from .._jit import leaf
from ..plant.pneumatics import gravity_compensation_dp
from .base import KIND_GC, Controller


@leaf
def add_gravity_compensation(use, Pm, ref, dp, scratch):
    """Add Delta p_gc(q_d) to ``dp`` in place if ``use`` > 0.5 (``scratch`` >= 12 floats).

    ``ref`` is the reference row; its first two entries are q_d [rad].
    """
    if use > 0.5:
        g1, g2 = gravity_compensation_dp(ref[0], ref[1], Pm, scratch[0:4], scratch[4:8],
                                         scratch[8:12])
        dp[0] += g1
        dp[1] += g2


@leaf
def gc_step(Pm, ref, dp_out, scratch):
    """Delta p_gc at the desired angles (feedforward only)."""
    dp_out[0] = 0.0
    dp_out[1] = 0.0
    add_gravity_compensation(1.0, Pm, ref, dp_out, scratch)


class GravityCompensation(Controller):
    """Open-loop static gravity compensation (no feedback)."""

    kind = KIND_GC
    name = "gravity compensation"

    def pack(self) -> np.ndarray:
        return np.zeros(1)
