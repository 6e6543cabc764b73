"""Stability of the names of a muscle record: the selection rerun on halves of its loops.

A name the diagnosis trusts must not hinge on a part of the record.  The
record's equations are grouped into **units**: the loops of the motion (a
contracting run and the extending run after it, with the rest that follows),
or, when the record has fewer than :data:`MIN_UNITS` loops (a pressure sweep at
fixed contraction, a single loop), :data:`TIME_SEGMENTS` contiguous time
segments.  Never alternate samples: neighbouring samples share the slow
structure of an effect (and of a filtered noise), so two interleaved halves are
not two experiments.

B times, the units are split at random into two halves of equal size and the
naming rule (:func:`~.selection.select`) runs on each half.  A name's
*frequency* is the fraction of the 2B halves that select it; it is *stable*
when the frequency reaches :data:`THRESHOLD`.  With a threshold pi > 1/2 the
expected number of false selections among the stable names is at most
q^2 / ((2 pi - 1) p) (q the mean number selected per half, p the number of
candidates; Meinshausen & Buehlmann 2010, Theorem 1, which Shah & Samworth
2013 show holds for complementary pairs) -- the arm's stability selection
(:func:`ppamsafety.diagnose.arm.selection.stability_selection`) on the units of
a muscle record.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..._validation import check_int, check_range
from ..core.criteria import false_selection_bound
from ..core.linear_selection import fit_linear
from .selection import select

#: Complementary pairs (2 x this many reruns of the selection).
PAIRS = 10
#: Selection frequency at or above which a name counts as stable.
THRESHOLD = 0.8
#: Fewest loops for the halves to be made of loops (else time segments).
MIN_UNITS = 4
#: Contiguous time segments used when the record has too few loops.
TIME_SEGMENTS = 8


@dataclass(frozen=True)
class LoopStability:
    """Result of :func:`stability_selection` (module docstring).

    Attributes
    ----------
    frequency : dict
        Candidate -> fraction of the 2B halves that selected it.
    pairs : int
        B.
    threshold : float
        pi: a name is stable when its frequency reaches it.
    q : float
        Mean number of candidates selected per half.
    p : int
        Number of candidates.
    expected_false_bound : float or None
        q^2 / ((2 pi - 1) p); None when pi <= 0.5.
    seed : int
    units : int
        Number of units the record was split into.
    unit : str
        ``"loops"`` or ``"time segments"``.
    """

    frequency: dict
    pairs: int
    threshold: float
    q: float
    p: int
    expected_false_bound: float | None
    seed: int
    units: int
    unit: str

    def to_dict(self) -> dict:
        """JSON-ready form (``diagnosis.json`` key ``stability``)."""
        return {"method": "complementary-pairs stability selection (Shah & Samworth 2013): the "
                          "naming rule re-run on both halves of B random splits of the record's "
                          f"{self.unit}",
                "pairs": self.pairs, "halves": 2 * self.pairs, "threshold": self.threshold,
                "mean_selected_per_half": self.q, "candidates": self.p,
                "expected_false_selections_bound": self.expected_false_bound,
                "bound": "E[V] <= q^2 / ((2 pi_thr - 1) p) (Meinshausen & Buehlmann 2010, "
                         "Theorem 1)",
                "seed": self.seed, "units": self.units, "unit": self.unit,
                "frequency": dict(self.frequency)}


def loop_units(design) -> tuple:
    """The unit (loop or time segment) of every equation of ``design`` (module docstring).

    Parameters
    ----------
    design : ActuatorDesign

    Returns
    -------
    numpy.ndarray of int, shape (m,)
        Unit labels 0, 1, ...
    str
        ``"loops"`` or ``"time segments"``.
    """
    d = design.direction[design.idx]
    start = np.zeros(d.size, bool)
    start[1:] = (d[1:] > 0) & (d[:-1] <= 0)          # a contracting run begins: a new loop
    labels = np.cumsum(start)
    if labels.size and int(labels.max()) + 1 >= MIN_UNITS:
        return labels, "loops"
    m = design.m
    return np.minimum((np.arange(m) * TIME_SEGMENTS) // max(m, 1), TIME_SEGMENTS - 1), \
        "time segments"


def stability_selection(design, *, alpha: float, pairs: int = PAIRS, seed: int = 0,
                        threshold: float = THRESHOLD) -> LoopStability:
    """Selection frequencies over complementary halves of the record's loops.

    Parameters
    ----------
    design : ActuatorDesign
    alpha : float, keyword-only
        Level of the LR test before the Bonferroni division.
    pairs : int, keyword-only
        B (>= 1).
    seed : int, keyword-only
        Seed of the splits.
    threshold : float, keyword-only
        pi in (0.5, 1].

    Returns
    -------
    LoopStability
    """
    pairs = check_int("pairs", pairs, 1, 10000)
    seed = check_int("seed", seed, 0)
    threshold = check_range("threshold", threshold, 0.5, 1.0, lo_open=True)
    splits, labels, unit, U = _splits(design, pairs, seed)
    names = list(design.columns)
    counts = dict.fromkeys(names, 0)
    total = 0
    for pair in splits:
        for h in pair:
            for n in select(design, alpha=alpha, mask=h).names:
                counts[n] += 1
                total += 1
    halves = 2 * pairs
    q = total / halves
    p = max(len(names), 1)
    return LoopStability(frequency={n: counts[n] / halves for n in names}, pairs=pairs,
                         threshold=threshold, q=q, p=p,
                         expected_false_bound=false_selection_bound(q, threshold, p), seed=seed,
                         units=U, unit=unit)


def _splits(design, pairs, seed):
    """The B complementary splits of :func:`stability_selection` (same seed, same splits)."""
    labels, unit = loop_units(design)
    U = int(labels.max()) + 1
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(pairs):
        perm = rng.permutation(U)
        half = np.zeros(U, bool)
        half[perm[:U // 2]] = True
        out.append((half[labels], ~half[labels]))
    return out, labels, unit, U


def half_sample_covariance(design, names, *, pairs: int = PAIRS, seed: int = 0) -> np.ndarray:
    """Covariance of the final model's coefficients from its fits on complementary halves.

    On each of the B splits of :func:`stability_selection` the model ``names`` is
    fitted on both halves of the record's loops (or time segments); with
    ``d = (phi_A - phi_B) / 2`` the half-sample covariance is the mean of ``d d^T``
    (``phi_full ~ (phi_A + phi_B) / 2``, so ``d`` has the full record's covariance).
    Unlike the HAC covariance of one fit it sees every error that differs from loop to
    loop -- the noise of the contraction that the Preisach input and the direction of
    motion are built from (errors in variables), a model slightly off in one loop --
    because whole loops are left out.

    Parameters
    ----------
    design : ActuatorDesign
    names : sequence of str
        The model's candidates.
    pairs : int, keyword-only
        B (>= 1).
    seed : int, keyword-only
        Seed of the splits (:func:`stability_selection`'s, for the same splits).

    Returns
    -------
    numpy.ndarray, shape (k, k)
        In the order of ``fit_linear(..., names)``'s coefficients.
    """
    pairs = check_int("pairs", pairs, 1, 10000)
    seed = check_int("seed", seed, 0)
    names = list(names)
    k = sum(design.columns[n].shape[1] for n in names)
    if k == 0:
        return np.zeros((0, 0))
    splits, _, _, U = _splits(design, pairs, seed)
    C = np.zeros((k, k))
    for a, b in splits:
        fa = fit_linear(design.e0, design.columns, names, mask=a)
        fb = fit_linear(design.e0, design.columns, names, mask=b)
        d = (fa.phi - fb.phi) / 2.0
        C += np.outer(d, d)
    return C / len(splits)


def inflated_covariance(cov, half) -> np.ndarray:
    """``cov`` with each coefficient's variance raised to its half-sample variance where larger.

    ``D cov D`` with ``D = diag(sqrt(max(1, half_jj / cov_jj)))``: the correlations
    of ``cov`` are kept, no variance is lowered.

    Parameters
    ----------
    cov : numpy.ndarray, shape (k, k)
        Covariance of one fit (HAC).
    half : numpy.ndarray, shape (k, k)
        :func:`half_sample_covariance`.
    """
    cov = np.asarray(cov, float)
    half = np.asarray(half, float)
    if cov.shape != half.shape:
        raise ValueError(f"half must have the shape of cov {cov.shape}, got {half.shape}")
    v = np.diag(cov)
    s = np.ones_like(v)
    ok = v > 0
    s[ok] = np.sqrt(np.maximum(1.0, np.diag(half)[ok] / v[ok]))
    return cov * np.outer(s, s)


__all__ = ["LoopStability", "loop_units", "stability_selection", "half_sample_covariance",
           "inflated_covariance", "PAIRS", "THRESHOLD",
           "MIN_UNITS", "TIME_SEGMENTS"]
