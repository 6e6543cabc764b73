"""The thesis revisited with the plant effects: muscle hysteresis (thesis §3.5.1.6, §3.6).

The nominal plant has no muscle hysteresis; the thesis shows it matters on
the real arm (§3.5.1.6, figs. 3.1-3.2; §3.6).  This study switches it on in
the plant truth only (``Effects(hysteresis_delta=(0.139,) * 4)``, the value
fitted for the arm's 25-fibre muscles, §3.6.5; the controllers keep the
nominal model) and repeats

1. the static gravity-compensation validation of §3.5.1.6: set angles
   stepped in a sawtooth, static gravity compensation alone
   (:class:`~ppamsafety.control.GravityCompensation` at the set angles),
   each gradual change followed by a 3 s pause and 1 s of data;
2. Table 5.2 (circle tracking, :func:`.tracking.circle_errors`,
   :func:`.tracking.compare_with_thesis`), the tracking conclusions (a)-(f)
   (:func:`~ppamsafety.experiments.conclusions.evaluate_conclusions`) and
   Table 6.1 (worst impacts, :func:`.safety._heuristic_table`), each with
   and without hysteresis.

The set-angle sequence of fig. 3.1 is not given in the text (the figure is
not part of the reference text), so :data:`SAWTOOTH_Q1_DEG` /
:data:`SAWTOOTH_Q2_DEG` are our choice: both joints stepped up and down
together in 10 deg steps over the part of the working area the arm can hold
(see :func:`sawtooth_levels`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from types import SimpleNamespace

import numpy as np
import pandas as pd

from .._validation import as_float_array, check_range
from ..control import GravityCompensation
from ..experiments import catalog
from ..experiments.case import ExperimentCase
from ..experiments.closed_loop import run_batch
from ..experiments.conclusions import conclusions_table, evaluate_conclusions
from ..experiments.trajectories import (REFERENCE_ROW, SAWTOOTH_Q1_DEG,  # noqa: F401
                                         SAWTOOTH_Q2_DEG, Reference, check_reference_size,
                                         experiment_references)
from ..hysteresis import DELTA_25_FIBRES
from ..markdown import markdown_table
from ..params import thesis_arm
from ..params.effects import Effects
from ..plant import geometry as geo
from ..plant.model import hysteresis_factors
from ..plant.muscle import muscle_force
from ..plots.effects import (plot_ratio_shift, plot_sawtooth_angles, plot_sawtooth_errors,
                             plot_sawtooth_forces)
from . import (Section, SectionInfo, checked_compute, compares_to_thesis, other_arm_note,
               resolve_arm, resolve_head_model, responses, safety, tracking)
from ..results import Result

#: This section in the report: what it shows (the README table), the thesis parts it
#: reproduces, and its wall time [s] in a full report on 2 cores with a cold kernel cache
#: (measured 2026-11-23), the order a first report starts the sections in.
SECTION = SectionInfo(
    summary=("the gravity-compensation sawtooth with and without Preisach hysteresis, Tables 5.2 "
             "and 6.1 regenerated with hysteresis"),
    thesis="§3.5.1.6, §3.6, figs. 3.1-3.2", typical_seconds=14.0, scope="hysteresis")

#: Hysteresis scale delta per muscle group (25-fibre muscles, thesis §3.6.5) [-].
HYSTERESIS_DELTA = DELTA_25_FIBRES
#: RMS angle errors of the thesis' gravity-compensation validation (§3.5.1.6) [deg].
THESIS_RMS_DEG = {"q1": 2.47, "q2": 2.06}
#: Duration of each gradual change of the set angles [s] (our choice; "gradual", §3.5.1.6).
RAMP_S = 1.0
#: Pause after each change before the data are taken [s] (§3.5.1.6).
SETTLE_S = 3.0
#: Data window after the pause [s] (§3.5.1.6).
WINDOW_S = 1.0
#: One tooth of the set-angle sawtooth [deg] (our choice, see the module docstring).
#: Teeth of the full sawtooth.
TEETH = 2
#: Variant whose limit cycle at P = 20 s is followed (see :mod:`.tracking`).
LIMIT_CYCLE_VARIANT = "PSMC joint Ki=12 λ=0.4"
#: Thesis muscle groups of link 2 (fig. 3.2): F3 contracts when q2 rises, F4 extends.
LINK2_GROUPS = (3, 4)


def hysteresis_arm(arm, delta: float = HYSTERESIS_DELTA):
    """``arm`` with the muscle-force hysteresis (3.35) of scale ``delta`` in every group.

    Parameters
    ----------
    arm : ppamsafety.params.ArmParameters
        Nominal arm (its other effects are kept).
    delta : float
        Hysteresis scale delta of (3.35) [-], in [0, 1].

    Returns
    -------
    ppamsafety.params.ArmParameters
        The same arm whose plant truth carries the hysteresis.
    """
    return arm.replace(effects=replace(arm.effects, hysteresis_delta=(float(delta),) * 4))


def sawtooth_levels(*, quick: bool = False, arm=None) -> np.ndarray:
    """Set angles of the sawtooth, one row per level (start level first) [rad].

    Parameters
    ----------
    quick : bool
        One short tooth (30-55-80-55-30 deg on q1) instead of :data:`TEETH`
        teeth of 10 deg steps.
    arm : ArmParameters, optional
        The arm whose working area places the levels (default the thesis arm: the values
        above; another arm: the same fractions of its joint ranges,
        :func:`~ppamsafety.experiments.trajectories.experiment_references`).

    Returns
    -------
    numpy.ndarray, shape (m, 2)
        (q1_d, q2_d) per level [rad]; the last level closes the sawtooth at
        the start level.
    """
    refs = experiment_references(thesis_arm() if arm is None else arm)
    if not refs.thesis:
        if not quick:
            return refs.sawtooth_levels(TEETH)
        (a1, b1), (a2, b2) = ((min(v), max(v)) for v in (refs.sawtooth_q1, refs.sawtooth_q2))
        return np.array([[a1, a2], [(a1 + b1) / 2, (a2 + b2) / 2], [b1, b2],
                         [(a1 + b1) / 2, (a2 + b2) / 2], [a1, a2]])
    if quick:
        q1 = (30.0, 55.0, 80.0, 55.0, 30.0)
        q2 = (-95.0, -70.0, -45.0, -70.0, -95.0)
    else:
        q1 = SAWTOOTH_Q1_DEG * TEETH + SAWTOOTH_Q1_DEG[:1]
        q2 = SAWTOOTH_Q2_DEG * TEETH + SAWTOOTH_Q2_DEG[:1]
    return np.radians(np.stack([q1, q2], 1))


def sawtooth_reference(arm, levels, *, ramp: float = RAMP_S, settle: float = SETTLE_S,
                       window: float = WINDOW_S, dt: float = 1e-3):
    """Joint reference of the sawtooth: hold, then per level a smooth ramp, a pause and data.

    The first level is held for ``settle + window``; each further level is
    reached by a raised-cosine ramp of ``ramp`` seconds and held for
    ``settle + window``.  The data window of each level is its last
    ``window`` seconds.

    Parameters
    ----------
    arm : ppamsafety.params.ArmParameters
        Arm (for the TCP columns).
    levels : array_like, shape (m, 2)
        Set angles per level [rad].
    ramp : float
        Duration of each change [s].
    settle : float
        Pause after each change [s].
    window : float
        Data window [s].
    dt : float
        Sample period [s].

    Returns
    -------
    reference : Reference
        The sampled reference.
    windows : numpy.ndarray, shape (m, 2) of int
        First and one-past-last sample index of each level's data window.
    """
    lv = as_float_array("levels", levels, shape_tail=(2,), ndim=2)
    if lv.shape[0] < 2:
        raise ValueError(f"levels must have shape (m >= 2, 2), got {lv.shape}")
    ramp, settle, window = (check_range(name, v, 0.0, 1e4, lo_open=True, unit="s")
                            for name, v in (("ramp", ramp), ("settle", settle),
                                            ("window", window)))
    dt = check_range("dt", dt, 1e-5, 0.1, unit="s")
    hold = settle + window
    t_start = [0.0] + [hold + i * (ramp + hold) for i in range(lv.shape[0] - 1)]
    duration = hold + (lv.shape[0] - 1) * (ramp + hold)
    n = check_reference_size(duration, dt, 8 * REFERENCE_ROW.size + 7 * 8 * 2)
    t = np.arange(n) * dt
    q = np.tile(lv[0], (n, 1))
    qd = np.zeros((n, 2))
    qdd = np.zeros((n, 2))
    for i in range(1, lv.shape[0]):
        t0 = t_start[i]
        tau = np.clip((t - t0) / ramp, 0.0, 1.0)
        s = 0.5 * (1 - np.cos(np.pi * tau))
        on = (t >= t0)
        d = lv[i] - lv[i - 1]
        q[on] = lv[i - 1] + s[on, None] * d
        r = (t >= t0) & (t < t0 + ramp)
        qd[r] = 0.5 * np.pi / ramp * np.sin(np.pi * tau[r])[:, None] * d
        qdd[r] = 0.5 * (np.pi / ramp) ** 2 * np.cos(np.pi * tau[r])[:, None] * d
    data = REFERENCE_ROW.empty(n)
    data[:, REFERENCE_ROW.slice("q_d")] = q
    data[:, REFERENCE_ROW.slice("qd_d")] = qd
    data[:, REFERENCE_ROW.slice("qdd_d")] = qdd
    data[:, REFERENCE_ROW.slice("r_d")] = geo.forward_kinematics(q, arm)
    data[:, REFERENCE_ROW.slice("rd_d")] = np.einsum("nij,nj->ni", geo.jacobian(q, arm), qd)
    ends = np.array([t0 + (ramp if i else 0.0) + hold for i, t0 in enumerate(t_start)])
    k1 = np.minimum(np.round(ends / dt).astype(int), n)
    k0 = k1 - int(round(window / dt))
    return Reference("gravity-compensation sawtooth", t, data, dt), np.stack([k0, k1], 1)


def _direction(d):
    return np.where(d > 0, "rising", np.where(d < 0, "falling", "held"))


def sawtooth_windows(res, windows, arm, *, hysteresis: bool) -> pd.DataFrame:
    """Per data window: set and mean angles, errors, and the muscle forces vs the model.

    Parameters
    ----------
    res : ExperimentResult
        The sawtooth run.
    windows : numpy.ndarray, shape (m, 2) of int
        Sample ranges of the data windows (:func:`sawtooth_reference`).
    arm : ppamsafety.params.ArmParameters
        The arm of the run (its plant truth).
    hysteresis : bool
        Whether the plant carries hysteresis (then the plant forces are the
        model forces times the factors of
        :func:`~ppamsafety.plant.model.hysteresis_factors`).

    Returns
    -------
    pandas.DataFrame
        One row per level: ``level``, ``q{j}_d_deg``, ``q{j}_deg`` (window
        mean), ``e{j}_deg`` = mean(q - q_d), ``dir{j}`` (rising / falling /
        held / start), ``F{k}_model`` [N] (nominal law (3.9) at the logged
        pressure and contraction), ``F{k}_plant`` [N], ``F{k}_ratio`` =
        plant / model (window means), ``eps{k}`` [-].
    """
    X = res.signals("q1", "q2", "qd1", "qd2", "p1", "p2", "p3", "p4")
    qd = res.signals("q1_d", "q2_d")
    nominal = arm.replace(effects=Effects())
    if hysteresis:
        eps, fac = hysteresis_factors(X, arm)
    else:
        eps, fac = geo.contractions(X[:, :2], nominal), np.ones((X.shape[0], 4))
    f_model = np.stack([muscle_force(k + 1, eps[:, k], X[:, 4 + k], nominal)
                        for k in range(4)], 1)
    f_plant = f_model * fac
    rows = []
    for i, (k0, k1) in enumerate(windows):
        w = slice(int(k0), int(k1))
        row = {"level": i}
        for j in range(2):
            row[f"q{j + 1}_d_deg"] = float(np.degrees(qd[k1 - 1, j]))
            row[f"q{j + 1}_deg"] = float(np.degrees(X[w, j].mean()))
            row[f"e{j + 1}_deg"] = float(np.degrees((X[w, j] - qd[w, j]).mean()))
        for k in range(4):
            row[f"eps{k + 1}"] = float(eps[w, k].mean())
            row[f"F{k + 1}_model"] = float(f_model[w, k].mean())
            row[f"F{k + 1}_plant"] = float(f_plant[w, k].mean())
            row[f"F{k + 1}_ratio"] = float((f_plant[w, k] / f_model[w, k]).mean())
        rows.append(row)
    df = pd.DataFrame(rows)
    for j in (1, 2):
        d = np.diff(df[f"q{j}_d_deg"].to_numpy(), prepend=np.nan)
        df[f"dir{j}"] = np.where(np.isnan(d), "start", _direction(np.nan_to_num(d)))
    return df


def sawtooth_summary(win: pd.DataFrame, res, windows) -> dict:
    """RMS errors over the data windows and the direction-pattern counts of one run.

    Parameters
    ----------
    win : pandas.DataFrame
        Output of :func:`sawtooth_windows`.
    res : ExperimentResult
        The run (for the sample-wise RMS).
    windows : numpy.ndarray, shape (m, 2) of int
        Data windows.

    Returns
    -------
    dict
        ``rms_q1_deg``, ``rms_q2_deg`` (all samples of all windows);
        per joint j ``pattern_q{j}`` = steps where a rising set angle
        settles below / a falling one above, ``steps_q{j}``,
        ``pattern_unbiased_q{j}`` (the same for the error minus its mean over
        the windows) and ``gap_q{j}_deg`` (mean error after a falling minus
        after a rising approach of the same set angle [deg]);
        ``F3_below_q2_rising``, ``F4_above_q2_rising``, ``q2_rising``
        (windows after a q2 rise with F3 < model / F4 > model),
        ``F3_above_q2_falling``, ``F4_below_q2_falling``, ``q2_falling``;
        ``contracting_below``, ``extending_above``, ``moving_groups``
        (every group of a moving joint: force below the model when its
        contraction grew over the step, above when it shrank).
    """
    idx = np.concatenate([np.arange(a, b) for a, b in windows])
    e = res.signals("q1", "q2")[idx] - res.signals("q1_d", "q2_d")[idx]
    out = {f"rms_q{j + 1}_deg": float(np.degrees(np.sqrt(np.mean(e[:, j] ** 2))))
           for j in range(2)}
    for j in (1, 2):
        d, err = win[f"dir{j}"], win[f"e{j}_deg"]
        ok = ((d == "rising") & (err < 0)) | ((d == "falling") & (err > 0))
        out[f"pattern_q{j}"] = int(ok.sum())
        out[f"steps_q{j}"] = int(d.isin(["rising", "falling"]).sum())
        # the same without the joint's static bias (the gravity model's error): the error
        # relative to its mean over all windows
        rel = err - err.mean()
        okr = ((d == "rising") & (rel < 0)) | ((d == "falling") & (rel > 0))
        out[f"pattern_unbiased_q{j}"] = int(okr.sum())
        # hysteresis gap: mean error when the set angle was approached falling minus rising,
        # over the set angles reached both ways (0 for a plant without memory)
        key = win[f"q{j}_d_deg"].round(6)
        up = err[d == "rising"].groupby(key[d == "rising"]).mean()
        dn = err[d == "falling"].groupby(key[d == "falling"]).mean()
        both = up.index.intersection(dn.index)
        out[f"gap_q{j}_deg"] = float((dn[both] - up[both]).mean()) if len(both) else float("nan")
    up, down = win.dir2 == "rising", win.dir2 == "falling"
    out.update({"q2_rising": int(up.sum()), "q2_falling": int(down.sum()),
                "F3_below_q2_rising": int((up & (win.F3_ratio < 1)).sum()),
                "F4_above_q2_rising": int((up & (win.F4_ratio > 1)).sum()),
                "F3_above_q2_falling": int((down & (win.F3_ratio > 1)).sum()),
                "F4_below_q2_falling": int((down & (win.F4_ratio < 1)).sum())})
    below = above = moving = 0
    for k in range(1, 5):
        j = 1 if k <= 2 else 2
        mv = win[f"dir{j}"].isin(["rising", "falling"]).to_numpy()
        de = np.diff(win[f"eps{k}"].to_numpy(), prepend=np.nan)
        r = win[f"F{k}_ratio"].to_numpy()
        moving += int(mv.sum())
        below += int((mv & (de > 0) & (r < 1)).sum())
        above += int((mv & (de < 0) & (r > 1)).sum())
    out.update({"contracting_below": below, "extending_above": above, "moving_groups": moving})
    return out


def run_sawtooth(arms: dict, *, quick: bool = False):
    """The gravity-compensation sawtooth for several plants in one batch.

    Parameters
    ----------
    arms : dict
        Label -> ArmParameters (plant truth; the controller uses the nominal model).
    quick : bool
        Short sawtooth (:func:`sawtooth_levels`).

    Returns
    -------
    runs : dict
        Label -> ExperimentResult.
    windows : numpy.ndarray, shape (m, 2) of int
        Data windows (:func:`sawtooth_reference`).
    """
    first = next(iter(arms.values()))
    ref, windows = sawtooth_reference(first, sawtooth_levels(quick=quick, arm=first))
    cases = [ExperimentCase(a, GravityCompensation(at="desired"), ref, name=f"sawtooth: {lab}",
                            meta={"label": lab}) for lab, a in arms.items()]
    return dict(zip(arms, run_batch(cases))), windows


def _log_ratio_median(r) -> float:
    r = np.asarray(r, dtype=float)
    r = r[np.isfinite(r) & (r > 0)]
    return float(np.median(np.abs(np.log(r)))) if r.size else float("nan")


@dataclass
class EffectsFindings(Result):
    """Result of :func:`compute`: the thesis' experiments with and without muscle hysteresis.

    Attributes
    ----------
    quick : bool
        Short sawtooth and circle windows (numbers not comparable to the thesis).
    delta : float
        Hysteresis scale of every muscle group [-].
    cases : tuple of str
        Plant labels, ``("nominal", "hysteresis")``.
    sawtooth_runs : dict
        Label -> ExperimentResult of the sawtooth.
    sawtooth_windows : numpy.ndarray
        Data windows of the sawtooth (sample ranges).
    sawtooth : dict
        Label -> :func:`sawtooth_windows` table.
    sawtooth_summary : pandas.DataFrame
        One row per label: :func:`sawtooth_summary` values.
    warmup, evaluate : float
        Circle warm-up and evaluation window [s].
    circle_errors : dict
        Label -> :func:`.tracking.circle_errors` table (timing board).
    comparison : dict
        Label -> :func:`.tracking.compare_with_thesis` table.
    conclusions : dict
        Label -> conclusions (a)-(f).
    table_6_1 : dict
        Label -> :func:`.safety._heuristic_table` table (Table 6.1 with ratios).
    ratios : pandas.DataFrame
        Per label and table (5.2 mean, 5.2 max, 6.1 HIC, 6.1 F_max):
        median |ln ratio|, median ratio, cells.
    limit_cycle : pandas.DataFrame
        :data:`LIMIT_CYCLE_VARIANT` at P = 20 s per label: mean and max error [m].
    wall_times : dict
        Part -> wall time [s].
    metrics : dict
        Headline numbers.
    thesis : bool
        Thesis values and ratios apply: the thesis arm and head.
    arm : ArmParameters or None
        The hysteresis plant (the arm with its hysteresis).
    head : HeadContactModel or None
        The head model of Table 6.1.
    delta_assumed : bool
        The arm (not the thesis arm) declares no hysteresis: ``delta`` stands in for it.
    """

    quick: bool
    delta: float
    cases: tuple
    sawtooth_runs: dict
    sawtooth_windows: np.ndarray
    sawtooth: dict
    sawtooth_summary: pd.DataFrame
    warmup: float
    evaluate: float
    circle_errors: dict
    comparison: dict
    conclusions: dict
    table_6_1: dict
    ratios: pd.DataFrame
    limit_cycle: pd.DataFrame
    wall_times: dict
    metrics: dict = field(default_factory=dict)
    thesis: bool = True
    arm: object = None
    head: object = None
    delta_assumed: bool = False

    def to_pandas(self) -> pd.DataFrame:
        """The sawtooth summary (RMS errors and pattern counts per plant)."""
        return self.sawtooth_summary.copy()

    def stacked(self, name: str) -> pd.DataFrame:
        """A per-plant table as one table with a ``plant`` column.

        Parameters
        ----------
        name : {"sawtooth", "comparison", "table_6_1"}
            The attribute holding ``{plant: DataFrame}``.
        """
        return pd.concat([t.assign(plant=lab) for lab, t in getattr(self, name).items()],
                         ignore_index=True)

    def tables(self) -> dict:
        return {**super().tables(), **{n: self.stacked(n)
                                       for n in ("sawtooth", "comparison", "table_6_1")}}

    def figures(self) -> dict:
        """The section's figures, ``{file name: Figure}``."""
        return _figures(self)


def _figures(study) -> dict:
    """All figures of the effects study, ``{file name: Figure}``.

    Parameters
    ----------
    study : ppamsafety.sections.effects.EffectsFindings
        Output of :func:`ppamsafety.sections.effects.compute`.

    Returns
    -------
    dict
        File name -> Figure.
    """
    figs = {"effects_sawtooth_angles.png": plot_sawtooth_angles(study.sawtooth),
            "effects_sawtooth_errors.png": plot_sawtooth_errors(study.sawtooth),
            "effects_sawtooth_forces.png": plot_sawtooth_forces(study.sawtooth["hysteresis"])}
    if study.thesis:
        figs["effects_ratio_shift.png"] = plot_ratio_shift(study.comparison, study.table_6_1)
    return figs


def plants(arm, delta: float = HYSTERESIS_DELTA) -> dict:
    """The two plants of the section: ``{"nominal": ..., "hysteresis": ...}``.

    The nominal plant is ``arm`` without muscle hysteresis; the hysteresis plant is ``arm``
    with its own hysteresis, or, if it has none (the thesis arm), with ``delta`` in every
    group.

    Parameters
    ----------
    arm : ppamsafety.params.ArmParameters
        The arm.
    delta : float
        Hysteresis scale of (3.35) for an arm without one [-].

    Returns
    -------
    dict
    """
    if arm.effects.hysteresis_delta is None:
        return {"nominal": arm, "hysteresis": hysteresis_arm(arm, delta)}
    return {"nominal": arm.replace(effects=replace(arm.effects, hysteresis_delta=None)),
            "hysteresis": arm}


@checked_compute
def compute(*, quick: bool = False, arm=None, delta: float = HYSTERESIS_DELTA,
            head=None) -> EffectsFindings:
    """Sawtooth validation, Table 5.2, conclusions and Table 6.1 with and without hysteresis.

    Parameters
    ----------
    quick : bool
        One short sawtooth tooth and 1 s + 4 s circle windows instead of two
        teeth and the thesis' 5 s + 40 s.
    arm : ppamsafety.params.ArmParameters, optional
        The arm (default: the thesis arm): :func:`plants` makes the nominal plant (no
        hysteresis) and the hysteresis plant (the arm's own, else ``delta``).
    delta : float
        Hysteresis scale of (3.35) for every group [-] (thesis: 0.139), for an arm
        without hysteresis of its own.
    head : HeadContactModel, optional
        Head model of Table 6.1 (default ``thesis-frontal``).  Thesis ratios only for
        the thesis arm and head.

    Returns
    -------
    EffectsFindings
        Tables, runs and metrics.
    """
    thesis = compares_to_thesis(arm, head)
    arm = resolve_arm(arm)
    if not (isinstance(delta, (int, float)) and 0.0 < delta <= 1.0):
        raise ValueError(f"delta = {delta!r} must be a number in (0, 1]")
    arms = plants(arm, delta)
    hd = arms["hysteresis"].effects.hysteresis_delta
    delta = float(delta) if len(set(hd)) > 1 or hd[0] == delta else float(hd[0])
    walls = {}

    t0 = time.perf_counter()
    runs, windows = run_sawtooth(arms, quick=quick)
    saw = {lab: sawtooth_windows(runs[lab], windows, a, hysteresis=(lab == "hysteresis"))
           for lab, a in arms.items()}
    summ = pd.DataFrame([{"plant": lab, **sawtooth_summary(saw[lab], runs[lab], windows)}
                         for lab in arms])
    walls["sawtooth"] = time.perf_counter() - t0

    warmup, evaluate = (1.0, 4.0) if quick else (catalog.CIRCLE_WARMUP, catalog.CIRCLE_EVAL)
    errs, cmps, concl, t61 = {}, {}, {}, {}
    head = resolve_head_model(head)
    for lab, a in arms.items():
        t0 = time.perf_counter()
        errs[lab], _ = tracking.circle_errors(a, catalog.thesis_variants(), warmup=warmup,
                                              evaluate=evaluate)
        cmps[lab] = tracking.compare_with_thesis(errs[lab]) if thesis else errs[lab]
        walls[f"table_5_2 {lab}"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        resp = responses.compute(arm=a)
        concl[lab] = evaluate_conclusions(errs[lab], resp.step_table, resp.switch_table)
        t61[lab], _, _ = safety._heuristic_table(
            a, head, runs={"step": resp.step, "switch": resp.switch}, thesis=thesis)
        walls[f"responses + table_6_1 {lab}"] = time.perf_counter() - t0
    if not thesis:
        study = _compute_other(quick, delta, arms, runs, windows, saw, summ, warmup, evaluate,
                               errs, cmps, concl, t61, walls, head)
        study.delta_assumed = arm.effects.hysteresis_delta is None
        return study

    rows = []
    for lab in arms:
        for name, r in (("Table 5.2 mean", cmps[lab].ratio_mean),
                        ("Table 5.2 max", cmps[lab].ratio_max),
                        ("Table 6.1 HIC36", t61[lab].HIC_ratio),
                        ("Table 6.1 F_max", t61[lab].Fmax_ratio)):
            rr = np.asarray(r, dtype=float)
            rows.append({"plant": lab, "table": name, "median |ln ratio|": _log_ratio_median(rr),
                         "median ratio": float(np.nanmedian(rr)),
                         "min ratio": float(np.nanmin(rr)), "max ratio": float(np.nanmax(rr)),
                         "cells": int(np.isfinite(rr).sum())})
    ratios = pd.DataFrame(rows)
    lc = []
    for lab in arms:
        e = errs[lab]
        g = e[(e.variant == LIMIT_CYCLE_VARIANT) & (e.period_s == 20.0)].iloc[0]
        lc.append({"plant": lab, "variant": LIMIT_CYCLE_VARIANT, "period_s": 20.0,
                   "mean_m": float(g.mean_m), "max_m": float(g.max_m)})
    lc = pd.DataFrame(lc)
    c20 = cmps["nominal"]
    thesis_max = float(c20[(c20.variant == LIMIT_CYCLE_VARIANT)
                           & (c20.period_s == 20.0)].thesis_max_m.iloc[0])
    sm = summ.set_index("plant")
    metrics = {
        "delta": float(delta),
        "sawtooth_rms_deg": {lab: [float(sm.loc[lab, "rms_q1_deg"]),
                                   float(sm.loc[lab, "rms_q2_deg"])] for lab in arms},
        "sawtooth_pattern": {lab: {f"q{j}": [int(sm.loc[lab, f"pattern_q{j}"]),
                                             int(sm.loc[lab, f"steps_q{j}"])] for j in (1, 2)}
                             for lab in arms},
        "median_abs_log_ratio": {f"{r.plant} {r.table}": float(r["median |ln ratio|"])
                                 for _, r in ratios.iterrows()},
        "limit_cycle_max_mm": {r.plant: 1e3 * r.max_m for r in lc.itertuples()},
        "limit_cycle_thesis_max_mm": 1e3 * thesis_max,
        # "gone": the hysteresis plant's max error within twice the thesis' max
        "limit_cycle_gone": bool(lc.set_index("plant").loc["hysteresis", "max_m"]
                                 <= 2 * thesis_max),
        "conclusions": {lab: {c.key: bool(c.holds) for c in concl[lab]} for lab in arms},
        "wall_times_s": {k: round(v, 2) for k, v in walls.items()},
    }
    return EffectsFindings(quick=quick, delta=float(delta), cases=tuple(arms), sawtooth_runs=runs,
                        sawtooth_windows=windows, sawtooth=saw, sawtooth_summary=summ,
                        warmup=warmup, evaluate=evaluate, circle_errors=errs, comparison=cmps,
                        conclusions=concl, table_6_1=t61, ratios=ratios, limit_cycle=lc,
                        wall_times=walls, metrics=metrics)


def _compute_other(quick, delta, arms, runs, windows, saw, summ, warmup, evaluate, errs, cmps,
                   concl, t61, walls, head) -> EffectsFindings:
    """The rest of :func:`compute` for another arm or head: hysteresis / nominal, no thesis."""
    n_err, h_err = errs["nominal"], errs["hysteresis"]
    n_61, h_61 = t61["nominal"], t61["hysteresis"]
    rows = []
    for name, a, b in (("Table 5.2 mean", n_err.mean_m, h_err.mean_m),
                       ("Table 5.2 max", n_err.max_m, h_err.max_m),
                       ("Table 6.1 HIC36", n_61.HIC36, h_61.HIC36),
                       ("Table 6.1 F_max", n_61.F_max, h_61.F_max)):
        rr = np.asarray(b, dtype=float) / np.asarray(a, dtype=float)
        rows.append({"table": name, "median hysteresis / nominal": float(np.nanmedian(rr)),
                     "min": float(np.nanmin(rr)), "max": float(np.nanmax(rr)),
                     "cells": int(np.isfinite(rr).sum())})
    ratios = pd.DataFrame(rows)
    lc = []
    for lab in arms:
        e = errs[lab]
        g = e[(e.variant == LIMIT_CYCLE_VARIANT) & (e.period_s == 20.0)].iloc[0]
        lc.append({"plant": lab, "variant": LIMIT_CYCLE_VARIANT, "period_s": 20.0,
                   "mean_m": float(g.mean_m), "max_m": float(g.max_m)})
    lc = pd.DataFrame(lc)
    sm = summ.set_index("plant")
    metrics = {
        "delta": float(delta),
        "sawtooth_rms_deg": {lab: [float(sm.loc[lab, "rms_q1_deg"]),
                                   float(sm.loc[lab, "rms_q2_deg"])] for lab in arms},
        "median_ratio_hysteresis_over_nominal": {r.table: r["median hysteresis / nominal"]
                                                 for _, r in ratios.iterrows()},
        "limit_cycle_max_mm": {r.plant: 1e3 * r.max_m for r in lc.itertuples()},
        "conclusions": {lab: {c.key: bool(c.holds) for c in concl[lab]} for lab in arms},
        "wall_times_s": {k: round(v, 2) for k, v in walls.items()},
    }
    return EffectsFindings(quick=quick, delta=float(delta), cases=tuple(arms), sawtooth_runs=runs,
                        sawtooth_windows=windows, sawtooth=saw, sawtooth_summary=summ,
                        warmup=warmup, evaluate=evaluate, circle_errors=errs, comparison=cmps,
                        conclusions=concl, table_6_1=t61, ratios=ratios, limit_cycle=lc,
                        wall_times=walls, metrics=metrics, thesis=False,
                        arm=arms["hysteresis"], head=head)


def _yes(b) -> str:
    return "holds" if b else "does not hold"


def render(study: EffectsFindings) -> Section:
    """The report section of the effects study (formatting only).

    Parameters
    ----------
    study : EffectsFindings
        Output of :func:`compute`.

    Returns
    -------
    Section
        Markdown and artifacts (figures and CSV tables).
    """
    if not study.thesis:
        return _render_other(study)
    sm = study.sawtooth_summary.set_index("plant")
    # .at keeps each column's dtype (counts stay int)
    n, h = (SimpleNamespace(**{c: sm.at[lab, c] for c in sm.columns})
            for lab in ("nominal", "hysteresis"))
    levels = study.sawtooth["nominal"]
    q1s = ", ".join(f"{v:g}" for v in levels.q1_d_deg)
    q2s = ", ".join(f"{v:g}" for v in levels.q2_d_deg)
    saw_tab = pd.DataFrame({
        "plant": list(sm.index),
        "RMS q1 [deg] (thesis 2.47)": [f"{v:.2f}" for v in sm.rms_q1_deg],
        "RMS q2 [deg] (thesis 2.06)": [f"{v:.2f}" for v in sm.rms_q2_deg],
        "q1: rising below / falling above": [f"{a} of {b}" for a, b in
                                             zip(sm.pattern_q1, sm.steps_q1)],
        "q2: rising below / falling above": [f"{a} of {b}" for a, b in
                                             zip(sm.pattern_q2, sm.steps_q2)],
        "same, bias removed (q1; q2)": [f"{a}; {b}" for a, b in
                                        zip(sm.pattern_unbiased_q1, sm.pattern_unbiased_q2)],
        "gap falling − rising [deg] (q1; q2)": [f"{a:.2f}; {b:.2f}" for a, b in
                                                zip(sm.gap_q1_deg, sm.gap_q2_deg)]})
    rt = study.ratios.copy()
    rat = rt.pivot(index="table", columns="plant", values="median |ln ratio|")
    med = rt.pivot(index="table", columns="plant", values="median ratio")
    rat_tab = pd.DataFrame({"table": rat.index,
                            "median abs(ln ratio) nominal": [f"{v:.3f}" for v in rat.nominal],
                            "median abs(ln ratio) hysteresis": [f"{v:.3f}" for v in rat.hysteresis],
                            "median ratio nominal": [f"{v:.3g}" for v in med.nominal],
                            "median ratio hysteresis": [f"{v:.3g}" for v in med.hysteresis],
                            "toward 1": ["yes" if b < a else "no"
                                         for a, b in zip(rat.nominal, rat.hysteresis)]})
    lc = study.limit_cycle.set_index("plant")
    thesis_max = study.metrics["limit_cycle_thesis_max_mm"]
    lc_n, lc_h = 1e3 * lc.loc["nominal", "max_m"], 1e3 * lc.loc["hysteresis", "max_m"]
    gone = study.metrics["limit_cycle_gone"]
    cn = {c.key: c for c in study.conclusions["nominal"]}
    ch = {c.key: c for c in study.conclusions["hysteresis"]}
    ct = pd.DataFrame({"": [f"({k})" for k in cn], "thesis claim": [c.claim for c in cn.values()],
                       "nominal plant": [_yes(c.holds) for c in cn.values()],
                       "with hysteresis": [_yes(ch[k].holds) for k in cn]})
    changed = [f"({k})" for k in cn if cn[k].holds != ch[k].holds]
    now_hold = [f"({k})" for k in "abc" if ch[k].holds and not cn[k].holds]
    still_fail = [f"({k})" for k in "abc" if not ch[k].holds]
    cmp_h = study.comparison["hysteresis"]
    walls = study.wall_times
    md = f"""The plant truth gets the muscle-force hysteresis of §3.6 ((3.35), Preisach weight (3.33),
δ = {study.delta:g} in every muscle group, the value fitted for the arm's 25-fibre muscles, §3.6.5);
the controllers keep the nominal model. Every experiment runs on both plants.
{'**Quick mode: one short tooth and short circle windows; numbers are not comparable to the thesis.**' if study.quick else ''}

### Gravity-compensation sawtooth (§3.5.1.6, figs. 3.1-3.2)

Static gravity compensation alone ((3.18)-(3.19) at the set angles, identified gravity model of
Table 3.1). The thesis gives neither the set angles nor the step size of its sawtooth, so we chose
them: q1_d = {q1s} deg and q2_d = {q2s} deg, each change a {RAMP_S:g} s raised-cosine ramp ("gradual"),
then {SETTLE_S:g} s pause and {WINDOW_S:g} s of data (the window mean is one point of the figures).
The RMS errors are over all samples of all data windows.

{markdown_table(saw_tab)}

* **RMS errors.** Without hysteresis {n.rms_q1_deg:.2f}° / {n.rms_q2_deg:.2f}° (q1 / q2), with
  hysteresis {h.rms_q1_deg:.2f}° / {h.rms_q2_deg:.2f}°, against the thesis' 2.47° / 2.06°. The nominal
  errors are the static error of the identified gravity model alone and depend only on the set
  angle; hysteresis adds a direction-dependent part.
* **Direction pattern.** Rising set angles settle below and falling ones above in
  {h.pattern_q1} of {h.steps_q1} (q1) and {h.pattern_q2} of {h.steps_q2} (q2) steps with hysteresis, against
  {n.pattern_q1} of {n.steps_q1} and {n.pattern_q2} of {n.steps_q2} without. The q1 count is limited by the static
  bias of the gravity model on q1 (all nominal q1 errors are below the set point); relative to each
  joint's mean error the pattern holds in {h.pattern_unbiased_q1} of {h.steps_q1} (q1) and
  {h.pattern_unbiased_q2} of {h.steps_q2} (q2) steps. At the same set angle, the error after a falling
  approach exceeds that after a rising one by {h.gap_q1_deg:.2f}° (q1) and {h.gap_q2_deg:.2f}° (q2) on
  average; without hysteresis the gap is {n.gap_q1_deg:.2f}° / {n.gap_q2_deg:.2f}° (no memory).
* **Muscle forces** (plant force vs the nominal law (3.9) at the same logged pressure and
  contraction, window means). While q2 rises, F3 is below the model in {h.F3_below_q2_rising} of
  {h.q2_rising} windows and F4 above it in {h.F4_above_q2_rising} of {h.q2_rising}, as in fig. 3.2; while q2
  falls, F3 is above in {h.F3_above_q2_falling} and F4 below in {h.F4_below_q2_falling} of {h.q2_falling}. Over all
  four groups of the moving joints, a muscle whose contraction grew over the step is below the
  model in {h.contracting_below} cases and one whose contraction shrank is above it in
  {h.extending_above} ({h.moving_groups} group-steps in all) -- the thesis' "if contraction increases,
  the output force is lower than predicted by the model". Exceptions follow the Preisach memory:
  after a reversal the new branch starts from the old one's value.

![sawtooth angles](effects_sawtooth_angles.png)

![sawtooth errors](effects_sawtooth_errors.png)

![sawtooth forces](effects_sawtooth_forces.png)

### Table 5.2 and Table 6.1 with hysteresis

Table 5.2 (ten variants, three circles, timing board, {study.warmup:g} s warm-up + {study.evaluate:g} s) and
Table 6.1 (worst of the four heuristic impact instants of the step and switch runs) recomputed on
both plants with the functions of the tracking and safety sections. Median over the cells of
|ln(toolkit / thesis)| (0 = the thesis exactly):

{markdown_table(rat_tab)}

**The Ki = 12 limit cycle.** {LIMIT_CYCLE_VARIANT} at P = 20 s: max error {lc_n:.2f} mm on the nominal
plant, {lc_h:.2f} mm with hysteresis (mean {1e3 * lc.loc['nominal', 'mean_m']:.2f} / {1e3 * lc.loc['hysteresis', 'mean_m']:.2f} mm;
thesis max {thesis_max:.2f} mm). Criterion "gone": max error at most twice the thesis' max --
{'met: the hysteresis damps the slow oscillation, as hypothesised in the tracking section' if gone else 'not met: hysteresis of this size does not remove the velocity-sensor limit cycle (tracking section)'}.

**The thesis' conclusions** (criteria of `ppamsafety/experiments/conclusions.py`):

{markdown_table(ct)}

{('Conclusions that change with hysteresis: ' + ', '.join(changed) + '.') if changed else 'No verdict changes with hysteresis.'}
Of the tracking conclusions that fail on the nominal plant, {', '.join(now_hold) if now_hold else 'none'} now
hold{'; ' + ', '.join(still_fail) + (' still fails' if len(still_fail) == 1 else ' still fail') if still_fail else ''}. Evidence with hysteresis:

{markdown_table(conclusions_table(study.conclusions['hysteresis'])[['', 'verdict', 'evidence']])}

Table 5.2 with hysteresis (toolkit / thesis (ratio), mm):

{markdown_table(tracking.comparison_markdown(cmp_h))}

![ratio shift](effects_ratio_shift.png)

Wall time of this section: {sum(walls.values()):.1f} s ({', '.join(f'{k} {v:.1f} s' for k, v in walls.items())}).
"""
    arts = [("effects_sawtooth.csv", study.stacked("sawtooth")),
            ("effects_summary.csv", study.sawtooth_summary),
            ("effects_ratios.csv", study.ratios),
            ("effects_table_5_2.csv", study.stacked("comparison")),
            ("effects_table_6_1.csv", study.stacked("table_6_1")),
            ("effects_conclusions.csv", ct),
            *study.figures().items()]
    return Section("Effects: the thesis revisited with muscle hysteresis (§3.5.1.6, §3.6)", md,
                   arts, dict(study.metrics))


def _render_other(study: EffectsFindings) -> Section:
    """The effects section for another arm or head: with and without hysteresis, no thesis."""
    sm = study.sawtooth_summary.set_index("plant")
    hd = study.arm.effects.hysteresis_delta
    delta_text = (f"δ = {', '.join(f'{v:g}' for v in hd)} per muscle group, the arm's own"
                  if not study.delta_assumed else
                  f"δ = {study.delta:g} in every muscle group, ASSUMED: the arm declares no "
                  f"hysteresis, so the value fitted for the thesis' 25-fibre muscles (§3.6.5) "
                  f"stands in; declare `hysteresis_delta` in the arm file's [effects] for its "
                  f"own muscles")
    saw_tab = pd.DataFrame({
        "plant": list(sm.index),
        "RMS q1 [deg]": [f"{v:.2f}" for v in sm.rms_q1_deg],
        "RMS q2 [deg]": [f"{v:.2f}" for v in sm.rms_q2_deg],
        "q1: rising below / falling above": [f"{a} of {b}" for a, b in
                                             zip(sm.pattern_q1, sm.steps_q1)],
        "q2: rising below / falling above": [f"{a} of {b}" for a, b in
                                             zip(sm.pattern_q2, sm.steps_q2)],
        "gap falling − rising [deg] (q1; q2)": [f"{a:.2f}; {b:.2f}" for a, b in
                                                zip(sm.gap_q1_deg, sm.gap_q2_deg)]})
    cn = {c.key: c for c in study.conclusions["nominal"]}
    ch = {c.key: c for c in study.conclusions["hysteresis"]}
    ct = pd.DataFrame({"": [f"({k})" for k in cn], "thesis claim": [c.claim for c in cn.values()],
                       "nominal plant": [_yes(c.holds) for c in cn.values()],
                       "with hysteresis": [_yes(ch[k].holds) for k in cn]})
    lc = study.limit_cycle.set_index("plant")
    t61 = study.stacked("table_6_1")[["experiment", "label", "HIC36", "F_max", "plant"]]
    t61w = t61.pivot_table(index=["experiment", "label"], columns="plant",
                           values=["F_max", "HIC36"], sort=False)
    t61w.columns = [f"{v} {p}" for v, p in t61w.columns]
    t61w = t61w.reset_index()
    md = f"""{other_arm_note(study.arm, study.head)}

The plant truth with and without the muscle-force hysteresis of §3.6 ((3.35), Preisach weight
(3.33), {delta_text}); the controllers keep the nominal
model. Every experiment runs on both plants.{' (quick mode)' if study.quick else ''}

### Gravity-compensation sawtooth (§3.5.1.6)

Static gravity compensation alone at the set angles; {RAMP_S:g} s ramps, {SETTLE_S:g} s pause,
{WINDOW_S:g} s of data per level:

{markdown_table(saw_tab)}

![sawtooth angles](effects_sawtooth_angles.png)

![sawtooth errors](effects_sawtooth_errors.png)

![sawtooth forces](effects_sawtooth_forces.png)

### Tracking and impacts with and without hysteresis

Hysteresis / nominal over the cells of Table 5.2 (ten variants, three circles, {study.warmup:g} s
warm-up + {study.evaluate:g} s) and Table 6.1 (worst of the four heuristic impacts):

{markdown_table(study.ratios, digits=3)}

Worst impacts per variant (the Table 6.1 setup) on both plants:

{markdown_table(t61w, digits=4)}

{LIMIT_CYCLE_VARIANT} at P = 20 s: max error {1e3 * lc.loc['nominal', 'max_m']:.2f} mm nominal,
{1e3 * lc.loc['hysteresis', 'max_m']:.2f} mm with hysteresis.

**The thesis' conclusions on this arm** (criteria of `ppamsafety/experiments/conclusions.py`):

{markdown_table(ct)}
"""
    arts = [("effects_sawtooth.csv", study.stacked("sawtooth")),
            ("effects_summary.csv", study.sawtooth_summary),
            ("effects_ratios.csv", study.ratios),
            ("effects_table_5_2.csv", study.stacked("comparison")),
            ("effects_table_6_1.csv", t61),
            ("effects_conclusions.csv", ct),
            *study.figures().items()]
    return Section("Effects: the thesis revisited with muscle hysteresis (§3.5.1.6, §3.6)", md,
                   arts, dict(study.metrics))
