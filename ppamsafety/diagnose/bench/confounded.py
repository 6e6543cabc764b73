"""Look-alikes on a muscle record: candidates the record cannot tell apart are confounded, never named.

A sensor fault and a plant effect may explain the same part of the residual:
a force-sensor gain is nested in a refitted force law (a uniform scale of its
coefficients), a pressure-sensor gain is a force-sensor gain on a muscle record,
and at one pressure level the offsets are nearly a refitted law.  For every
member A of the final model M and every applicable candidate B outside it
(admissible in the model ``M - A + B``):

* **A given B**: adding A to ``M - A + B`` under the naming rule (likelihood-ratio
  p < alpha/K, a lower BIC, and rule 5: a chi2 decrease of at least
  ``MIN_EFFECT_RMS^2`` per equation, :mod:`.selection`);
* **B given A**: the likelihood-ratio test of adding B to M (reported).

When A given B does not pass the rule *and* B takes at least
:data:`LOOKALIKE_SHARE` of A's likelihood-ratio statistic (A given ``M - A``),
B explains what A explains as far as the record can tell: the pair is
**confounded**.  (The share keeps an unrelated candidate that takes a sliver of
a weak effect from being called its look-alike.)  This holds when *both*
directions are not significant (the two explain the same part: the nested
gain and refit on a pure scale), and also when what tells A from B is too
small to be named itself (a hysteresis below its detection limit tipping the
balance between a force offset and a pressure offset; the shape that a
refitted law adds to a force gain) -- naming A would then rest on a
difference the diagnosis would not name on its own.  Pairs sharing a member are merged into one
group.  A group is reported (``Diagnosis.confounded``) with each member's
interpretation -- its parameters if it were the cause -- the two tests of each
pair, and the experiment that would separate them
(:func:`~.candidates.separating_experiment`); no member is named.
"""

from __future__ import annotations

import math

from ..core.criteria import _chi2_sf
from ..core.linear_selection import fit_linear
from ..core.result import ConfoundedGroup, Estimate
from .candidates import separating_experiment
from .selection import MIN_EFFECT_RMS, admissible_in

#: Smallest share of a member's likelihood-ratio statistic that an outside candidate must
#: take to be its look-alike.
LOOKALIKE_SHARE = 0.5


def _lr(small, big):
    d = max(small.chi2 - big.chi2, 0.0)
    df = max(big.k - small.k, 1)
    return d, df, _chi2_sf(d, df)


def lookalike_pairs(design, fit, *, alpha: float) -> list:
    """Pairs (member of the model, candidate outside it) the record cannot tell apart.

    Parameters
    ----------
    design : ActuatorDesign
    fit : _LinearFit
        The final model.
    alpha : float, keyword-only
        Level of the LR test before the Bonferroni division (over every applicable
        candidate).

    Notes
    -----
    A pair is returned when the member does not pass the naming rule given the
    alternative (module docstring).

    Returns
    -------
    list of dict
        ``member``, ``alternative``, ``lr_member_given_alternative``, ``p_member_given_alternative``,
        ``lr_alternative_given_member``, ``p_alternative_given_member``, ``df`` (member, alternative).
    """
    e0, cols = design.e0, design.columns
    level = alpha / max(len(cols), 1)
    admissible = admissible_in(design)
    out = []
    model = list(fit.names)
    for a in model:
        rest = [n for n in model if n != a]
        d_alone = _lr(fit_linear(e0, cols, rest), fit)[0]
        for b in cols:
            if b in model:
                continue
            swapped = fit_linear(e0, cols, rest + [b])
            if not admissible(swapped, b):
                continue
            both = fit_linear(e0, cols, model + [b])
            d_a, df_a, p_a = _lr(swapped, both)
            d_b, df_b, p_b = _lr(fit, both)
            told_apart = (p_a < level and both.bic < swapped.bic
                          and d_a / max(both.m, 1) >= MIN_EFFECT_RMS ** 2)
            if not told_apart and d_a <= (1.0 - LOOKALIKE_SHARE) * d_alone:
                out.append({"member": a, "alternative": b, "lr_member_given_alternative": d_a,
                            "p_member_given_alternative": p_a,
                            "lr_alternative_given_member": d_b,
                            "p_alternative_given_member": p_b, "df": [df_a, df_b]})
    return out


def _groups(pairs):
    parent = {}

    def find(x):
        parent.setdefault(x, x)
        while parent[x] != x:
            x = parent[x]
        return x

    for p in pairs:
        parent[find(p["member"])] = find(p["alternative"])
    out = {}
    for p in pairs:
        for x in (p["member"], p["alternative"]):
            out.setdefault(find(x), [])
            if x not in out[find(x)]:
                out[find(x)].append(x)
    return list(out.values())


def _gain_as_pressure_gain(table):
    """The pressure-sensor gain g_p = -g/(1 + g) that gives the same column as force gain g."""
    d = table["g"]

    def conv(g):
        return -g / (1.0 + g) if g > -1.0 else math.nan
    lo, hi = conv(d.ci_high), conv(d.ci_low)      # decreasing map
    return Estimate(value=conv(d.value), unit="-", ci_low=lo, ci_high=hi,
                    std_error=d.std_error / (1.0 + d.value) ** 2 if d.value > -1 else math.nan,
                    nominal=0.0,
                    note="the pressure-sensor gain that gives the same column (g_p = -g/(1 + g))")


def confounded_groups(design, fit, *, alpha: float) -> list:
    """The confounded groups of the final model (module docstring).

    Parameters
    ----------
    design : ActuatorDesign
    fit : _LinearFit
        The final model.
    alpha : float, keyword-only

    Returns
    -------
    list of ConfoundedGroup
        ``members`` (model members first), ``interpretations`` (member -> its parameter
        table if it were the cause, with the other model members refitted), ``evidence``
        (``pairs``: the two likelihood-ratio tests of every pair), ``separating_experiment``
        and ``signature`` (each member's).
    """
    pairs = lookalike_pairs(design, fit, alpha=alpha)
    e0, cols = design.e0, design.columns
    out = []
    for g in _groups(pairs):
        members = [n for n in fit.names if n in g] + [n for n in g if n not in fit.names]
        others = [n for n in fit.names if n not in g]
        interp = {}
        for mbr in members:
            f = fit if mbr in fit.names else fit_linear(e0, cols, others + [mbr])
            sl = f.slices[mbr]
            tab = design.extensions[mbr].values(f.phi[sl], f.cov[sl, sl])
            if mbr == "force_sensor_gain":
                tab = {**tab, "g_p": _gain_as_pressure_gain(tab)}
            interp[mbr] = tab
        out.append(ConfoundedGroup(
            members=tuple(members), interpretations=interp,
            evidence={"pairs": [p for p in pairs if p["member"] in g]},
            separating_experiment=separating_experiment(members),
            signature="; ".join(f"{m}: {design.extensions[m].signature}" for m in members)))
    return out


__all__ = ["lookalike_pairs", "confounded_groups", "LOOKALIKE_SHARE"]
