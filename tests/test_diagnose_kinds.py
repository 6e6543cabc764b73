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
