"""Reference results of the thesis' control chapter, keyed by the variants' fields.

Thesis tables are joined to toolkit results on the fields of the controller
variant (:class:`~ppamsafety.experiments.catalog.ControllerVariant`):
:data:`VARIANT_KEYS` = (``controller_family``, ``ki_bar``, ``lambda_s``),
never on label strings or row order.  :func:`join_thesis` does the join
(one-to-one, every thesis row must find a result when all variants ran).

* :func:`table_5_2` -- Table 5.2 (§5.3.5): mean and max of the task-space
  tracking error on the 20 cm circle, periods 5, 10, 20 s.
* Table 6.1 (HIC and F_max) lives in :mod:`ppamsafety.impact.thesis_data`
  with the same keys.
"""

from __future__ import annotations

import math

import pandas as pd

from .catalog import Family, label_of

#: Columns the thesis tables are keyed by: controller family (``"PID"``,
#: ``"PSMC joint"``, ``"PSMC task"``), integral gain Ki [bar/(rad s)] (PID and
#: joint PSMC, NaN otherwise), lambda [s] (PSMC, NaN otherwise).
VARIANT_KEYS = ("controller_family", "ki_bar", "lambda_s")

_NAN = math.nan

#: Periods of the circles of Table 5.2 [s].
TABLE_5_2_PERIODS = (5.0, 10.0, 20.0)

#: Thesis Table 5.2 (§5.3.5): mean and max of ||r_d - r|| [m] over the 40 s of
#: measurements, columns P = 5, 10, 20 s x (mean, max).  The row labels were lost
#: in the text extraction of the thesis; the variant of each row is
#: reconstructed from the discussion in §5.3.5 (the order is that of
#: Table 6.1).  Values are the printed ones (4 decimals, i.e. +-0.05 mm).
#: Rows: (controller family, Ki [bar/(rad s)], lambda [s], 6 values).
TABLE_5_2 = (
    ("PID", 2.0, _NAN, (0.0130, 0.0188, 0.0084, 0.0146, 0.0048, 0.0096)),
    ("PSMC joint", 2.0, 0.4, (0.0140, 0.0197, 0.0094, 0.0161, 0.0054, 0.0104)),
    ("PSMC joint", 2.0, 0.8, (0.0138, 0.0193, 0.0094, 0.0167, 0.0055, 0.0104)),
    ("PSMC joint", 2.0, 1.5, (0.0136, 0.0189, 0.0095, 0.0168, 0.0058, 0.0115)),
    ("PSMC joint", 12.0, 0.4, (0.0041, 0.0082, 0.0022, 0.0053, 0.0011, 0.0039)),
    ("PSMC joint", 12.0, 0.8, (0.0038, 0.0078, 0.0022, 0.0059, 0.0014, 0.0057)),
    ("PSMC joint", 12.0, 1.5, (0.0037, 0.0080, 0.0021, 0.0061, 0.0016, 0.0060)),
    ("PSMC task", _NAN, 0.4, (0.0221, 0.0447, 0.0123, 0.0277, 0.0060, 0.0144)),
    ("PSMC task", _NAN, 0.8, (0.0222, 0.0474, 0.0125, 0.0285, 0.0061, 0.0145)),
    ("PSMC task", _NAN, 1.5, (0.0222, 0.0517, 0.0125, 0.0295, 0.0063, 0.0149)),
)


def table_5_2() -> pd.DataFrame:
    """Thesis Table 5.2 (§5.3.5) in long format, keyed by :data:`VARIANT_KEYS` and ``period_s``.

    Returns
    -------
    pandas.DataFrame
        Columns ``controller_family``, ``ki_bar``, ``lambda_s``, ``variant``
        (display label, not a key), ``period_s`` [s], ``thesis_mean_m``,
        ``thesis_max_m`` [m]; one row per (variant, period), Table 6.1 order.
    """
    rows = []
    for fam, ki, lam, vals in TABLE_5_2:
        for k, P in enumerate(TABLE_5_2_PERIODS):
            rows.append({"controller_family": Family(fam).value, "ki_bar": ki, "lambda_s": lam,
                         "variant": label_of(fam, ki, lam), "period_s": P,
                         "thesis_mean_m": vals[2 * k], "thesis_max_m": vals[2 * k + 1]})
    return pd.DataFrame(rows)


def join_thesis(results: pd.DataFrame, thesis: pd.DataFrame, *, on=(), take=None,
                complete: bool | None = None, what: str = "thesis table") -> pd.DataFrame:
    """Left-join toolkit results to a thesis table on the variant fields.

    Parameters
    ----------
    results : pandas.DataFrame
        One row per result; must have the :data:`VARIANT_KEYS` columns and
        the columns ``on``.  Its row order is kept.
    thesis : pandas.DataFrame
        Thesis table with the same key columns.
    on : sequence of str
        Further key columns (e.g. ``period_s``, ``experiment``).
    take : sequence of str, optional
        Thesis columns to add (default: all non-key columns not already in
        ``results``).
    complete : bool, optional
        Require every thesis row (of the ``on`` values present in
        ``results``) to find a result.  Default (None): required when the
        results hold at least as many distinct variants as the thesis table,
        i.e. when all variants were run.
    what : str
        Table name for the error messages.

    Returns
    -------
    pandas.DataFrame
        ``results`` with the thesis columns (NaN where a result has no thesis
        row, e.g. an ablation variant).

    Raises
    ------
    ValueError
        If a key column is missing, a key occurs twice on either side, or a
        thesis row found no result although ``complete``.
    """
    keys = list(VARIANT_KEYS) + list(on)
    for name, df in (("results", results), (what, thesis)):
        missing = [k for k in keys if k not in df.columns]
        if missing:
            raise ValueError(f"join with {what}: {name} lacks key columns {missing}")
    if take is None:
        take = [c for c in thesis.columns if c not in keys and c not in results.columns]
    right = thesis[keys + list(take)]
    try:
        out = results.merge(right, on=keys, how="left", validate="one_to_one", sort=False)
    except pd.errors.MergeError as e:
        raise ValueError(f"join with {what}: keys {keys} are not unique ({e})") from None
    if complete is None:
        n_res = len(results[list(VARIANT_KEYS)].drop_duplicates())
        n_th = len(thesis[list(VARIANT_KEYS)].drop_duplicates())
        complete = n_res >= n_th
    if complete:
        expected = right[keys]
        if on:      # only the thesis rows of the experiments / periods that were run
            expected = expected.merge(results[list(on)].drop_duplicates(), on=list(on))
        hit = expected.merge(results[keys].drop_duplicates(), on=keys, how="left",
                             indicator=True)
        lost = hit[hit["_merge"] != "both"][keys]
        if len(lost):
            raise ValueError(f"join with {what}: {len(lost)} thesis row(s) found no result: "
                             f"{lost.to_dict('records')}")
    return out


def variant_keys(result) -> dict:
    """The :data:`VARIANT_KEYS` of an ``ExperimentResult`` of :func:`run_thesis_experiment`.

    Parameters
    ----------
    result : ExperimentResult
        A result of :func:`run_thesis_experiment` (its ``meta["variant"]`` is
        read).

    Raises
    ------
    ValueError
        If the result carries no variant.
    """
    meta = getattr(result, "meta", None)
    if not isinstance(meta, dict) or "variant" not in meta:
        raise ValueError("variant_keys: the result carries no variant (run it with "
                         "run_thesis_experiment)")
    return meta["variant"].keys()


__all__ = ["VARIANT_KEYS", "TABLE_5_2", "TABLE_5_2_PERIODS", "table_5_2", "join_thesis",
           "variant_keys"]
