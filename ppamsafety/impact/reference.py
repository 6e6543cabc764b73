"""Reference impact solution with scipy's adaptive integrator (one call per impact).

Same model as :mod:`ppamsafety.impact.engine` (its compiled right-hand side),
integrated by :func:`scipy.integrate.solve_ivp` with tight tolerances and
sampled on the same uniform grid for the HIC.  Used to cross-check the fixed
step integrator and as the baseline of the batch-speed benchmark.
"""

from __future__ import annotations

import math

import numpy as np

from ..params.head import head_model
from ..plant import geometry as geo
from ..plant import layout as lay
from ..units import G0
from . import engine as eng
from .hic import hic


def simulate_impact_scipy(arm, q, qd, stiffness, *, head=None, method: str = "RK45",
                          rtol: float = 1e-9, atol: float = 1e-12, dt: float = 2e-5,
                          duration: float = 0.05) -> dict:
    """One impact by ``solve_ivp``; returns F_max [N], HIC36, HIC15, delta_max [m].

    Parameters as :func:`ppamsafety.impact.model.simulate_impacts` for a single
    case (tool velocity direction, head at rest); ``dt`` is the output grid.
    """
    from scipy.integrate import solve_ivp

    hm = head_model() if head is None else (head_model(head) if isinstance(head, str) else head)
    q = np.asarray(q, dtype=float)
    qd = np.asarray(qd, dtype=float)
    v = geo.jacobian(q, arm) @ qd
    case = eng.pack_cases(1, q=q, qd=qd, K=stiffness, u=v / np.linalg.norm(v),
                          v_head=0.0, arm_mode=int(eng.ArmMode.FLEXIBLE))[0]
    P = np.array(lay.pack(arm))
    hp = eng.pack_head(hm)
    y0 = np.empty(eng.NY)
    eng.initial_state(case, P, hp, y0)
    dy = np.empty(eng.NY)

    def rhs(t, y):
        eng.impact_rhs(y, case, P, hp, dy)
        return dy.copy()

    n = int(math.ceil(duration / dt - 1e-9))
    t = np.arange(n + 1) * dt
    sol = solve_ivp(rhs, (0.0, t[-1]), y0, method=method, t_eval=t, rtol=rtol, atol=atol)
    F = np.empty(n + 1)
    delta = np.empty(n + 1)
    for i in range(n + 1):
        F[i], delta[i], _, _ = eng.impact_rhs(sol.y[:, i], case, P, hp, dy)
    a = F / (hm.mass * G0)
    return {"F_max": float(F.max()), "HIC36": hic(a, dt).value,
            "HIC15": hic(a, dt, window=0.015).value, "delta_max": float(delta.max()),
            "nfev": int(sol.nfev)}
