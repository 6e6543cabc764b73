"""Contact layers in series: one shared force through the covering, the tissue and the bone.

A contact is a stack of layers in series (:mod:`ppamsafety.params.contact`): the robot's
covering, then the body's soft tissue and bone.  They carry **one force**.  Given the total
compression delta (the overlap of the undeformed surfaces), the layers split it so that each
carries the same elastic force::

    F_el = k_i delta_i^n_i   for every layer i that has not bottomed out,
    delta_i = limit_i        for a layer that has (it is rigid beyond its limit),
    sum_i delta_i = delta.

This is an algebraic solve at every evaluation, not a state: a safeguarded Newton iteration on
ln F_el between rigorous brackets (:func:`stack_eval`; the compressions of the layers add up
to delta within 1e-13 relative, about four iterations from the previous evaluation's force;
it never divides 0 by 0: at first touch delta = 0 the force is 0 without a solve).  The elastic
potential of the stack is V(delta) = sum_i k_i delta_i^(n_i+1)/(n_i+1), and dV/d(delta) = F_el
exactly (each layer's force is F_el), so the elastic part is conservative.

Damping.  Each layer carries a Hunt-Crossley hysteresis factor alpha_i = b_i / k_i [s/m].  In a
stack they act through one factor on the shared force::

    F = max(F_el(delta) (1 + alpha_eff delta_dot), 0),   alpha_eff = sum_i w_i^2 alpha_i,
    w_i = (d delta_i / d F) / sum_j (d delta_j / d F)      (the layers' share of the compliance:
          a rate delta_dot moves layer i by w_i delta_dot when the layers follow the force)

Layer i's damping force F_el alpha_i w_i delta_dot acts through its own rate w_i delta_dot,
so it dissipates F_el alpha_i (w_i delta_dot)^2: summed, the power (F - F_el) delta_dot of the
factor above, which is booked to layer i in the share w_i^2 alpha_i / alpha_eff.  This is the
damping of dashpots in series to first order in the damping (Kelvin-Voigt elements in series:
K x + sum w_i^2 C_i x_dot on the slow manifold), exact for identical layers.  So the force is
never negative, is 0 at first touch (F_el(0) = 0, no jump), the dissipated power is >= 0, and
kinetic energy in = kinetic out + what each layer dissipated + the potential still stored.
With one layer this *is* the Hunt-Crossley law of thesis eq. (6.2), evaluated by the same
compiled function (:func:`~ppamsafety.impact.contact.hunt_crossley_force`), so a bare robot
with a one-layer body reproduces the single-layer engine bit for bit.  When the layers share
one exponent and none bottoms out, the shares w_i are constant, the stack's elastic law is
one power law and alpha_eff one constant: the Hunt-Crossley phase-plane invariant holds for
the stack, mu [v/alpha_eff - ln(1 + alpha_eff v)/alpha_eff^2] + V(delta) = const
(:func:`phase_plane_max_compression`).  docs/impact_models.md compares the factor with the
layers as dashpots in series and a massless interface (:func:`two_body_dashpots`).

Geometry.  A material law's stiffness follows from the contact's effective radius
R_e = sqrt(R_1 R_2), with 1/R_1 = 1/R_body + 1/r_1 and 1/R_2 = 1/R_body + 1/r_2 (R_body the
body's radius of curvature, r_1, r_2 the robot surface's principal radii,
:attr:`~ppamsafety.params.contact.ContactPoint.radii`); for a Winkler layer this is exact for
an elliptic contact, for Hertz the usual equivalent-sphere approximation (Johnson 1985, §4.2).

Contact area and pressure.  The contact area at a total compression delta is taken as that of
Hertz's rigid-indenter relation, A = pi a^2 with a^2 = R_e delta, and the pressure reported is
the mean pressure F / A (:func:`contact_area`).  For a thin layer the footprint is up to twice
larger (a^2 = 2 R_e delta), so the pressure is an upper estimate there; against a flat robot
face and a flat body (R_e infinite) no area follows and no pressure is reported.

Data layout (:mod:`ppamsafety.layouts`): :data:`STACK` (the stack as a kernel row,
:func:`pack_stack`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from .._jit import kernel, kernel_array, leaf
from .._validation import (as_float_array, check_finite_result, check_instance, check_range,
                           check_range_array)
from ..layouts import Field, Layout
from ..params.contact import BARE, BodyContact, ContactPoint, Covering, Layer
from ..units import G0
from .contact import hunt_crossley_elastic, hunt_crossley_force, hunt_crossley_potential
from .hic import hic_pair_kernel

#: Layers of a stack row (covering and body together); equals
#: :data:`ppamsafety.params.contact.MAX_LAYERS` (a kernel constant, so written here: the
#: kernels read no parameter module).
NL = 4

# ---- declared layout ----------------------------------------------------------------------
#: A contact stack as a kernel row: covering layers first, then the body's, outermost first.
STACK = Layout("contact stack", [
    Field("n_layers", 1, "-", "number of layers in series (covering + body), 1..4"),
    Field("n_covering", 1, "-", "how many of them (the first) are the robot's covering"),
    Field("k", NL, "N/m^n", "elastic stiffness of each layer (F = k delta^n)"),
    Field("n", NL, "-", "elastic exponent of each layer"),
    Field("b", NL, "N s/m^(n+1)", "Hunt-Crossley damping of each layer (b = alpha k)"),
    Field("limit", NL, "m", "compression at which each layer bottoms out (inf: never)"),
    Field("lnk", NL, "-", "ln k of each layer (the solve works on ln F)"),
    Field("inv_n", NL, "-", "1 / n of each layer"),
    Field("alpha", NL, "s/m", "hysteresis factor b / k of each layer"),
    Field("mass", 1, "kg", "effective mass of the body region"),
    Field("radius", 1, "m", "radius of the body surface (where its centre starts)"),
    Field("area_factor", 1, "m", "pi R_e: contact area A = pi R_e delta (inf: none)"),
])
(S_NL, S_NC, S_K, S_N, S_B, S_LIM, S_LNK, S_INVN, S_ALPHA, S_M, S_R, S_AF) = STACK.offsets(
    "n_layers", "n_covering", "k", "n", "b", "limit", "lnk", "inv_n", "alpha", "mass",
    "radius", "area_factor")
NSTACK = STACK.size
#: Length of the work array of :func:`stack_eval`: compressions, weights, warm start.
NWORK = 2 * NL + 1
#: Index of the warm start (ln F of the last solve) in the work array.
W_HINT = 2 * NL


# ---- geometry and packing ---------------------------------------------------------------
def effective_radius(body_radius: float, radii) -> float:
    """Effective radius R_e = sqrt(R_1 R_2) of a body against a robot surface [m].

    Parameters
    ----------
    body_radius : float
        Radius of curvature of the body surface [m] (> 0; ``inf``: flat).
    radii : (float, float)
        Principal radii of the robot surface [m] (``inf``: flat in that direction).

    Returns
    -------
    float
        R_e [m]; ``inf`` when both surfaces are flat in some direction pair.
    """
    cb = 0.0 if body_radius == math.inf else 1.0 / body_radius
    out = 1.0
    for r in radii:
        c = cb + (0.0 if r == math.inf else 1.0 / r)
        if c == 0.0:
            return math.inf
        out *= 1.0 / c
    return math.sqrt(out)


def layer_law(layer: Layer, re: float) -> tuple:
    """(k, n, b, limit) of a layer at the effective radius ``re`` [m] (module docstring).

    Parameters
    ----------
    layer : Layer
        The layer.
    re : float
        Effective radius of the contact [m] (must be finite for a material law).

    Returns
    -------
    tuple of float
        Stiffness k [N/m^n], exponent n, Hunt-Crossley b [N s/m^(n+1)], bottoming limit [m].
    """
    layer = check_instance("layer", layer, Layer)
    if layer.law == "power":
        return layer.stiffness, layer.exponent, layer.damping, layer.limit
    if not math.isfinite(re):
        raise ValueError(f"layer {layer.name!r} ({layer.law} law) needs a curved contact: a flat "
                         f"robot face against a flat body has no effective radius; give the "
                         f"body a radius or the contact point a curved shape")
    if layer.law == "thin-layer":
        k, n = math.pi * layer.modulus * re / layer.thickness, 2.0
    else:                                              # hertz
        k, n = 4.0 / 3.0 * layer.modulus / (1.0 - layer.poisson ** 2) * math.sqrt(re), 1.5
    return k, n, layer.hysteresis * k, layer.limit


def pack_stack(covering: Covering, body: BodyContact, radii=(math.inf, math.inf)) -> np.ndarray:
    """The :data:`STACK` row of a covering on a robot surface against a body.

    Parameters
    ----------
    covering : Covering
        The robot's covering (``BARE``: none).
    body : BodyContact
        The body region's contact model.
    radii : (float, float)
        Principal radii of the robot surface [m] (default flat).

    Returns
    -------
    numpy.ndarray, shape (STACK.size,)
    """
    covering = check_instance("covering", covering, Covering)
    body = check_instance("body", body, BodyContact)
    layers = covering.layers + body.layers
    if len(layers) > NL:
        raise ValueError(f"covering {covering.name!r} ({len(covering.layers)} layers) and body "
                         f"{body.name!r} ({len(body.layers)} layers) make {len(layers)} layers; "
                         f"at most {NL} in series")
    re = effective_radius(body.radius, radii)
    row = np.zeros(NSTACK)
    row[S_NL], row[S_NC] = len(layers), len(covering.layers)
    for i in range(NL):
        if i < len(layers):
            k, n, b, lim = layer_law(layers[i], re)
        else:
            k, n, b, lim = 1.0, 1.0, 0.0, math.inf
        if not (0.0 < k < 1e25 and math.isfinite(b)):
            raise ValueError(f"layer {layers[i].name!r} gives a stiffness k = {k:g} outside (0, "
                             f"1e25) at the effective radius {re:g} m")
        row[S_K + i], row[S_N + i], row[S_B + i], row[S_LIM + i] = k, n, b, lim
        row[S_LNK + i], row[S_INVN + i], row[S_ALPHA + i] = math.log(k), 1.0 / n, b / k
    row[S_M], row[S_R] = body.mass, body.radius
    row[S_AF] = math.pi * re
    return row


def contact_area(delta, re: float):
    """Contact area A = pi R_e delta [m^2] at the total compression ``delta`` [m] (module docstring).

    Parameters
    ----------
    delta : float or array_like
        Total compression [m] (<= 0: no contact, area 0).
    re : float
        Effective radius [m].
    """
    d = np.asarray(delta, dtype=float)
    return np.pi * re * np.maximum(d, 0.0)


# ---- the law, compiled ---------------------------------------------------------------------
@leaf
def stack_eval(delta, ddelta, S, work):
    """Force of a stack at total compression ``delta`` [m] and its rate [m/s].

    Returns ``(F, F_el, alpha_eff, V)``: the contact force [N] (>= 0), its elastic part [N],
    the stack's hysteresis factor [s/m] and the elastic potential [J].  Fills ``work[:L]``
    with the layers' compressions [m] and ``work[NL:NL + L]`` with their shares of the
    dissipated power, w_i^2 alpha_i / alpha_eff (sum 1; all 0 without damping);
    ``work[W_HINT]`` holds ln F_el of the last solve (a warm start; NaN: none).
    A one-layer stack that cannot bottom out is the Hunt-Crossley law itself (same compiled
    functions, same arithmetic).

    Parameters
    ----------
    delta, ddelta : float
        Total compression [m] (<= 0: no contact) and its rate [m/s].
    S : ndarray of float64, shape (NSTACK,)
        The stack row (:data:`STACK`).
    work : ndarray of float64, shape (NWORK,)
        Work array (read: the warm start; written as above).
    """
    nl = int(S[S_NL])
    if delta <= 0.0:
        for i in range(2 * NL):
            work[i] = 0.0
        return 0.0, 0.0, 0.0, 0.0
    if nl == 1 and S[S_LIM] == math.inf:
        k, n, b = S[S_K], S[S_N], S[S_B]
        work[0] = delta
        work[NL] = 1.0
        return (hunt_crossley_force(delta, ddelta, k, n, b), hunt_crossley_elastic(delta, k, n),
                S[S_ALPHA], hunt_crossley_potential(delta, k, n))
    # brackets of u = ln F_el: all the compression in one unlimited layer gives an upper
    # bound; a 1/nl share in every layer a lower one (module docstring)
    lnd = math.log(delta)
    lnl = math.log(nl)
    uhi = math.inf
    ulo = math.inf
    for i in range(nl):
        a = S[S_LNK + i] + S[S_N + i] * lnd
        if S[S_LIM + i] == math.inf and a < uhi:
            uhi = a
        c = S[S_LNK + i] + S[S_N + i] * (lnd - lnl)
        if c < ulo:
            ulo = c
    u = work[W_HINT]
    if not (ulo <= u <= uhi):
        u = uhi
    for _ in range(200):
        s = 0.0
        ds = 0.0
        for i in range(nl):
            di = math.exp((u - S[S_LNK + i]) * S[S_INVN + i])
            lim = S[S_LIM + i]
            if di >= lim:
                di = lim
            else:
                ds += di * S[S_INVN + i]
            work[i] = di
            s += di
        h = s - delta
        if abs(h) <= 1e-13 * delta:
            break
        if h > 0.0:
            uhi = u
        else:
            ulo = u
        tol = 1e-14 * max(1.0, abs(u))
        if uhi - ulo <= tol:
            break
        un = u - h / ds
        if not (ulo < un < uhi):
            un = 0.5 * (ulo + uhi)
        if abs(un - u) <= tol:
            break
        u = un
    work[W_HINT] = u
    fel = math.exp(u)
    v = 0.0
    csum = 0.0
    for i in range(nl):
        di = work[i]
        n = S[S_N + i]
        if di >= S[S_LIM + i]:
            v += S[S_K + i] * di ** (n + 1.0) / (n + 1.0)
            work[NL + i] = 0.0
        else:
            v += fel * di / (n + 1.0)
            c = di * S[S_INVN + i]
            work[NL + i] = c
            csum += c
    # alpha_eff = sum w_i^2 alpha_i: layer i moves at w_i d(delta)/dt and its damping force
    # F_el alpha_i w_i d(delta)/dt acts through that rate (module docstring); work[NL + i]
    # becomes layer i's share of the dissipated power, w_i^2 alpha_i / alpha_eff
    alpha = 0.0
    for i in range(nl):
        w = work[NL + i] / csum
        work[NL + i] = w * w * S[S_ALPHA + i]
        alpha += work[NL + i]
    for i in range(nl):
        work[NL + i] = work[NL + i] / alpha if alpha > 0.0 else 0.0
    f = fel * (1.0 + alpha * ddelta)
    return max(f, 0.0), fel, alpha, v


@kernel
def stack_batch(delta, ddelta, S, out, parts):
    """:func:`stack_eval` element-wise: ``out[j] = (F, F_el, alpha, V)``, ``parts[j]`` = layer
    compressions [m] (shape (m, NL)).

    Parameters
    ----------
    delta, ddelta : ndarray of float64, shape (m,)
        Total compressions [m] and their rates [m/s].
    S : ndarray of float64, shape (NSTACK,)
        The stack row.
    out : ndarray of float64, shape (m, 4)
        Output.
    parts : ndarray of float64, shape (m, NL)
        Output: the layers' compressions.
    """
    work = np.empty(NWORK)
    work[W_HINT] = np.nan
    for j in range(delta.shape[0]):
        f, fel, a, v = stack_eval(delta[j], ddelta[j], S, work)
        out[j, 0], out[j, 1], out[j, 2], out[j, 3] = f, fel, a, v
        for i in range(NL):
            parts[j, i] = work[i]


@kernel
def _twobody_stack_batch(V, MU, S, dt, nsteps, w36, w15, out, acc):
    """Two-body impacts through a stack: RK4 on (delta, delta_dot), mu delta'' = -F.

    ``out[c]`` = (F_max, t_Fmax, HIC36, HIC15, delta_max, separation speed, E_dissipated,
    V at the end, p_max); the body's acceleration F / (m g0) is sampled every step.
    """
    work = np.empty(NWORK)
    mb = S[S_M]
    af = S[S_AF]
    for c in range(V.shape[0]):
        work[W_HINT] = np.nan
        d, dd = 0.0, V[c]
        mu = MU[c]
        fmax, tmax, dmax, ed, pmax = 0.0, 0.0, 0.0, 0.0, 0.0
        f, fel, _, _ = stack_eval(d, dd, S, work)
        for s in range(nsteps + 1):
            acc[s] = f / (mb * G0)
            if f > fmax:
                fmax, tmax = f, s * dt
            if d > dmax:
                dmax = d
            if d > 0.0 and f / (af * d) > pmax:
                pmax = f / (af * d)
            if s == nsteps:
                break
            # RK4 on (delta, delta_dot, E_dissipated)
            f1, e1, _, _ = stack_eval(d, dd, S, work)
            a1, p1 = -f1 / mu, (f1 - e1) * dd
            d2, dd2 = d + 0.5 * dt * dd, dd + 0.5 * dt * a1
            f2, e2, _, _ = stack_eval(d2, dd2, S, work)
            a2, p2 = -f2 / mu, (f2 - e2) * dd2
            d3, dd3 = d + 0.5 * dt * dd2, dd + 0.5 * dt * a2
            f3, e3, _, _ = stack_eval(d3, dd3, S, work)
            a3, p3 = -f3 / mu, (f3 - e3) * dd3
            d4, dd4 = d + dt * dd3, dd + dt * a3
            f4, e4, _, _ = stack_eval(d4, dd4, S, work)
            a4, p4 = -f4 / mu, (f4 - e4) * dd4
            d += dt / 6.0 * (dd + 2.0 * dd2 + 2.0 * dd3 + dd4)
            dd += dt / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
            ed += dt / 6.0 * (p1 + 2.0 * p2 + 2.0 * p3 + p4)
            f, fel, _, _ = stack_eval(d, dd, S, work)
            if d < 0.0 and dd <= 0.0:
                # apart and not closing: every later force is 0 and nothing else acts
                for r in range(s + 1, nsteps + 1):
                    acc[r] = 0.0
                break
        h36, _, _, h15, _, _ = hic_pair_kernel(acc, dt, w36, w15, False)
        _, _, _, vend = stack_eval(d, dd, S, work)
        out[c, 0], out[c, 1], out[c, 2], out[c, 3], out[c, 4] = fmax, tmax, h36, h15, dmax
        out[c, 5], out[c, 6], out[c, 7], out[c, 8] = -dd, ed, vend, pmax


@kernel
def stack_force_bound(E0, VREL, alpha_max, D, F, V, out):
    """Rigorous upper bounds on the contact force of impacts with energies ``E0``.

    For an impact whose energy is at most E0 and whose relative normal speed obeys
    (1/2) mu delta_dot^2 + V(delta) <= E0 (:mod:`ppamsafety.impact.anywhere`), on each cell
    [D[j-1], D[j]] of a grid of the stack's compression the force is at most
    F_el(D[j]) (1 + alpha_max V_rel sqrt(1 - V(D[j-1]) / E0)) (F_el and V increase; the
    damping factor alpha_eff <= alpha_max); the largest cell value below the compression where
    V reaches E0 bounds F_max.  Cells are visited downwards until no lower one can win.

    Parameters
    ----------
    E0, VREL : ndarray of float64, shape (N,)
        Energy bound [J] and relative-speed bound sqrt(2 E0 / mu) [m/s] of each impact.
    alpha_max : float
        Largest hysteresis factor of the stack's layers [s/m].
    D, F, V : ndarray of float64, shape (G,)
        Grid of total compressions [m] (increasing, from nearly 0 to beyond any reachable
        value) and the stack's elastic force [N] and potential [J] there.
    out : ndarray of float64, shape (N,)
        Output: the bounds [N] (``inf`` where E0 exceeds the grid's last potential).
    """
    g = D.shape[0]
    for i in range(E0.shape[0]):
        e = E0[i]
        if e <= 0.0:
            out[i] = 0.0
            continue
        if V[g - 1] < e:
            out[i] = math.inf
            continue
        lo, hi = 0, g - 1
        while lo < hi:
            mid = (lo + hi) // 2
            if V[mid] >= e:
                hi = mid
            else:
                lo = mid + 1
        c = alpha_max * VREL[i]
        best = 0.0
        j = lo
        while j >= 1:
            val = F[j] * (1.0 + c * math.sqrt(max(0.0, 1.0 - V[j - 1] / e)))
            if val > best:
                best = val
            if F[j] * (1.0 + c) <= best:
                break
            j -= 1
        if j == 0:
            best = max(best, F[0] * (1.0 + c))
        out[i] = best


# ---- Python level ------------------------------------------------------------------------
@dataclass(frozen=True)
class SeriesContact:
    """A covering on a robot surface against a body: the stack, ready for the kernels.

    Attributes
    ----------
    covering : Covering
        The robot's covering.
    body : BodyContact
        The body region.
    radii : tuple of float
        Principal radii of the robot surface [m].
    row : numpy.ndarray
        The :data:`STACK` row.
    effective_radius : float
        R_e [m] (:func:`effective_radius`).
    """

    covering: Covering
    body: BodyContact
    radii: tuple
    row: np.ndarray
    effective_radius: float

    @property
    def layers(self) -> tuple:
        """Every layer in series, covering first."""
        return self.covering.layers + self.body.layers

    def table(self) -> pd.DataFrame:
        """One row per layer: where it is, its law at this geometry (k, n, b, alpha, limit)."""
        rows = []
        for i, lay in enumerate(self.layers):
            rows.append({"layer": lay.name, "side": "covering" if i < len(self.covering.layers)
                         else "body", "law": lay.law, "k": self.row[S_K + i],
                         "n": self.row[S_N + i], "b": self.row[S_B + i],
                         "alpha": self.row[S_ALPHA + i], "limit": self.row[S_LIM + i]})
        return pd.DataFrame(rows)

    def evaluate(self, delta, delta_dot=0.0) -> pd.DataFrame:
        """The law at total compressions ``delta`` [m] and rates ``delta_dot`` [m/s].

        Parameters
        ----------
        delta : array_like
            Total compressions [m] (<= 0: no contact), finite.
        delta_dot : float or array_like
            Their rates [m/s], broadcast against ``delta``.

        Returns
        -------
        pandas.DataFrame
            ``delta``, ``delta_dot``, ``F`` [N], ``F_el`` [N], ``alpha`` [s/m], ``V`` [J],
            ``delta_<i>`` (compression of each layer [m], covering first) and
            ``p_mean`` [Pa] (F over the contact area, :func:`contact_area`).
        """
        d = np.atleast_1d(as_float_array("delta", delta)).astype(float).ravel()
        dd = np.broadcast_to(np.atleast_1d(as_float_array("delta_dot", delta_dot)), d.shape)
        for nm, a in (("delta", d), ("delta_dot", dd)):
            if not np.all(np.isfinite(a)):
                raise ValueError(f"{nm} must be finite [m, m/s]")
        out = np.empty((d.size, 4))
        parts = np.empty((d.size, NL))
        stack_batch(kernel_array(d), kernel_array(dd), self.row, out, parts)
        df = pd.DataFrame({"delta": d, "delta_dot": dd, "F": out[:, 0], "F_el": out[:, 1],
                           "alpha": out[:, 2], "V": out[:, 3]})
        for i in range(len(self.layers)):
            df[f"delta_{i + 1}"] = parts[:, i]
        with np.errstate(divide="ignore", invalid="ignore"):
            a = contact_area(d, self.effective_radius)
            df["p_mean"] = np.where(a > 0, out[:, 0] / np.where(a > 0, a, 1.0), 0.0)
        return df

    def potential(self, delta) -> np.ndarray:
        """Elastic potential V(delta) of the stack [J] (dV/d(delta) = F_el).

        Parameters
        ----------
        delta : array_like
            Total compressions [m].
        """
        return self.evaluate(delta)["V"].to_numpy()

    def compression_at_energy(self, energy) -> float:
        """Largest total compression [m] whose elastic potential is at most ``energy`` [J].

        Monotone bisection on V (strictly increasing); used by the rigorous bounds.

        Parameters
        ----------
        energy : float
            Energy [J], >= 0.
        """
        e = check_range("energy", energy, 0.0, 1e12, unit="J")
        if e == 0.0:
            return 0.0
        lo, hi = 0.0, 1e-3
        while self.potential(hi)[0] < e:
            lo, hi = hi, 2.0 * hi
            if hi > 1e3:
                raise ValueError(f"energy = {e:g} J is beyond the stack's range")
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if self.potential(mid)[0] < e:
                lo = mid
            else:
                hi = mid
            if hi - lo <= 1e-15 * hi:
                break
        return hi


def series_contact(covering=None, body=None, point: ContactPoint | None = None, *,
                   radii=None) -> SeriesContact:
    """The stack of a covering on a robot surface against a body.

    Parameters
    ----------
    covering : Covering, optional
        Default: the contact point's covering, else bare metal.
    body : BodyContact
        The body region's contact model (required).
    point : ContactPoint, optional
        Gives the robot surface's radii (and the default covering).
    radii : (float, float), optional
        Principal radii of the robot surface [m] instead of a point (default flat).

    Returns
    -------
    SeriesContact
    """
    if body is None:
        raise TypeError("series_contact() needs body= (a BodyContact)")
    body = check_instance("body", body, BodyContact)
    if point is not None:
        point = check_instance("point", point, ContactPoint)
        if radii is not None:
            raise ValueError("give point= or radii=, not both")
        radii = point.radii
        covering = point.covering if covering is None else covering
    covering = BARE if covering is None else check_instance("covering", covering, Covering)
    radii = (math.inf, math.inf) if radii is None else tuple(float(r) for r in radii)
    if len(radii) != 2 or not all(r > 0 for r in radii):
        raise ValueError(f"radii = {radii!r}: two positive radii [m] (inf: flat)")
    row = pack_stack(covering, body, radii)
    return SeriesContact(covering, body, radii, row, effective_radius(body.radius, radii))


#: Largest number of integration steps of one two-body call.
MAX_STEPS = 10 ** 7


def two_body_series(speed, contact: SeriesContact, *, arm_mass, dt: float = 1e-6,
                    duration: float = 0.03) -> pd.DataFrame:
    """Two-body impacts through a stack: an arm's effective mass against the free body region.

    The reduced problem behind the engine (:mod:`ppamsafety.impact.twobody` for one layer):
    mu delta'' = -F(delta, delta'), mu = m_a m_b / (m_a + m_b) (``arm_mass`` = inf: the body
    hits a fixed surface, as in a drop test), the body accelerates with F / m_b.

    Parameters
    ----------
    speed : array_like
        Closing speeds at first touch [m/s], each in (0, 1000].
    contact : SeriesContact
        The stack (:func:`series_contact`).
    arm_mass : float or array_like
        Effective arm mass [kg] (> 0; ``inf`` for a fixed surface), broadcast against speed.
    dt : float
        RK4 step [s] in [1e-9, 1e-4].
    duration : float
        Simulated time [s], in [dt, 1].

    Returns
    -------
    pandas.DataFrame
        ``speed``, ``F_max`` [N], ``t_Fmax`` [s], ``HIC36``, ``HIC15``, ``delta_max`` [m],
        ``a_max_g`` [g], ``p_max`` [Pa], ``separation_speed`` [m/s], ``E_initial`` [J],
        ``E_dissipated`` [J], ``E_stored`` [J] (potential left at the end),
        ``E_balance_error`` [-] ((kinetic out + dissipated + stored - in) / in).
    """
    contact = check_instance("contact", contact, SeriesContact)
    v = np.atleast_1d(as_float_array("speed", speed, ndim=(0, 1)))
    check_range_array("speed", v, 0.0, 1e3, unit="m/s")
    if np.any(v <= 0):
        raise ValueError(f"speed = {v.min():g} m/s must be positive")
    ma = np.broadcast_to(as_float_array("arm_mass", arm_mass, allow_nonfinite=True), v.shape)
    if np.any(np.isnan(ma)) or np.any(ma <= 0):
        raise ValueError("arm_mass must be positive (inf: a fixed surface)")
    dt = check_range("dt", dt, 1e-9, 1e-4, unit="s")
    duration = check_range("duration", duration, dt, 1.0, unit="s")
    nsteps = int(math.ceil(duration / dt - 1e-9))
    if nsteps > MAX_STEPS:
        raise ValueError(f"duration / dt = {nsteps} steps exceeds {MAX_STEPS}")
    mb = contact.body.mass
    mu = np.where(np.isfinite(ma), ma * mb / (np.where(np.isfinite(ma), ma, 1.0) + mb), mb)
    out, acc = _two_body_run(v, mu, contact, dt, nsteps)
    check_finite_result("two_body_series", out[:, :8], "this stack and these speeds")
    e0 = 0.5 * mu * v * v
    ek = 0.5 * mu * out[:, 5] ** 2
    p = out[:, 8] if math.isfinite(contact.effective_radius) else np.full(v.size, np.nan)
    return pd.DataFrame({"speed": v, "F_max": out[:, 0], "t_Fmax": out[:, 1],
                         "HIC36": out[:, 2], "HIC15": out[:, 3], "delta_max": out[:, 4],
                         "a_max_g": out[:, 0] / (mb * G0), "p_max": p,
                         "separation_speed": out[:, 5], "E_initial": e0,
                         "E_dissipated": out[:, 6], "E_stored": out[:, 7],
                         "E_balance_error": (ek + out[:, 6] + out[:, 7] - e0) / e0})


def _two_body_run(v, mu, contact, dt, nsteps):
    """The two-body kernel on checked inputs: (summary rows, acceleration record [g] of the
    last speed)."""
    out = np.empty((v.size, 9))
    acc = np.empty(nsteps + 1)
    w36 = int(math.floor(0.036 / dt * (1 + 1e-9)))
    w15 = int(math.floor(0.015 / dt * (1 + 1e-9)))
    _twobody_stack_batch(kernel_array(v), kernel_array(mu), contact.row, float(dt), nsteps, w36,
                         w15, out, acc)
    return out, acc


def phase_plane_max_compression(contact: SeriesContact, mu: float, v0: float) -> float:
    """Largest compression [m] of a two-body impact through a stack, from the phase plane.

    When the layers share one exponent and none bottoms out, the compliance shares are
    constant and so is alpha_eff = sum w_i^2 alpha_i; then the invariant of Hunt & Crossley
    (Marhefka & Orin 1999) holds for the stack with its potential V: mu [v/alpha -
    ln(1 + alpha v)/alpha^2] + V(delta) = const, so V(delta_max) = mu [v0/alpha -
    ln(1 + alpha v0)/alpha^2] (mu v0^2 / 2 without damping), solved on V
    (:meth:`SeriesContact.compression_at_energy`).

    Parameters
    ----------
    contact : SeriesContact
        Its layers must share one exponent (else ``ValueError``); the caller keeps the impact
        below every layer's bottoming limit.
    mu : float
        Reduced mass [kg], > 0.
    v0 : float
        Closing speed [m/s], > 0.
    """
    contact = check_instance("contact", contact, SeriesContact)
    mu = check_range("mu", mu, 0.0, 1e6, lo_open=True, unit="kg")
    v0 = check_range("v0", v0, 0.0, 1e3, lo_open=True, unit="m/s")
    nl = int(contact.row[S_NL])
    n = contact.row[S_N:S_N + nl]
    if np.ptp(n) > 0.0:
        raise ValueError(f"the phase-plane closed form needs one exponent for every layer; this "
                         f"stack has n = {n.tolist()}")
    alpha = float(contact.evaluate([1e-9])["alpha"].iloc[0])   # constant with one exponent
    x = alpha * v0
    if x < 1e-3:
        level = mu * v0 * v0 / 2.0 * (1.0 - 2.0 * x / 3.0 + x * x / 2.0 - 2.0 * x ** 3 / 5.0)
    else:
        level = mu / alpha ** 2 * (x - math.log1p(x))
    return contact.compression_at_energy(level)


def two_body_dashpots(speed, contact: SeriesContact, *, arm_mass, duration: float = 0.03,
                      rtol: float = 1e-8) -> pd.DataFrame:
    """Reference model: the same layers as Kelvin-Voigt-like dashpots in series, a massless
    interface between each (scipy's stiff Radau integrator; for comparison, not speed).

    Each damped layer i (alpha_i > 0) carries its own Hunt-Crossley law F = a_i (1 + alpha_i
    d(delta_i)/dt), a_i = k_i delta_i^n_i, so the rate splits between the layers by their
    damping as well as their stiffness (the layers' memory).  With one undamped layer (the
    bone) the force is its elastic force and every damped layer's compression is a state;
    with none, the force follows from the rates adding up, F = (d(delta)/dt + sum 1/alpha_i)
    / sum 1/(alpha_i a_i), and all but the last layer's compression are states.  The layers
    do not bottom out here; the run stops when the force returns to 0.  Compare with the
    lumped law of :func:`stack_eval` (docs/impact_models.md).

    Parameters
    ----------
    speed : array_like
        Closing speeds [m/s], each in (0, 20].
    contact : SeriesContact
        The layers (their k, n, alpha at the contact's geometry); at most one undamped.
    arm_mass : float
        Effective arm mass [kg] (``inf``: a fixed surface).
    duration : float
        Longest simulated time [s].
    rtol : float
        Relative tolerance of the integrator.

    Returns
    -------
    pandas.DataFrame
        ``speed``, ``F_max`` [N], ``delta_max`` [m] (largest total compression).
    """
    from scipy.integrate import solve_ivp
    from scipy.optimize import brentq

    contact = check_instance("contact", contact, SeriesContact)
    v = np.atleast_1d(as_float_array("speed", speed, ndim=(0, 1)))
    check_range_array("speed", v, 0.0, 20.0, unit="m/s")
    ma = float(arm_mass)
    nl = int(contact.row[S_NL])
    k = contact.row[S_K:S_K + nl]
    n = contact.row[S_N:S_N + nl]
    a = contact.row[S_ALPHA:S_ALPHA + nl]
    elastic = np.nonzero(a == 0)[0]
    if elastic.size > 1:
        raise ValueError("two_body_dashpots takes at most one undamped layer")
    states = [i for i in range(nl) if a[i] > 0][:nl - 1] if elastic.size == 0 else \
        [i for i in range(nl) if a[i] > 0]
    last = [i for i in range(nl) if i not in states][0]       # the layer that closes the sum
    mb = contact.body.mass
    mu = mb if not math.isfinite(ma) else ma * mb / (ma + mb)

    def parts(y):
        ds = [max(min(y[2 + i], y[0]), 1e-300) for i in range(len(states))]
        return ds, max(y[0] - sum(ds), 1e-300)

    def force(y):
        ds, dl = parts(y)
        if elastic.size:
            return k[last] * dl ** n[last]
        acs = [k[j] * d ** n[j] for j, d in zip(states, ds)] + [k[last] * dl ** n[last]]
        al = [a[j] for j in states] + [a[last]]
        return (y[1] + sum(1.0 / x for x in al)) / sum(1.0 / (x * c) for x, c in zip(al, acs))

    def rhs(t, y):
        f = force(y)
        ds, _ = parts(y)
        return [y[1], -f / mu] + [(f / (k[j] * d ** n[j]) - 1.0) / a[j]
                                  for j, d in zip(states, ds)]

    rows = []
    for v0 in v:
        d0 = 1e-6 * v0                      # start on the elastic split after about 1 us
        f0 = brentq(lambda f: sum((f / k[j]) ** (1.0 / n[j]) for j in range(nl)) - d0, 0.0,
                    min(k[j] * d0 ** n[j] for j in range(nl)), rtol=1e-13)
        y0 = [d0, float(v0)] + [(f0 / k[j]) ** (1.0 / n[j]) for j in states]

        def apart(t, y):
            return force(y) if t > 1e-5 else 1.0
        apart.terminal, apart.direction = True, -1
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            sol = solve_ivp(rhs, (0.0, duration), y0, method="Radau", rtol=rtol, atol=1e-14,
                            events=apart, dense_output=True)
            tt = np.linspace(0.0, sol.t[-1], 4001)
            Y = sol.sol(tt)
            F = np.array([force(Y[:, i]) for i in range(tt.size)])
        rows.append({"speed": float(v0), "F_max": float(F.max()),
                     "delta_max": float(Y[0].max())})
    return pd.DataFrame(rows)


__all__ = ["STACK", "SeriesContact", "series_contact", "pack_stack", "effective_radius",
           "layer_law", "contact_area", "two_body_series", "phase_plane_max_compression",
           "stack_eval", "two_body_dashpots"]
