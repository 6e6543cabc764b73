"""Input validation and plausibility checks of the impact entry points (issue 8).

One test per refused / warned input class, with the issue's own examples: angles in
degrees, joint stiffness 1e6 and 1e12 N m/rad, head radius 1e-9 m, damping 1e15, and
the post-run checks (energy balance, status column).
"""

import math
import warnings

import numpy as np
import pandas as pd
import pytest

from ppamsafety.impact import contact
from ppamsafety.impact.engine import FREE_STRIDE
from ppamsafety.impact.instants import evaluate_experiment, heuristic_instants, impact_states
from ppamsafety.impact.model import (ENERGY_TOL, ImpactResults, effective_mass, simulate_impacts,
                                     stiffness_limit)
from ppamsafety.impact.reference import simulate_impact_scipy
from ppamsafety.impact.thesis_data import FIG_6_3, join_table_6_1
from ppamsafety.impact.twobody import two_body_impact
from ppamsafety.params import thesis_arm
from ppamsafety.impact.head import HeadContactModel, head_model
from ppamsafety.units import DEG

ARM = thesis_arm()
Q = np.array([50 * DEG, -80 * DEG])
QD = np.array([3.0, -1.0])
K = np.array([43.0, 27.0])


def _no_warnings(fn):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return fn()


# --- angles ----------------------------------------------------------------------------

def test_degrees_passed_as_radians_are_refused_with_a_hint():
    # the issue's example: silently returned 330 N before
    with pytest.raises(ValueError, match=r"q\[0\] = \[50.0, -80.0\] rad.*did you mean np.radians"):
        simulate_impacts(ARM, [50, -80], QD, K)
    with pytest.raises(ValueError, match="np.radians"):
        effective_mass([50.0, -80.0], [1.0, 0.0], ARM)
    with pytest.raises(ValueError, match=r"q = \[7.0, -1.0\].*2 pi"):
        simulate_impact_scipy(ARM, [7.0, -1.0], QD, K)


def test_angles_outside_the_working_area_warn_but_run():
    with pytest.warns(UserWarning, match="outside the working area"):
        r = simulate_impacts(ARM, [0.1, -0.2], QD, K, duration=0.01)
    assert r.summary.F_max.iloc[0] > 0 and r.summary.status.iloc[0] == "ok"


# --- joint stiffness vs the integration step -------------------------------------------

@pytest.mark.parametrize("k", [1e6, 1e12])
def test_stiffness_beyond_the_step_resolution_is_refused(k):
    with pytest.raises(ValueError, match=r"stiffness\[0\] = .*k <= 2.534e\+04 N m/rad.*rigid-arm"):
        simulate_impacts(ARM, Q, QD, [k, k])


def test_stiffness_limit_formula_and_the_fig_6_3_sweep_passes():
    dt = 2e-5
    h = FREE_STRIDE * dt
    from ppamsafety.plant import dynamics as dyn
    lam = np.linalg.eigvalsh(dyn.inertia_matrix(Q, ARM))[0]
    assert stiffness_limit(Q, ARM, h) == pytest.approx(lam * (2 * math.pi / (20 * h)) ** 2,
                                                       rel=1e-12)
    g = ARM.geometry
    grid = np.stack(np.meshgrid(np.linspace(g.q1_min, g.q1_max, 25),
                                np.linspace(g.q2_min, g.q2_max, 25)), -1).reshape(-1, 2)
    # fig. 6.3 sweeps k up to 6000 N m/rad at dt = 20 us: allowed everywhere in the working area
    assert stiffness_limit(grid, ARM, h).min() > 1.5 * FIG_6_3["k_max"]
    r = _no_warnings(lambda: simulate_impacts(ARM, Q, QD, [6000.0, 6000.0]))
    assert bool(r.summary.energy_ok.iloc[0])
    # the remedy in the message works: a smaller step accepts 1e6
    with pytest.raises(ValueError) as ei:
        simulate_impacts(ARM, Q, QD, [1e6, 1e6])
    dt_ok = float(ei.value.args[0].split("use dt <= ")[1].split(" s")[0])
    assert stiffness_limit(Q, ARM, FREE_STRIDE * dt_ok * 0.99) > 1e6


def test_fixed_arm_ignores_the_stiffness_limit():
    u = np.array([0.6, 0.8])
    r = simulate_impacts(ARM, Q, [0.0, 0.0], [1e12, 1e12], direction=u, head_velocity=-u,
                         fixed_arm=True, duration=0.01)
    assert r.summary.F_max.iloc[0] > 0


# --- head model vs the case ------------------------------------------------------------

def test_head_radius_and_damping_of_the_issue_are_refused_by_the_model():
    with pytest.raises(ValueError, match="radius"):
        head_model().replace(radius=1e-9)
    with pytest.raises(ValueError, match="damping"):
        head_model().replace(damping=1e15)


def test_case_whose_closing_speed_passes_through_the_head_is_refused():
    # linear undamped head, sqrt(m/k) = 8 ms: penetration 0.04 m at 5 m/s (accepted by the
    # model) but 0.064 m > radius 0.05 m at 8 m/s
    hm = HeadContactModel("soft", mass=5.0, radius=0.05, stiffness=5.0 / 0.008 ** 2,
                          exponent=1.0, damping=0.0)
    assert contact.max_penetration(5.0, 8.0, hm.stiffness, 1.0) == pytest.approx(0.064)
    u = np.array([1.0, 0.0])
    with pytest.raises(ValueError, match=r"case 1: at the closing speed 8 m/s .*'soft'"):
        simulate_impacts(ARM, Q, [0.0, 0.0], K, head=hm, direction=u,
                         head_velocity=[-4.0 * u, -8.0 * u], fixed_arm=True)


# --- speeds ----------------------------------------------------------------------------

def test_implausible_tool_speed_warns_and_absurd_speed_is_refused():
    with pytest.warns(UserWarning, match="plausible maximum 10 m/s"):
        simulate_impacts(ARM, Q, [30.0, 0.0], K, duration=0.005)
    with pytest.raises(ValueError, match=r"qd\[0, 0\] = 1e\+300 rad/s"):
        simulate_impacts(ARM, Q, [1e300, 0.0], K)


# --- shapes, types, consistency ----------------------------------------------------------

@pytest.mark.parametrize("kwargs, exc, match", [
    (dict(qd=[[1.0, 0.0]] * 4, stiffness=[[43.0, 27.0]] * 3), ValueError,
     "stiffness has 3 rows, qd has 4"),
    (dict(q="abc"), TypeError, "q must be an array of real numbers"),
    (dict(qd=[1.0, 2.0, 3.0]), ValueError, r"qd must have trailing shape \(\.\.\., 2\)"),
    (dict(stiffness=[np.nan, 1.0]), ValueError, "stiffness contains NaN"),
    (dict(stiffness=[-1.0, 2.0]), ValueError, r"stiffness\[0, 0\] = -1 N m/rad is outside"),
    (dict(direction=[0.0, 0.0]), ValueError, r"direction = \[0.0, 0.0\] is a zero vector"),
    (dict(head="martian"), ValueError, r"head = 'martian': unknown head model; choose from "
                                       r"'child-frontal'"),
    (dict(head=3.0), TypeError, "head must be a HeadContactModel or a head model name"),
    (dict(fixed_arm=1), TypeError, "fixed_arm must be True or False"),
    (dict(dt=1e-3, duration=2e-4), ValueError, "duration = 0.0002 s is shorter than dt"),
    (dict(dt=1e-8, duration=1.0), ValueError, "steps exceeds"),
    (dict(history=[0, 5]), ValueError, r"history\[1\] = 5 is outside \[0, 0\]"),
    (dict(history=[True]), TypeError, r"history\[0\] must be an integer, got a bool"),
    (dict(history="all"), TypeError, "history must be True, False or a sequence"),
    (dict(arm=None), TypeError, "arm must be a ArmParameters"),
])
def test_simulate_impacts_refuses_bad_input(kwargs, exc, match):
    args = dict(arm=ARM, q=Q, qd=QD, stiffness=K)
    args.update(kwargs)
    with pytest.raises(exc, match=match):
        simulate_impacts(args.pop("arm"), args.pop("q"), args.pop("qd"), args.pop("stiffness"),
                         **args)


def test_rows_broadcast_and_duplicate_history_indices():
    r = simulate_impacts(ARM, Q, [[3.0, -1.0], [1.0, 0.0]], K, duration=0.01, history=[1, 1])
    assert len(r) == 2 and sorted(r.histories) == [1]
    np.testing.assert_array_equal(r.summary[["q1", "q2"]].to_numpy(), [Q, Q])


# --- post-run checks ---------------------------------------------------------------------

def test_valid_cases_are_ok_and_columns_keep_their_order():
    from ppamsafety.impact import engine as eng
    r = _no_warnings(lambda: simulate_impacts(ARM, np.stack([Q, Q]), [[0.0, 0.0], QD], K))
    cols = list(r.summary.columns)
    assert cols[-2:] == ["energy_ok", "status"]
    assert cols[-2 - eng.NSUM:-2] == eng.SUMMARY_COLUMNS
    assert list(r.summary.status) == ["at rest", "ok"]
    assert abs(r.summary.E_balance_error.iloc[1]) < 1e-5 < ENERGY_TOL


def test_energy_balance_error_is_flagged():
    # a 1 ms step under-resolves the undamped linear ISO/TS 15066 forehead contact
    with pytest.warns(UserWarning, match=r"flagged for case\(s\) 0: energy balance error"):
        r = simulate_impacts(ARM, Q, QD, [1.0, 1.0], dt=1e-3, head="iso15066-forehead")
    s = r.summary.iloc[0]
    assert abs(s.E_balance_error) > ENERGY_TOL and not s.energy_ok
    assert s.status.startswith("energy balance error")


# --- results object ------------------------------------------------------------------------

def test_impact_results_methods_refuse_bad_input():
    r = simulate_impacts(ARM, Q, QD, K, duration=0.005, history=[0])
    with pytest.raises(TypeError, match="index must be"):
        r.history("a")
    with pytest.raises(KeyError, match="no history recorded"):
        r.history(3)
    with pytest.raises(ValueError, match="no history recorded"):
        r.history(3)
    with pytest.raises(ValueError, match="is not a history signal"):
        r.signal("F_max", 0)
    with pytest.raises(TypeError, match="name must be a string"):
        r.signal(1, 0)
    with pytest.raises(ValueError, match="at least one signal"):
        r.signals(index=0)
    with pytest.raises(ValueError, match="metric = 'status' is not one of"):
        r.worst("status")
    assert r.worst("F_max").F_max == r.summary.F_max.max()
    with pytest.raises(ValueError, match="no case has a finite value"):
        ImpactResults(pd.DataFrame({"x": [np.nan]})).worst("x")


# --- other entry points --------------------------------------------------------------------

def test_effective_mass_checks():
    with pytest.raises(ValueError, match="zero vector"):
        effective_mass(Q, [0.0, 0.0], ARM)
    with pytest.raises(ValueError, match="does not broadcast"):
        effective_mass(np.stack([Q] * 3), [[1.0, 0.0]] * 2, ARM)
    with pytest.raises(TypeError, match="arm must be"):
        effective_mass(Q, [1.0, 0.0], "thesis")
    m = effective_mass(np.stack([Q] * 3), [1.0, 0.0], ARM)
    assert m.shape == (3,) and np.all(np.isfinite(m)) and np.all(m > 0)


def test_two_body_impact_checks():
    with pytest.raises(TypeError, match="arm_mass must be an array of real numbers"):
        two_body_impact([1.0], arm_mass="heavy", stiffness=1e6, exponent=1.5)
    with pytest.raises(ValueError, match="head_mass .* does not broadcast"):
        two_body_impact([1.0, 2.0], arm_mass=2.0, head_mass=[5.0] * 3, stiffness=1e6,
                        exponent=1.5)
    with pytest.raises(ValueError, match=r"arm_mass contains NaN"):
        two_body_impact([1.0], arm_mass=np.nan, stiffness=1e6, exponent=1.5)
    r = two_body_impact([1.0], arm_mass=np.inf, stiffness=1e6, exponent=1.5)
    assert r["F_max"][0] > 0


def test_contact_closed_forms_refuse_overflow():
    with pytest.raises(ValueError, match="v0 = 1e\\+10 m/s is outside"):
        contact.max_penetration(5.0, 1e10, 1e6, 1.5)
    with pytest.raises(ValueError, match="overflows"):
        contact.exit_velocity(5.0, 1e3, 1e-300, 1.5, 1e20)


def test_reference_and_instants_checks():
    with pytest.raises(ValueError, match="method = 'Euler' is not one of"):
        simulate_impact_scipy(ARM, Q, QD, K, method="Euler")
    with pytest.raises(ValueError, match="tool is at rest"):
        simulate_impact_scipy(ARM, Q, [0.0, 0.0], K)
    with pytest.raises(TypeError, match="result must be a ExperimentResult"):
        evaluate_experiment(None, ARM)
    with pytest.raises(TypeError, match="result must be a ExperimentResult"):
        impact_states({"q1": 1}, ARM)
    with pytest.raises(ValueError, match="states has no rows"):
        heuristic_instants(pd.DataFrame({"tcp_speed": [], "qd1": [], "qd2": []}))
    with pytest.raises(ValueError, match="lacks the column"):
        heuristic_instants(pd.DataFrame({"tcp_speed": [1.0]}))
    with pytest.raises(TypeError, match="results must be a pandas DataFrame"):
        join_table_6_1([1, 2])
    with pytest.raises(ValueError, match="lacks the key column"):
        join_table_6_1(pd.DataFrame({"experiment": ["step"]}))


def test_heuristic_impacts_start_from_the_rows_of_impact_states():
    """evaluate_experiment computes the joint stiffness of its four starting states only: the
    same numbers as impact_states gives for those rows, so the same impacts."""
    from ppamsafety.control import PID
    from ppamsafety.experiments import ExperimentCase, run_batch
    from ppamsafety.experiments.catalog import thesis_reference

    res = run_batch([ExperimentCase(ARM, PID(), thesis_reference(ARM, "step", duration=3.0))])[0]
    st = impact_states(res, ARM)
    assert list(st.columns) == ["t", "q1", "q2", "qd1", "qd2", "K1", "K2", "tcp_speed"]
    sub = st.iloc[list(heuristic_instants(st).values())]
    direct = simulate_impacts(ARM, sub[["q1", "q2"]].to_numpy(), sub[["qd1", "qd2"]].to_numpy(),
                              sub[["K1", "K2"]].to_numpy()).summary
    ev = evaluate_experiment(res, ARM).summary
    np.testing.assert_array_equal(ev.t0.to_numpy(), sub.t.to_numpy())
    for c in ("F_max", "HIC36", "HIC15", "tcp_speed"):
        np.testing.assert_array_equal(ev[c].to_numpy(), direct[c].to_numpy())
