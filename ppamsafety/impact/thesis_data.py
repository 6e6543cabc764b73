"""Reference results of the thesis' safety chapter (data, with citations)."""

from __future__ import annotations

import pandas as pd

#: Table 6.1: HIC and F_max [N] for the step response and the trajectory switch.
#: Columns: label, controller, Ki [bar/(rad s)], lambda [s], HIC_step, Fmax_step,
#: HIC_switch, Fmax_switch.
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

#: Stiffness sweep of fig. 6.3: F_max changes by less than 5 N (0.33 %) for k in [1, 6000].
FIG_6_3 = {"k_min": 1.0, "k_max": 6000.0, "max_change_N": 5.0, "max_change_rel": 0.0033}


def table_6_1() -> pd.DataFrame:
    """Table 6.1 as a DataFrame."""
    return pd.DataFrame(TABLE_6_1, columns=["label", "controller", "Ki", "lambda", "HIC_step",
                                            "Fmax_step", "HIC_switch", "Fmax_switch"])


def table_6_1_pairs() -> pd.DataFrame:
    """All 20 (HIC, F_max) pairs of Table 6.1 in long form (experiment column)."""
    t = table_6_1()
    a = t[["label", "HIC_step", "Fmax_step"]].rename(columns={"HIC_step": "HIC",
                                                             "Fmax_step": "F_max"})
    b = t[["label", "HIC_switch", "Fmax_switch"]].rename(columns={"HIC_switch": "HIC",
                                                                 "Fmax_switch": "F_max"})
    return pd.concat([a.assign(experiment="step"), b.assign(experiment="switch")],
                     ignore_index=True)
