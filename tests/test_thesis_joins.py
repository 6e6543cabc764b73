"""Thesis Tables 5.2 and 6.1 are joined to results on the variants' fields (issue 7).

Reference values: the thesis' printed tables (Table 5.2, §5.3.5; Table 6.1,
§6.3.3), compared exactly (they are the stored data).
"""

import numpy as np
import pandas as pd
import pytest

from ppamsafety.control import SensorConfig
from ppamsafety.experiments import catalog
from ppamsafety.experiments.thesis_data import VARIANT_KEYS, join_thesis, table_5_2
from ppamsafety.impact.thesis_data import join_table_6_1, table_6_1, table_6_1_long
from ppamsafety.sections import tracking


def test_thesis_tables_are_keyed_by_the_variant_fields():
    keys = [tuple(v.keys().values()) for v in catalog.thesis_variants()]
    t52 = table_5_2()
    assert len(t52) == 30 and not t52.duplicated(list(VARIANT_KEYS) + ["period_s"]).any()
    t61 = table_6_1()
    assert len(t61) == 10 and not t61.duplicated(list(VARIANT_KEYS)).any()
    for t in (t52, t61):
        got = {(f, k, l) for f, k, l in t[list(VARIANT_KEYS)].itertuples(index=False)}
        want = set(keys)
        # NaN != NaN in a set: compare on a NaN-free encoding
        enc = lambda s: {(f, -1.0 if np.isnan(k) else k, -1.0 if np.isnan(l) else l)  # noqa: E731
                         for f, k, l in s}
        assert enc(got) == enc(want)
    # spot checks against the printed tables
    r = t52[(t52.controller_family == "PSMC joint") & (t52.ki_bar == 12.0)
            & (t52.lambda_s == 0.4) & (t52.period_s == 10.0)].iloc[0]
    assert (r.thesis_mean_m, r.thesis_max_m) == (0.0022, 0.0053)
    r = t61[(t61.controller_family == "PSMC task") & (t61.lambda_s == 0.8)].iloc[0]
    assert np.isnan(r.ki_bar) and (r.HIC_step, r.Fmax_switch) == (0.05, 81.0)
    assert r.label == "PSMC task, lambda 0.8"


def _errors_from_thesis(order):
    th = tracking.thesis_table()
    errs = th.rename(columns={"thesis_mean_m": "mean_m", "thesis_max_m": "max_m"})
    return errs.iloc[order].reset_index(drop=True)


def test_table_5_2_join_does_not_depend_on_row_order():
    n = 30
    base = tracking.compare_with_thesis(_errors_from_thesis(np.arange(n)))
    np.testing.assert_allclose(base.ratio_mean, 1.0)
    shuffled = np.random.default_rng(1).permutation(n)
    cmp = tracking.compare_with_thesis(_errors_from_thesis(shuffled))
    np.testing.assert_allclose(cmp.ratio_mean, 1.0)      # every row got its own thesis cell
    np.testing.assert_allclose(cmp.ratio_max, 1.0)
    key = ["variant", "period_s"]
    a = base.sort_values(key).reset_index(drop=True)
    b = cmp.sort_values(key).reset_index(drop=True)
    pd.testing.assert_frame_equal(a, b)


def test_joins_refuse_duplicates_and_lost_thesis_rows():
    errs = _errors_from_thesis(np.arange(30))
    with pytest.raises(ValueError, match="not unique"):
        tracking.compare_with_thesis(pd.concat([errs, errs.iloc[:1]], ignore_index=True))
    wrong = errs.copy()
    wrong.loc[wrong.lambda_s == 0.4, "lambda_s"] = 0.4000001     # all variants, keys off
    with pytest.raises(ValueError, match="found no result"):
        tracking.compare_with_thesis(wrong)
    with pytest.raises(ValueError, match="lacks key columns"):
        join_thesis(errs.drop(columns="ki_bar"), table_5_2(), on=("period_s",))
    # a subset of variants (an ablation) is fine: missing thesis rows are not required
    sub = tracking.compare_with_thesis(errs.iloc[:6])
    assert len(sub) == 6 and sub.thesis_mean_m.notna().all()


def _safety_rows(results, experiment):
    return pd.DataFrame([{"experiment": experiment, "label": r.meta["label"],
                          **r.meta["variant"].keys()} for r in results])


def test_table_6_1_join_of_real_runs_is_independent_of_variant_order(arm):
    variants = catalog.thesis_variants()
    order = np.random.default_rng(7).permutation(len(variants))
    shuffled = [variants[i] for i in order]
    kw = {"duration": 2.2, "sensors": SensorConfig.ideal()}
    a = catalog.run_thesis_experiment(arm, "step", variants, **kw)
    b = catalog.run_thesis_experiment(arm, "step", shuffled, **kw)
    ja = join_table_6_1(_safety_rows(a, "step"), complete=True)
    jb = join_table_6_1(_safety_rows(b, "step"), complete=True)
    assert list(jb.label) == [v.label for v in shuffled]           # row order of the results
    pd.testing.assert_frame_equal(ja.set_index("label").sort_index(),
                                  jb.set_index("label").sort_index())
    # and each variant got its own thesis row (checked against the printed labels)
    printed = dict(zip(table_6_1().label, table_6_1().HIC_step))
    assert ja.set_index("label").loc["PID", "HIC_thesis"] == printed["PID"] == 4.81
    assert ja.set_index("label").loc["PSMC joint Ki=12 λ=0.8", "HIC_thesis"] == printed[
        "PSMC joint, lambda 0.8, Ki 12"]
    assert ja.set_index("label").loc["PSMC task λ=1.5", "Fmax_thesis"] == 82.0
    # a shuffled run gives the same logs per variant
    by_label = {r.meta["label"]: r for r in b}
    for r in a:
        np.testing.assert_array_equal(r.log, by_label[r.meta["label"]].log)
    assert len(table_6_1_long()) == 20
