"""Property-based tests of the impact entry points (issue 8), pattern of test_properties.py.

For arbitrary (mostly invalid) input each call must raise ``TypeError``/``ValueError``
naming the argument, or return a finite result (summary values finite, or the case
flagged in ``status`` with a warning).  Counts per entry point are printed and written to
``$PPAMSAFETY_PROPERTY_COUNTS/property_counts_impact.txt`` when that variable names a folder.
"""

import math

import numpy as np
import pandas as pd
import pytest
hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from property_support import Recorder, anything, numbers, special  # noqa: E402

from ppamsafety.impact import contact  # noqa: E402
from ppamsafety.impact import engine as eng  # noqa: E402
from ppamsafety.impact.instants import heuristic_instants  # noqa: E402
from ppamsafety.impact.model import effective_mass, simulate_impacts  # noqa: E402
from ppamsafety.impact.reference import simulate_impact_scipy  # noqa: E402
from ppamsafety.impact.thesis_data import join_table_6_1  # noqa: E402
from ppamsafety.impact.twobody import two_body_impact  # noqa: E402
from ppamsafety.params import thesis_arm  # noqa: E402
from ppamsafety.units import DEG  # noqa: E402

FAST = settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
SLOW = settings(max_examples=30, deadline=None, suppress_health_check=list(HealthCheck))
ARM = thesis_arm()
Q = np.array([50 * DEG, -80 * DEG])
QD = np.array([3.0, -1.0])
K = np.array([43.0, 27.0])

pairs = st.one_of(st.lists(st.one_of(numbers, special), min_size=0, max_size=3),
                  st.tuples(st.floats(-8.0, 8.0), st.floats(-8.0, 8.0)),
                  st.lists(st.tuples(st.floats(-3.0, 3.0), st.floats(-3.0, 3.0)), min_size=1,
                           max_size=3),
                  anything)


_REC = Recorder("impact", ignore=(UserWarning,))
outcome = _REC.outcome


@pytest.fixture(scope="module", autouse=True)
def _report_counts():
    yield
    _REC.report()


def _summary_sane(r):
    s = r.summary
    num = s[eng.SUMMARY_COLUMNS].to_numpy()
    ok = np.isfinite(num).all(axis=1)
    # a non-finite value is never silent: the case is flagged
    assert all(st_.startswith("non-finite") or "non-finite" in st_
               for st_ in s.status[~ok]), s.status[~ok].tolist()
    assert set(s.energy_ok[s.status == "ok"]) <= {True}


SIM_ARGS = ["q", "qd", "stiffness", "direction", "head_velocity", "head", "fixed_arm", "dt",
            "duration", "history"]


@SLOW
@given(field=st.sampled_from(SIM_ARGS),
       value=st.one_of(pairs, st.sampled_from(["martian", "thesis-frontal", True, False,
                                               [0, 1], [5], 2e-5, 1e-3, 1.0])))
def test_simulate_impacts(field, value):
    kw = dict(q=Q, qd=QD, stiffness=K, duration=0.01)
    kw[field] = value
    r = outcome("simulate_impacts", lambda: simulate_impacts(
        ARM, kw.pop("q"), kw.pop("qd"), kw.pop("stiffness"), **kw), field,
        *(["q"] if field == "q" else []), "case 0", "case 1", "case 2")
    if r is not None:
        _summary_sane(r)


@FAST
@given(q=pairs, direction=pairs)
def test_effective_mass(q, direction):
    m = outcome("effective_mass", lambda: effective_mass(q, direction, ARM), "q", "direction")
    if m is not None:
        assert np.all(np.isfinite(m)) and np.all(m > 0)


@FAST
@given(field=st.sampled_from(["speed", "arm_mass", "head_mass", "stiffness", "exponent",
                              "damping", "dt", "duration"]),
       value=st.one_of(anything, st.lists(numbers, max_size=3)))
def test_two_body_impact(field, value):
    kw = dict(speed=[1.0], arm_mass=2.0, stiffness=9.5e5, exponent=1.5, damping=3.3e6,
              dt=1e-5, duration=0.01)
    kw[field] = value
    r = outcome("two_body_impact", lambda: two_body_impact(kw.pop("speed"), **kw), field)
    if r is not None:
        assert all(np.all(np.isfinite(v)) for v in r.values())


@FAST
@given(func=st.sampled_from(["max_penetration", "exit_velocity", "restitution"]),
       field=st.integers(0, 4), value=anything)
def test_contact_closed_forms(func, field, value):
    args = [5.0, 1.0, 9.5e5, 1.5, 3.3e6]
    names = ["mass", "v0", "k", "n", "b"]
    if func == "restitution":
        args, names = [1.0, 9.5e5, 3.3e6], ["v0", "k", "b"]
        field %= 3
    args[field] = value
    r = outcome(f"contact.{func}", lambda: getattr(contact, func)(*args), names[field])
    if r is not None:
        assert type(r) is float and math.isfinite(r) and r >= 0


@SLOW
@given(field=st.sampled_from(["q", "qd", "stiffness", "head", "method", "rtol", "atol", "dt",
                              "duration"]),
       value=st.one_of(anything, st.sampled_from(["RK23", "LSODA", "x"])))
def test_simulate_impact_scipy(field, value):
    kw = dict(q=Q, qd=QD, stiffness=K, dt=1e-4, duration=0.004, rtol=1e-6, atol=1e-9)
    kw[field] = value
    r = outcome("simulate_impact_scipy", lambda: simulate_impact_scipy(
        ARM, kw.pop("q"), kw.pop("qd"), kw.pop("stiffness"), **kw), field, "case 0")
    if r is not None:
        assert all(math.isfinite(r[k]) for k in ("F_max", "HIC36", "HIC15", "delta_max"))


@FAST
@given(value=st.one_of(anything, st.builds(pd.DataFrame, st.dictionaries(
    st.sampled_from(["tcp_speed", "qd1", "qd2"]), st.lists(numbers, min_size=1, max_size=1),
    min_size=1))))
def test_heuristic_instants(value):
    h = outcome("heuristic_instants", lambda: heuristic_instants(value), "states")
    if h is not None:
        assert len(h) == 4 and all(type(i) is int for i in h.values())


@FAST
@given(results=st.one_of(anything, st.just(pd.DataFrame({"experiment": ["step"]}))),
       complete=st.one_of(st.none(), st.booleans(), anything))
def test_join_table_6_1(results, complete):
    outcome("join_table_6_1", lambda: join_table_6_1(results, complete=complete), "results",
            "complete")


@FAST
@given(index=anything, name=st.one_of(anything, st.sampled_from(["F", "t", "F_max"])),
       metric=st.one_of(anything, st.sampled_from(["HIC36", "status", "nope"])))
def test_impact_results_methods(index, name, metric):
    r = _RESULT
    h = outcome("ImpactResult.history", lambda: r.history(index), "index")
    if h is not None:
        assert len(h) > 0
    s = outcome("ImpactResult.signal", lambda: r.signal(name, index), "name", "index")
    if s is not None:
        assert np.all(np.isfinite(s))
    w = outcome("ImpactResult.worst", lambda: r.worst(metric), "metric")
    if w is not None:
        assert math.isfinite(w[metric])


_RESULT = simulate_impacts(ARM, Q, QD, K, duration=0.005, history=[0])
