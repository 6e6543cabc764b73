"""Reference results of the thesis' safety chapter (data, with citations).

Table 6.1 is keyed by the fields of the controller variants
(:data:`~ppamsafety.experiments.thesis_data.VARIANT_KEYS`: controller family,
Ki, lambda) and joined to toolkit results on them with :func:`join_table_6_1`.
"""

from __future__ import annotations

import math

import pandas as pd

from .._validation import InvalidTypeError, check_bool, describe
from ..experiments.thesis_data import join_thesis

#: Thesis Table 6.1 (§6.3.3): HIC and F_max [N] of the worst of four impact instants
#: for the step response (fig. 5.17) and the trajectory switch (fig. 5.15), printed
#: values.  Columns: label (the thesis' wording), controller (family), Ki
#: [bar/(rad s)] (the PID's own Ki for PID, None for task PSMC), lambda [s] (None
#: for PID), HIC_step, Fmax_step, HIC_switch, Fmax_switch.
TABLE_6_1 = [
    ("PID", "PID", 2.0, None, 4.81, 1524.0, 3.02, 1004.0),
    ("PSMC joint, lambda 0.4, Ki 2", "PSMC joint", 2.0, 0.4, 0.23, 338.0, 0.10, 206.0),
    ("PSMC joint, lambda 0.8, Ki 2", "PSMC joint", 2.0, 0.8, 0.05, 167.0, 0.02, 100.0),
    ("PSMC joint, lambda 1.5, Ki 2", "PSMC joint", 2.0, 1.5, 0.01, 62.0, 0.02, 96.0),
    ("PSMC joint, lambda 0.4, Ki 12", "PSMC joint", 12.0, 0.4, 0.48, 481.0, 0.14, 251.0),
    ("PSMC joint, lambda 0.8, Ki 12", "PSMC joint", 12.0, 0.8, 0.10, 233.0, 0.03, 132.0),
    ("PSMC joint, lambda 1.5, Ki 12", "PSMC joint", 12.0, 1.5, 0.02, 110.0, 0.04, 129.0),
    ("PSMC task, lambda 0.4", "PSMC task", None, 0.4, 0.29, 375.0, 0.03, 117.0),
    ("PSMC task, lambda 0.8", "PSMC task", None, 0.8, 0.05, 170.0, 0.01, 81.0),
    ("PSMC task, lambda 1.5", "PSMC task", None, 1.5, 0.01, 82.0, 0.01, 80.0),
]

#: Stiffnesses at the step-response impact instant (§6.3.3) [N m/rad].
STEP_IMPACT_STIFFNESS = (43.0, 27.0)

#: Stiffness sweep of fig. 6.3 (§6.3.4): F_max *rises* by less than 5 N (0.33 %) for k from
#: 1 to 6000 Nm/rad ("an increase of less than 5 N (or 0.33 %) for an increase of 5999
#: Nm/rad").  The figure itself is not tabulated; its level is the PID step impact of
#: Table 6.1, 1524 N at the experiment's stiffnesses (``F_level_N``), and the rise is an
#: increase (``rise_sign`` +1).
FIG_6_3 = {"k_min": 1.0, "k_max": 6000.0, "max_change_N": 5.0, "max_change_rel": 0.0033,
           "rise_sign": 1, "F_level_N": 1524.0}


def table_6_1() -> pd.DataFrame:
    """Thesis Table 6.1 (§6.3.3) as a DataFrame, one row per controller variant.

    Returns
    -------
    pandas.DataFrame
        Columns ``label``, ``controller``, ``Ki``, ``lambda`` (as printed),
        the keys ``controller_family``, ``ki_bar`` [bar/(rad s)],
        ``lambda_s`` [s] (NaN where a gain does not apply), and
        ``HIC_step``, ``Fmax_step``, ``HIC_switch``, ``Fmax_switch`` [N].
    """
    t = pd.DataFrame(TABLE_6_1, columns=["label", "controller", "Ki", "lambda", "HIC_step",
                                         "Fmax_step", "HIC_switch", "Fmax_switch"])
    nan = math.nan
    t.insert(4, "controller_family", t["controller"])
    t.insert(5, "ki_bar", [nan if pd.isna(k) else float(k) for k in t["Ki"]])
    t.insert(6, "lambda_s", [nan if pd.isna(v) else float(v) for v in t["lambda"]])
    return t


def table_6_1_long() -> pd.DataFrame:
    """Table 6.1 with one row per (variant, experiment), keyed for :func:`join_table_6_1`.

    Returns
    -------
    pandas.DataFrame
        Columns ``controller_family``, ``ki_bar``, ``lambda_s``,
        ``experiment`` (``"step"`` or ``"switch"``), ``HIC_thesis``,
        ``Fmax_thesis`` [N].
    """
    t = table_6_1()
    keys = ["controller_family", "ki_bar", "lambda_s"]
    parts = [t[keys].assign(experiment=exp, HIC_thesis=t[f"HIC_{exp}"],
                            Fmax_thesis=t[f"Fmax_{exp}"]) for exp in ("step", "switch")]
    return pd.concat(parts, ignore_index=True)


def join_table_6_1(results: pd.DataFrame, *, complete: bool | None = None) -> pd.DataFrame:
    """Add ``HIC_thesis`` and ``Fmax_thesis`` of Table 6.1 to toolkit results.

    Parameters
    ----------
    results : pandas.DataFrame
        One row per (variant, experiment) with the columns
        ``controller_family``, ``ki_bar``, ``lambda_s`` and ``experiment``.
    complete : bool, optional
        Require every Table 6.1 row of the experiments present to find a
        result (default: when all ten variants ran); see
        :func:`ppamsafety.experiments.thesis_data.join_thesis`.

    Returns
    -------
    pandas.DataFrame
        ``results`` (row order kept) with ``HIC_thesis`` and ``Fmax_thesis``.
    """
    if not isinstance(results, pd.DataFrame):
        raise InvalidTypeError(f"results must be a pandas DataFrame, got {describe(results)}")
    missing = [c for c in ("controller_family", "ki_bar", "lambda_s", "experiment")
               if c not in results.columns]
    if missing:
        raise ValueError(f"results lacks the key column(s) {missing}; needs controller_family, "
                         f"ki_bar, lambda_s, experiment")
    if complete is not None:
        complete = check_bool("complete", complete)
    return join_thesis(results, table_6_1_long(), on=("experiment",),
                       take=("HIC_thesis", "Fmax_thesis"), complete=complete,
                       what="thesis Table 6.1")


def table_6_1_pairs() -> pd.DataFrame:
    """All 20 (HIC, F_max) pairs of Table 6.1 in long form (experiment column).

    Returns
    -------
    pandas.DataFrame
        Columns ``label``, ``HIC``, ``F_max`` [N], ``experiment``.
    """
    t = table_6_1()
    a = t[["label", "HIC_step", "Fmax_step"]].rename(columns={"HIC_step": "HIC",
                                                             "Fmax_step": "F_max"})
    b = t[["label", "HIC_switch", "Fmax_switch"]].rename(columns={"HIC_switch": "HIC",
                                                                 "Fmax_switch": "F_max"})
    return pd.concat([a.assign(experiment="step"), b.assign(experiment="switch")],
                     ignore_index=True)
