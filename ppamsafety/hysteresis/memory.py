"""Staircase memory of the discrete Preisach operator, in a flat float64 row.

Choice of memory: a stack of alternating dominant extrema (Mayergoyz 1991),
not a relay grid.  The boundary between P+ and P- (fig. 3.14) is a staircase
whose corners are the alternating dominant extrema of the past input; with
the Everett function E (:mod:`.everett`) the output is a signed sum over the
corners, so the operator is exact for any input (no quantisation of the
input or of the plane), rate independent by construction, and its cost does
not depend on a grid resolution.  A relay grid would be simpler but
quantises the output to steps of one relay weight and costs O(grid) per
update.

Representation.  The reduced history x_0, x_1, ..., x_{n-1}, u: x_0 = -1 or
+1 is the saturation the history started from, x_1 ... x_{n-1} alternate
between maxima and minima, each strictly inside the interval of the two
before it (nested), and u is the current input (the staircase tip).  With
t(a, b) = sign(b - a) E(max(a, b), min(a, b)) the output is::

    W = x_0 + 2 sum_{j=1}^{n-1} t(x_{j-1}, x_j) + 2 t(x_{n-1}, u)
      = S_{n-1} + 2 t(x_{n-1}, u),

(Mayergoyz 1991, the staircase sum; from negative saturation, rising to u
gives W = -1 + 2 E(u, -1)).  The prefix sums S_k (output when the tip sits
on x_k) are stored with the extrema, so an update costs one or two Everett
evaluations whatever the depth:

* a reversal at the old input pushes it as a new extremum (one Everett call
  for its prefix sum);
* wiping-out pops the pairs of extrema the new input passes (no arithmetic:
  the surviving prefix sums are still valid, which also makes return-point
  memory exact to the last bit: after a closed minor loop the output is the
  same expression as before it);
* the output is S_{n-1} + 2 t(x_{n-1}, u) (one Everett call).

Saturation.  The input is clipped to [-1, 1]; reaching +1 (-1) wipes the
whole memory and resets it to positive (negative) saturation, where W = +1
(-1) exactly.

Bounded depth.  The row holds at most ``MAX_DEPTH`` = 32 extrema.  Each
stored extremum is strictly inside the previous pair, so 32 levels need 31
nested reversals of decreasing amplitude without any wiping-out, far more
than a muscle contraction history produces.  When a reversal would push a
33rd extremum, the innermost pair (the previous extremum x_{n-1} and the new
reversal point) is dropped instead: that pair has the smallest amplitude of
the stack (amplitudes decrease strictly inwards), so only the finest minor
loop is forgotten.  The output then misses the weight of a strip of the
plane of width a = |u - x_{n-1}| (the amplitude of the dropped pair)::

    |W_dropped - W_exact| <= 2 * (2 a) * max mu-tilde = 4 a / z

(max mu-tilde = 1/z, z = :attr:`~.everett.PreisachWeight.z`; 3.74 a for the
thesis weight), summed over dropped pairs; the error disappears as soon as
the input passes the extremum that enclosed the dropped loop (both memories
wipe it out).  ``tests/test_hysteresis.py`` checks this bound.

Row layout (:data:`MEMORY`, ``STATE_LENGTH`` = 2 + 2 MAX_DEPTH floats per
operator): depth n, current input u, extrema[MAX_DEPTH], prefix[MAX_DEPTH].

Use in the plant (intended scheme).  The thesis model is rate independent,
so the memory is a function of the path of eps_s only.  Keep one row per
hysteretic muscle group in the plant's effect-state vector z (at offsets
``k * STATE_LENGTH``), initialise it with :func:`initial_memory`
(negative saturation: the thesis requires the muscle to be brought to an
extreme first, §3.6.6), and

* inside the RK4 stages evaluate W with :func:`preisach_peek` (memory of the
  start of the step + the stage's eps_s; nothing written, so the stages of a
  rejected or repeated step do not corrupt the memory);
* after each accepted integration step commit the end-of-step eps_s with
  :func:`preisach_update`.

A turning point of eps inside one step is thus registered at the end of the
step instead of at its exact instant: an O(dt) error in the position of one
reversal, of the same order as the sampling of any discrete-time record.
Cost (measured, 2-core machine under a load average of ~5.6, so upper
bounds): one Everett evaluation per call without reversal, 0.85 us per
:func:`preisach_update` and 1.0 us per :func:`preisach_peek` along a smooth
contraction-like path; 2.2 us per update in the worst case of a reversal at
every call (two Everett evaluations).
"""

from __future__ import annotations

import numpy as np

from .._jit import kernel, leaf, step_kernel
from .._validation import as_float_array, check_int
from ..layouts import Field, Layout
from .everett import (C_THESIS, D_THESIS, THESIS_WEIGHT, PreisachWeight, check_weight,
                      everett_raw)

#: Maximum number of stored extrema (including the initial saturation x_0).
MAX_DEPTH = 32

#: Declared layout of one Preisach memory row.
MEMORY = Layout("preisach memory", [
    Field("depth", 1, "-", "number n of stored extrema x_0..x_{n-1}, 1 <= n <= MAX_DEPTH",
          default=1.0),
    Field("input", 1, "-", "current (last committed) scaled input u in [-1, 1], the "
          "staircase tip", default=-1.0),
    Field("extrema", MAX_DEPTH, "-", "alternating dominant extrema x_0 (= +-1 saturation), "
          "x_1, ..., nested; slots >= n unused", default=-1.0),
    Field("prefix", MAX_DEPTH, "-", "S_k = output W when the input sits on x_k "
          "(prefix sums of the staircase); slots >= n unused", default=-1.0),
])

#: Floats needed per Preisach operator in a flat state vector.
STATE_LENGTH = MEMORY.size

N_, U_, X_ = MEMORY.offsets("depth", "input", "extrema")
_S_THESIS = MEMORY.offset("prefix")

_C = C_THESIS
_D = D_THESIS
_INV_Z = THESIS_WEIGHT.inv_z
#: MAX_DEPTH as a run-time int64 for :func:`advance`: the flag ``write`` and the capacity are
#: passed as numpy scalars, not constants, so that numba compiles :func:`advance` once (it
#: compiles a kernel once per distinct constant argument).
_CAP = np.int64(MAX_DEPTH)


def state_length(capacity: int = MAX_DEPTH) -> int:
    """Floats of a memory row holding ``capacity`` extrema (``STATE_LENGTH`` for the default).

    Parameters
    ----------
    capacity : int
        Maximum number of stored extrema (default :data:`MAX_DEPTH`).
    """
    return 2 + 2 * capacity


@leaf
def _signed(a, b, c, d, inv_z):
    """2 t(a, b): twice the signed weight switched by moving the input from a to b."""
    if b > a:
        return 2.0 * inv_z * everett_raw(b, a, c, d)
    if b < a:
        return -2.0 * inv_z * everett_raw(a, b, c, d)
    return 0.0


@step_kernel
def advance(z, o, cap, v, c, d, inv_z, write):
    """Move the input of the memory row ``z[o:]`` to ``v``; return the output W.

    Parameters
    ----------
    z : float64[:]
        Array holding the memory row at ``o`` (layout :data:`MEMORY` with
        ``cap`` extrema: extrema at ``o + 2``, prefix sums at ``o + 2 + cap``).
    o : int
        Offset of the row in ``z``.
    cap : int
        Capacity (maximum depth), >= 2.
    v : float
        New scaled input; clipped to [-1, 1]; NaN keeps the current input.
    c, d, inv_z : float
        Weight parameters and normalisation (:class:`~.everett.PreisachWeight`).
    write : bool
        Commit the new input to the memory (True) or only evaluate (False).

    Returns
    -------
    float
        W in [-1, 1].
    """
    xs = o + X_
    ss = o + X_ + cap
    if not v == v:
        v = z[o + U_]
    if v >= 1.0 or v <= -1.0:
        v = 1.0 if v >= 1.0 else -1.0
        if write:
            z[o + N_] = 1.0
            z[o + U_] = v
            z[xs] = v
            z[ss] = v
        return v
    n = int(z[o + N_])
    u = z[o + U_]
    last = z[xs + n - 1]
    virt = False
    vx = 0.0
    vs = 0.0
    m = n
    if (u - last) * (v - u) < 0.0:          # reversal at u
        if n < cap:
            virt = True                       # u becomes extremum number n
            vx = u
            vs = z[ss + n - 1] + _signed(last, u, c, d, inv_z)
            m = n + 1
        else:
            m = n - 1                         # full: forget the innermost pair (x_{n-1}, u)
    while m >= 2:
        x1 = vx if (virt and m - 1 == n) else z[xs + m - 1]
        x2 = z[xs + m - 2]
        if (x1 - x2) * (v - x1) >= 0.0:       # x1 no longer a reversal (degenerate tip)
            m -= 1
        elif m >= 3 and (v - x2) * (x2 - x1) >= 0.0:   # wiping-out of the pair (x2, x1)
            m -= 2
        else:
            break
    if virt and m - 1 == n:
        xt = vx
        st = vs
    else:
        xt = z[xs + m - 1]
        st = z[ss + m - 1]
    w = st + _signed(xt, v, c, d, inv_z)
    if write:
        if virt and m == n + 1:
            z[xs + n] = vx
            z[ss + n] = vs
        z[o + N_] = m
        z[o + U_] = v
    return w


@leaf
def preisach_update(state, u, offset):
    """Commit the scaled input ``u`` to the memory row at ``state[offset:]``; return W.

    Thesis weight (3.33), capacity :data:`MAX_DEPTH`.  ``u`` is clipped to
    [-1, 1]; call once per accepted integration step (see the module
    docstring).  Output dimensionless, in [-1, 1].

    Parameters
    ----------
    state : ndarray of float64, 1-D
        Array holding the memory row (layout :data:`MEMORY`,
        ``STATE_LENGTH`` floats) at ``offset``; updated in place.
    u : float
        New scaled input eps_s [-]; clipped to [-1, 1]; NaN keeps the current
        input.
    offset : int
        Index of the row's first slot in ``state``.
    """
    return advance(state, offset, _CAP, u, _C, _D, _INV_Z, np.bool_(True))


@leaf
def preisach_peek(state, u, offset):
    """Output W for input ``u`` with the memory row at ``state[offset:]``, nothing written.

    Same result as :func:`preisach_update` would return; for the stages of
    an integration step.

    Parameters
    ----------
    state : ndarray of float64, 1-D
        Array holding the memory row (layout :data:`MEMORY`,
        ``STATE_LENGTH`` floats) at ``offset``; only read.
    u : float
        Scaled input eps_s [-]; clipped to [-1, 1]; NaN means the current
        input.
    offset : int
        Index of the row's first slot in ``state``.
    """
    return advance(state, offset, _CAP, u, _C, _D, _INV_Z, np.bool_(False))


@leaf
def preisach_output(state, offset):
    """Current output W of the memory row at ``state[offset:]`` (input unchanged).

    Parameters
    ----------
    state : ndarray of float64, 1-D
        Array holding the memory row (layout :data:`MEMORY`,
        ``STATE_LENGTH`` floats) at ``offset``; only read.
    offset : int
        Index of the row's first slot in ``state``.
    """
    return advance(state, offset, _CAP, state[offset + U_], _C, _D, _INV_Z, np.bool_(False))


@kernel
def run(u, z, cap, c, d, inv_z, out):
    """Feed the samples ``u`` through the memory row ``z`` (updated), W into ``out``.

    Parameters
    ----------
    u : ndarray of float64, shape (n,)
        Scaled inputs eps_s [-], in order; each is clipped to [-1, 1].
    z : ndarray of float64, shape (2 + 2 cap,)
        The memory row, starting at index 0 (layout :data:`MEMORY` for
        ``cap = MAX_DEPTH``); updated in place with every sample.
    cap : int
        Capacity (maximum depth) of ``z``, >= 2.
    c, d : float
        Weight parameters of (3.33) [-] (see :func:`advance`).
    inv_z : float
        Normalisation 1/z of the weight (:class:`~.everett.PreisachWeight`).
    out : ndarray of float64, shape (n,)
        Output, overwritten: W after each sample, in [-1, 1] [-].
    """
    for i in range(u.size):
        out[i] = advance(z, np.int64(0), cap, u[i], c, d, inv_z, np.bool_(True))


def initial_memory(initial="negative", *, weight: PreisachWeight = THESIS_WEIGHT,
                   capacity: int = MAX_DEPTH) -> np.ndarray:
    """A fresh memory row.

    Parameters
    ----------
    initial : {"negative", "positive"} or sequence of float
        ``"negative"``: negative saturation, all relays -1, input -1, W = -1
        (the thesis' initial state, §3.6.3 and fig. 3.15).  ``"positive"``:
        positive saturation, W = +1.  A sequence: a past input history in
        [-1, 1] starting at a saturation value (-1 or +1), e.g. a list of
        extrema ``[-1, 0.8, -0.4, 0.3]``; it is fed through the operator and
        the last value becomes the current input.
    weight : PreisachWeight, keyword-only
        Weight the prefix sums are computed with (must be the one the row is
        later used with; the plant leaves use the thesis weight).
    capacity : int, keyword-only
        Maximum depth, 2..10000 (default :data:`MAX_DEPTH`; the plant leaves
        require the default).

    Returns
    -------
    numpy.ndarray, shape (2 + 2 capacity,)
        The row (layout :data:`MEMORY` for the default capacity).

    Raises
    ------
    ValueError
        For an unknown string, an empty/non-finite history, values outside
        [-1, 1], or a history not starting at -1 or +1.
    TypeError
        If ``weight`` is not a :class:`~.everett.PreisachWeight`.
    """
    w = check_weight(weight)
    cap = check_int("capacity", capacity, 2, 10000)
    z = np.empty(state_length(cap))
    if isinstance(initial, str):
        if initial not in ("negative", "positive"):
            raise ValueError(f"initial = {initial!r} is not one of 'negative', 'positive' "
                             "or a sequence of past inputs")
        x0 = -1.0 if initial == "negative" else 1.0
        history = np.empty(0)
    else:
        h = as_float_array("initial", initial)
        if h.ndim != 1 or h.size == 0:
            raise ValueError(f"initial must be 'negative', 'positive' or a non-empty 1-D "
                             f"sequence of past inputs, got shape {h.shape}")
        if h.min() < -1.0 or h.max() > 1.0:
            raise ValueError(f"initial history must lie in [-1, 1], got values in "
                             f"[{h.min():g}, {h.max():g}]")
        if h[0] not in (-1.0, 1.0):
            raise ValueError(f"initial history must start at a saturation value -1 or +1, "
                             f"got {h[0]!r}")
        x0 = float(h[0])
        history = np.ascontiguousarray(h[1:])
    z[:] = x0
    z[N_] = 1.0
    if history.size:
        run(history, z, cap, w.c, w.d, w.inv_z, np.empty(history.size))
    return z


def history_of_memory(row) -> tuple:
    """The past-input history that rebuilds a Preisach memory row exactly.

    Parameters
    ----------
    row : array_like, shape (STATE_LENGTH,)
        A memory row (layout :data:`MEMORY`), e.g. one
        group's slice of the effect state returned by
        ``plant.model.simulate(..., return_effect_state=True)``.

    Returns
    -------
    tuple of float
        The stored extrema x_0 .. x_{n-1} followed by the current input: fed
        through the operator (:func:`ppamsafety.hysteresis.initial_memory`) it
        reproduces the row (the prefix sums are recomputed by the same
        operations).  Use it for ``ppamsafety.params.Effects.hysteresis_initial``.

    Raises
    ------
    ValueError
        If ``row`` has the wrong shape or is not a valid memory row.
    """
    h = as_float_array("row", row)
    if h.shape != (STATE_LENGTH,):
        raise ValueError(f"row must have shape ({STATE_LENGTH},), got {h.shape}")
    n = h[MEMORY.offset("depth")]
    if not (n == int(n) and 1 <= n <= MAX_DEPTH):
        raise ValueError(f"row is not a memory row: depth {n!r} outside 1..{MAX_DEPTH}")
    hist = np.append(MEMORY.read(h, "extrema")[:int(n)], MEMORY.read(h, "input"))
    if not (np.all(np.isfinite(hist)) and np.all(np.abs(hist) <= 1.0) and abs(hist[0]) == 1.0):
        raise ValueError(f"row is not a memory row: its history {hist!r} must lie in [-1, 1] and "
                         "start at a saturation value -1 or +1")
    return tuple(float(v) for v in hist)


__all__ = ["history_of_memory", "MAX_DEPTH", "MEMORY", "STATE_LENGTH", "advance", "initial_memory",
           "preisach_output", "preisach_peek", "preisach_update", "run", "state_length"]
