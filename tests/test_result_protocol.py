"""Every public result class follows the one result protocol of ``ppamsafety.results``.

The classes are found, not listed: every public class of a public module of the package
(not ``plots``, ``params``) that defines ``to_pandas``, ``plot`` or ``figures``, or whose name
ends like a result (``Result``, ``Fit``, ``Map``, ``Diagnosis``, ``Sweep``, ``Envelope``,
``Instants``, ``Findings``, ``Verdicts``...).  Each must derive from ``Result``; the instance
checks build one of each (cheap inputs) and call the whole protocol on it.
"""

import dataclasses
import importlib
import inspect
import json
import pkgutil
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import ppamsafety
from ppamsafety.results import SCHEMA, Result, strip_unit, unit_name

RESULT_NAME = re.compile(r"(Results?|Fit|Map|Diagnosis|Sweep|Envelope|Instants|Findings|"
                         r"Verdicts)$")

#: Public classes that match the rule but are inputs or parameters, not results.
NOT_RESULTS = {
    "ppamsafety.data.measured.MeasuredData": "a measured record (input; saved by .save())",
    "ppamsafety.data.bench_import.ChannelMap": "part of an import profile (input)",
    "ppamsafety.experiments.trajectories.Reference": "a reference trajectory (input)",
    "ppamsafety.identify.excitation.FourierExcitation": "an excitation signal (input)",
    "ppamsafety.identify.static.StaticExperiment": "a synthetic data set (input)",
    "ppamsafety.impact.anywhere.BodyContact": "a contact model (parameter)",
    "ppamsafety.params.contact.BodyContact": "a contact model (parameter)",
    "ppamsafety.impact.directions.TwoBodyPredictor": "a fitted predictor (parameter)",
    "ppamsafety.study_files.Study": "a study file (input)",
    "ppamsafety.impact.layers.SeriesContact": "a contact law of layers in series (parameter)",
    "ppamsafety.sections.SectionResult": "what the report wrote for a section (file names)",
    "ppamsafety.results.Result": "the protocol itself",
}


def _public_modules():
    for m in pkgutil.walk_packages(ppamsafety.__path__, "ppamsafety."):
        parts = m.name.split(".")
        if any(p.startswith("_") for p in parts[1:]) or parts[1] in ("plots", "params"):
            continue
        yield importlib.import_module(m.name)


def _defines(cls, name):
    return any(name in vars(k) for k in cls.__mro__ if k not in (Result, object))


def result_classes():
    out = {}
    for mod in _public_modules():
        for name, obj in vars(mod).items():
            if (not inspect.isclass(obj) or obj.__module__ != mod.__name__
                    or name.startswith("_") or issubclass(obj, BaseException)):
                continue
            full = f"{obj.__module__}.{name}"
            if full in NOT_RESULTS:
                continue
            if (issubclass(obj, Result) or RESULT_NAME.search(name)
                    or any(_defines(obj, m) for m in ("to_pandas", "plot", "figures"))):
                out[full] = obj
    return out


CLASSES = result_classes()


def test_the_rule_finds_the_results():
    names = {k.rsplit(".", 1)[1] for k in CLASSES}
    for expected in ("ImpactResult", "WorstInstants", "HICResult", "HeadFit", "Campaign",
                     "SweepResult", "SafetyEnvelope", "ExperimentResult", "SafetyFindings",
                     "StiffnessMap", "Diagnosis"):
        assert expected in names
    assert len(CLASSES) >= 50


def test_names_are_singular_and_sections_are_not_studies():
    for full in CLASSES:
        name = full.rsplit(".", 1)[1]
        assert not name.endswith("Results"), full
        assert not name.endswith("Study"), full


@pytest.mark.parametrize("full", [k for k in sorted(CLASSES)])
def test_class_follows_the_protocol(full):
    cls = CLASSES[full]
    assert issubclass(cls, Result), f"{full} does not derive from ppamsafety.results.Result"
    assert _defines(cls, "plot") or _defines(cls, "figures"), full
    assert "write" not in vars(cls) or "to_dict" in vars(cls), \
        f"{full}: a write() of its own comes with its own to_dict() schema"


# ---- instances: the whole protocol on one object of each class -------------------------------
@pytest.fixture(scope="module")
def arm():
    return ppamsafety.thesis_arm()


@pytest.fixture(scope="module")
def pid_step(arm):
    from ppamsafety.experiments.catalog import run_thesis_experiment, thesis_variants
    v = [x for x in thesis_variants() if x.label == "PID"]
    return run_thesis_experiment(arm, "step", v)[0]


Q, QD, K = np.radians([50.0, -80.0]), np.array([1.0, 0.0]), np.array([43.0, 27.0])


def _impact(arm):
    from ppamsafety.impact.model import simulate_impacts
    return simulate_impacts(arm, Q[None], QD[None], K, history=True)


def _builders(arm, pid_step):
    from ppamsafety import design
    from ppamsafety.impact.hic import hic
    from ppamsafety.impact import directions as dr
    from ppamsafety.impact.anywhere import simulate_contacts
    from ppamsafety.impact.bodies import hybrid3_drop, body_from_head
    from ppamsafety.impact.clamping import simulate_clamping
    from ppamsafety.impact.instants import worst_instant
    from ppamsafety.impact.verdicts import impact_verdicts
    from ppamsafety.identify.static import identify_muscle
    from ppamsafety.sweep import run_sweep
    from ppamsafety.diagnose import diagnose
    from ppamsafety.diagnose.bench.cylinder_synth import synthesize_cylinder
    from ppamsafety.diagnose.bench.synthesize import synthesize_actuator
    from ppamsafety.thesis_fits.as_built import identifiability
    t = np.linspace(0.0, 0.02, 201)
    eps = np.linspace(0.01, 0.2, 50)
    p = np.linspace(1e5, 3e5, 50)
    return {
        "HICResult": lambda: hic(50.0 * np.sin(np.pi * t / 0.02) ** 2, 1e-4),
        "ImpactResult": lambda: _impact(arm),
        "WorstInstants": lambda: worst_instant(pid_step, arm, every=20, min_speed=1e-3),
        "ExperimentResult": lambda: pid_step,
        "DirectionSweep": lambda: dr.direction_sweep(arm, Q, QD, K, angles=[0.0, 0.2]),
        "ContactResult": lambda: simulate_contacts(arm, Q[None], QD[None], K, history=True),
        "ClampingResult": lambda: simulate_clamping(arm, Q[None], QD[None], K),
        "Verdicts": lambda: impact_verdicts(arm, Q, QD, K),
        "DropTest": lambda: hybrid3_drop(body_from_head("thesis-frontal")),
        "LSQResult": lambda: identify_muscle(1e-3 * p * (1 - eps), p, eps),
        "TorqueFunctions": lambda: design.torque_function_curves(arm, n=11),
        "StiffnessMap": lambda: design.stiffness_map(arm, n1=5, n2=5),
        "MaxLoadMap": lambda: design.max_load_map(arm, n1=5, n2=5),
        "ArmSummary": lambda: design.arm_summary(arm, n=11),
        "SweepResult": lambda: run_sweep(_square, grid={"x": [1.0, 2.0, 3.0]}, progress=False),
        "Diagnosis": lambda: diagnose(synthesize_actuator({"friction_coulomb": 10.0}, seed=16,
                                                          cycles=1)),
        "BenchDiagnosis": lambda: diagnose(synthesize_cylinder({"coulomb": 5.0}, seed=1,
                                                               cycles=4, pressures=(3e5,))),
        "Identifiability": lambda: identifiability(
            np.random.default_rng(0).normal(size=(20, 3)), ("a", "b", "c")),
    }


def _square(x):
    return {"y": x * x}


BUILT = ["HICResult", "ImpactResult", "WorstInstants", "ExperimentResult", "DirectionSweep",
         "ContactResult", "ClampingResult", "Verdicts", "DropTest", "LSQResult",
         "TorqueFunctions", "StiffnessMap", "MaxLoadMap", "ArmSummary", "SweepResult",
         "Diagnosis", "BenchDiagnosis", "Identifiability"]


#: Figures whose every axes with data shows a unit in brackets on an axis label (an image's
#: quantity is on its colour bar).
UNITS_ON_AXES = {"ArmSummary", "Verdicts", "DropTest", "CoveringFit", "DeltaFit",
                 "DirectionOptimum", "Identifiability", "SummaryFit", "PairFit", "AsBuiltFit"}


def check_protocol(res, tmp_path):
    """The whole protocol on one result object."""
    t = res.to_pandas()
    assert isinstance(t, pd.DataFrame)
    assert res.table is t or res.table.equals(t)
    name = type(res).__name__
    from matplotlib.figure import Figure
    fig = res.plot()
    assert isinstance(fig, Figure)
    if name in UNITS_ON_AXES:
        for ax in fig.axes:
            if ax.has_data() and ax.get_label() != "<colorbar>" and not ax.images:
                assert "[" in ax.get_xlabel() + ax.get_ylabel(), \
                    f"{name}: axes {ax.get_title()!r} show no unit"
    figs = res.figures()
    assert figs and all(isinstance(k, str) and isinstance(f, Figure)
                        for k, f in figs.items())
    d = res.to_dict()
    json.dumps(d, allow_nan=False)                 # JSON-ready, no NaN
    if "to_dict" not in vars(type(res)):
        assert d["schema"] == SCHEMA and d["kind"] == name
        units = res.column_units()              # the CSV names: "column [unit]"
        assert d["tables"]["table"]["columns"] == [unit_name(c, units.get(c)) for c in t.columns]
        assert [strip_unit(c)[0] for c in d["tables"]["table"]["columns"]] == \
            [strip_unit(c)[0] for c in t.columns]
    out = tmp_path / "res"
    files = res.write(out)
    assert (out / "result.json").exists() or _defines(type(res), "write")
    assert files and all(f.exists() for f in files)
    # a folder holding a user's file is refused, and the file is left alone
    user = tmp_path / "user"
    user.mkdir()
    (user / "notes.txt").write_text("mine")
    with pytest.raises(ValueError):
        res.write(user)
    assert (user / "notes.txt").read_text() == "mine"
    # the previous result is replaced only on request
    with pytest.raises(ValueError):
        res.write(out)
    res.write(out, overwrite=True)


def test_every_library_class_has_an_instance_check():
    lib = {k.rsplit(".", 1)[1] for k in CLASSES
           if not k.startswith("ppamsafety.sections.")}
    missing = lib - set(BUILT) - SLOW_BUILT
    assert not missing, f"add a builder for {sorted(missing)}"


#: Built in the slow protocol test (they run identifications, fits or sweeps of seconds).
SLOW_BUILT = {"SafetySummary", "HeadFit", "Campaign", "SafetyEnvelope", "DirectionOptimum", "WorstDirection",
              "WorstContact", "CollisionResult", "CoveringFit", "DeltaFit", "DynamicResult",
              "ConsistentResult", "ExcitationDesign", "Identification", "SummaryFit", "PairFit",
              "AsBuiltFit"}


@pytest.mark.parametrize("name", BUILT)
def test_instance_follows_the_protocol(name, arm, pid_step, tmp_path):
    res = _builders(arm, pid_step)[name]()
    assert type(res).__name__ == name
    check_protocol(res, tmp_path)


def test_result_of_scalars_is_one_row():
    @dataclasses.dataclass
    class Two(Result):
        a: float
        b: str
        c: np.ndarray

        def plot(self):
            raise AssertionError("not called")

    r = Two(1.5, "x", np.zeros(1000))
    assert r.to_pandas().to_dict("records") == [{"a": 1.5, "b": "x"}]
    assert r.to_dict()["values"] == {"a": 1.5, "b": "x"}


def test_dataclass_field_named_table_is_the_table():
    @dataclasses.dataclass(frozen=True)
    class T(Result):
        table: pd.DataFrame
        n: int = 0

        def to_pandas(self):
            return self.table

    df = pd.DataFrame({"x [m]": [1.0]})
    assert T(df).table is df


SECTIONS_QUICK = ["design", "stiffness", "responses", "lambda_sweep", "safety"]


@pytest.mark.parametrize("name", SECTIONS_QUICK)
def test_section_findings_follow_the_protocol(name, tmp_path):
    from ppamsafety.sections import section_module
    res = section_module(name).compute(quick=True)
    assert type(res).__name__.endswith("Findings")
    check_protocol(res, tmp_path)


def _slow_builders(arm, pid_step):
    from ppamsafety.data.campaign import load_campaign
    from ppamsafety.data.datasets import zillen2021_manifest
    from ppamsafety.envelope import safety_envelope
    from ppamsafety.hysteresis.tensile import fit_delta, simulate_tensile_test
    from ppamsafety.identify import excitation as ex
    from ppamsafety.data import identify_measured, load_measured
    from ppamsafety.identify.consistent import identify_dynamic_consistent
    from ppamsafety.identify.dynamic import identify_dynamic
    from ppamsafety.impact import directions as dr
    from ppamsafety.impact.anywhere import worst_contact
    from ppamsafety.impact.summary import safety_summary
    from ppamsafety.impact.covering_fit import fit_covering
    from ppamsafety.impact.head_fit import fit_thesis_head
    from ppamsafety.thesis_fits.as_built import Design, fit_as_built
    from ppamsafety.thesis_fits.summary_fit import TableDesign, fit_pair, fit_summary

    def excitation_record():
        rng = np.random.default_rng(0)
        k = np.arange(1, 6)[:, None]
        exc = ex.FourierExcitation(a=rng.normal(size=(5, 2)) * 3e4 / k,
                                   b=rng.normal(size=(5, 2)) * 3e4 / k,
                                   offset=ex.default_offset(arm))
        return ex.simulate_excitation(arm, exc, periods=2, dt=1e-3, name="ES")

    def collision():
        from ppamsafety.control import PID
        from ppamsafety.control.estimation import ForceEstimator
        from ppamsafety.experiments import ExperimentCase, run_batch
        from ppamsafety.experiments.trajectories import Reference
        from ppamsafety.experiments.catalog import thesis_reference
        from ppamsafety.impact.collision import head_touching, simulate_collision
        from ppamsafety.impact.instants import heuristic_instants, impact_states
        ref = thesis_reference(arm, "step", duration=3.0)
        free = run_batch([ExperimentCase(arm, PID(), ref, estimator=ForceEstimator())])[0]
        st = impact_states(free, arm)
        k0 = int(round(st["t"].iloc[heuristic_instants(st)["max TCP speed"]] / ref.dt))
        xh, _ = head_touching(free, k0)
        n = k0 + 300
        case = ExperimentCase(arm, PID(), Reference(ref.name, ref.t[:n], ref.data[:n], ref.dt),
                              estimator=ForceEstimator())
        return simulate_collision(case, head_position=xh)

    def delta_fit():
        rec = simulate_tensile_test(0.3, noise_std=5.0, seed=42, periods=2)
        return fit_delta(rec.eps, rec.force, rec.attrs["pressure"])

    def summary_fit():
        return fit_summary(arm, effects=("payload_mass", "valve_time_constant_factor"),
                           design=TableDesign(variants=("PID",), periods=(5.0,), warmup=1.0,
                                              window=5.0), fine=11)

    def as_built_fit():
        design = Design(variants=("PID",), periods=(5.0,), warmup=1.0, windows=(4.0,),
                        step_duration=9.0, switch_duration=10.0, sawtooth_levels=4,
                        impacts=False)
        return fit_as_built(arm, candidates=("payload_mass",), design=design,
                            max_evaluations=2)

    return {
        "SummaryFit": summary_fit,
        "PairFit": lambda: fit_pair(summary_fit(), arm, fine=5),
        "AsBuiltFit": as_built_fit,
        "HeadFit": lambda: fit_thesis_head(arm),
        "Campaign": lambda: load_campaign(zillen2021_manifest("O-ring257")),
        "SafetyEnvelope": lambda: safety_envelope(
            "covering_thickness", (0.5e-3, 30e-3), limit="iso_ts_15066",
            case={"controller": "PSMC joint", "lam": 0.4, "contact": "tool point"},
            tolerance=0.05, scan=3, processes=1),
        "DirectionOptimum": lambda: dr.worst_direction_state(arm, Q, QD, K),
        "WorstDirection": lambda: dr.worst_direction(pid_step, arm, every=20, min_speed=1e-3),
        "WorstContact": lambda: worst_contact(pid_step, arm, limits={"head (forehead)": 260.0},
                                              every=200),
        "CoveringFit": lambda: fit_covering(),
        "SafetySummary": lambda: safety_summary(arm, experiments=("step",), every=200),
        "DeltaFit": delta_fit,
        "ExcitationDesign": lambda: ex.design_excitation(arm, n_random=4, maxfev=6, seed=1),
        "DynamicResult": lambda: identify_dynamic(excitation_record(), arm),
        "ConsistentResult": lambda: identify_dynamic_consistent(
            excitation_record(), arm, sign_velocity=arm.friction_velocity),
        "Identification": lambda: identify_measured(
            load_measured(Path(__file__).parent / "data" / "measured" / "equilibria.csv"),
            "static"),
        "CollisionResult": collision,
    }


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(SLOW_BUILT))
def test_slow_instance_follows_the_protocol(name, arm, pid_step, tmp_path):
    res = _slow_builders(arm, pid_step)[name]()
    assert type(res).__name__ == name
    check_protocol(res, tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(set(__import__("ppamsafety.sections").sections.REGISTRY)
                                        - set(SECTIONS_QUICK)))
def test_slow_section_findings_follow_the_protocol(name, tmp_path):
    from ppamsafety.sections import section_module
    res = section_module(name).compute(quick=True)
    assert type(res).__name__.endswith("Findings")
    check_protocol(res, tmp_path)
