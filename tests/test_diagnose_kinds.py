"""Record kinds are adapters the front door loops over (``diagnose.core.kind``)."""

import pytest

from ppamsafety.diagnose import diagnose, synthesize
from ppamsafety.diagnose.arm.kind import ARM, ArmKind
from ppamsafety.diagnose.bench.cylinder_synth import synthesize_cylinder
from ppamsafety.diagnose.bench.kind import CAMPAIGN, MUSCLE
from ppamsafety.diagnose.bench.synthesize import synthesize_actuator
from ppamsafety.diagnose.core.kind import RecordKind, kind_of, register_kind, registered
from ppamsafety.params import thesis_arm


@pytest.fixture(scope="module")
def records():
    camp = synthesize_cylinder({"coulomb": 5.0}, seed=1, cycles=4, pressures=(3e5,))
    return {ARM: synthesize(experiment="closed-loop", seed=1, duration=2.0),
            MUSCLE: synthesize_actuator({}, seed=0, noise="none", cycles=1),
            CAMPAIGN: camp}


def test_every_record_has_exactly_one_kind(records):
    assert set(records) <= set(registered())
    for kind, data in records.items():
        assert kind_of(data) is kind
        assert [k for k in registered() if k.accepts(data)] == [kind]
        assert kind.candidates() and kind.rule.gates


def test_a_bench_kind_refuses_the_arm_option(records):
    for kind in (MUSCLE, CAMPAIGN):
        with pytest.raises(ValueError, match="arm applies to arm records"):
            diagnose(records[kind], arm=thesis_arm())


def test_registry_refuses_a_kind_twice_and_non_kinds():
    with pytest.raises(ValueError, match="ArmKind"):
        register_kind(ArmKind())
    with pytest.raises(TypeError, match="kind"):
        register_kind(object())


def test_a_record_no_kind_accepts_names_the_registered_kinds(records):
    class Nobody(RecordKind):
        name = "nothing"

        def accepts(self, data):
            return False

    with pytest.raises(ValueError, match="arm record"):
        kind_of(object())
    assert not Nobody().accepts(records[ARM])


def test_every_kind_runs_the_one_pipeline_in_its_order():
    from ppamsafety.diagnose.arm.pipeline import ArmSteps
    from ppamsafety.diagnose.bench.campaign import CampaignSteps
    from ppamsafety.diagnose.bench.pipeline import MuscleSteps
    from ppamsafety.diagnose.core.pipeline import STAGES, Steps, run_steps

    assert STAGES == ("design", "selection", "stability", "covariance", "intervals",
                      "explained", "detection", "consistency", "gates", "regions")
    for cls in (ArmSteps, MuscleSteps, CampaignSteps):
        assert issubclass(cls, Steps)
        missing = [s for s in STAGES + ("result",) if s not in vars(cls)]
        assert not missing, (cls.__name__, missing)

    class Recorder(Steps):
        def __init__(self):
            self.calls = []

        def result(self, seconds):
            return self.calls, seconds

    for stage in STAGES:
        setattr(Recorder, stage, lambda self, s=stage: self.calls.append(s))
    calls, seconds = run_steps(Recorder())
    assert tuple(calls) == STAGES and tuple(seconds) == STAGES
    assert all(t >= 0.0 for t in seconds.values())
    with pytest.raises(NotImplementedError, match="design"):
        run_steps(Steps())
    with pytest.raises(TypeError, match="Steps"):
        run_steps(object())


def test_the_result_of_every_kind_is_typed(records):
    from ppamsafety.diagnose import ConfoundedGroup, Effect, Estimate

    named = 0
    for kind, data in records.items():
        dg = diagnose(data)
        for e in dg.effects + dg.partial:
            assert isinstance(e, Effect)
            assert all(isinstance(p, Estimate) for p in e.parameters.values())
            assert e.to_dict()["parameters"] == {k: p.to_dict() for k, p in e.parameters.items()}
        assert all(isinstance(g, ConfoundedGroup) for g in dg.confounded)
        assert dg.to_dict()["effects"] == [e.to_dict() for e in dg.effects]
        assert dg.to_dict()["confounded"] == [g.to_dict() for g in dg.confounded]
        named += len(dg.effects)
    assert named                                  # the campaign hides a Coulomb friction
    c0 = diagnose(records[CAMPAIGN]).effects[0].parameters["c0"]
    assert c0.moved and c0.unit == "N" and c0.ci_low < c0.value < c0.ci_high


def test_an_estimate_writes_the_schema_keys_in_their_order():
    from ppamsafety.diagnose import Estimate

    e = Estimate(value=-0.05, unit="kg", ci_low=-0.2, ci_high=0.1, std_error=0.07, nominal=0.0)
    assert list(e.to_dict()) == ["value", "unit", "ci_low", "ci_high", "std_error", "nominal"]
    assert not e.moved
    w = e.widened(-0.3, 0.2, ("payload",))
    assert (w.ci_low_noise, w.ci_high_noise, w.widened_by) == (-0.2, 0.1, ("payload",))
    c = w.cut(0.0, 5.0)              # a mass is not negative: cut, the raw interval kept
    assert (c.ci_low, c.ci_high, c.raw_interval) == (0.0, 0.2, (-0.3, 0.2))
    assert (c.ci_low_noise, c.ci_high_noise) == (0.0, 0.1)
    assert list(c.to_dict()) == ["value", "unit", "ci_low", "ci_high", "std_error", "nominal",
                                 "ci_low_noise", "ci_high_noise", "widened_by", "ci_low_raw",
                                 "ci_high_raw"]
    s = c.shifted(1.0)
    assert (s.value, s.ci_low, s.ci_low_noise, s.ci_low_raw) == (0.95, 1.0, 1.0, 0.7)
    assert s.nominal == 0.0 and s.moved
