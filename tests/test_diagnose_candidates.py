"""A candidate is one object: its library, its battery draw, the gates it needs and its
separating experiments, read by the generator, the batteries and the gates.

The checks hold for every registered candidate of every kind, so a new candidate that forgets
a part (a draw the generator refuses, a truth that names no parameter, a separating
experiment of an unknown look-alike) fails here with its name.
"""

import warnings
from dataclasses import replace

import numpy as np
import pytest

from ppamsafety.data.measured import MeasuredDataWarning
from ppamsafety.diagnose import scenarios as arm_scenarios
from ppamsafety.diagnose.arm import candidates as arm_candidates
from ppamsafety.diagnose.arm.kind import ArmKind
from ppamsafety.diagnose.arm.synthesize import hidden_effects, plant_with
from ppamsafety.diagnose.bench import candidates as bench_candidates
from ppamsafety.diagnose.bench import gates as bench_gates
from ppamsafety.diagnose.bench import scenarios as bench_scenarios
from ppamsafety.diagnose.bench.design import actuator_design
from ppamsafety.diagnose.bench.kind import MuscleKind
from ppamsafety.diagnose.bench.synthesize import EFFECTS as BENCH_EFFECTS
from ppamsafety.diagnose.bench.synthesize import synthesize_actuator
from ppamsafety.diagnose.core.candidate import Candidate, Library, libraries, library
from ppamsafety.params import thesis_arm
from ppamsafety.params.effects import Effects
from ppamsafety.plant import packing
from ppamsafety.plant.layout import PLANT

ARM = arm_candidates.REGISTRY
MUSCLE = bench_candidates.MUSCLE_LIBRARY


def test_each_kind_registers_its_library_and_its_adapter_reads_it():
    assert library("arm") is ARM and library("muscle") is MUSCLE
    assert set(libraries()) >= {"arm", "muscle"}
    assert ArmKind().candidates() == tuple(ARM)
    assert MuscleKind().candidates() == bench_candidates.ACTUATOR_VOCABULARY == tuple(MUSCLE)
    for lib in (ARM, MUSCLE):
        assert all(isinstance(c, lib.cls) and isinstance(c, Candidate) for c in lib.values())


def test_the_tables_of_the_batteries_and_gates_are_read_from_the_candidates():
    assert arm_scenarios.LIBRARY_DRAWS == {n: c.draw for n, c in ARM.items()}
    assert bench_scenarios.LIBRARY_DRAWS == {n: c.draw for n, c in MUSCLE.items()}
    assert set(bench_gates.HISTORY_EFFECTS) == {n for n, c in MUSCLE.items()
                                                 if "reversals" in c.needs}
    assert set(bench_gates.PRESSURE_EFFECTS) == {n for n, c in MUSCLE.items()
                                                  if "pressure_levels" in c.needs}
    assert bench_scenarios.MOTION_EFFECTS == bench_gates.HISTORY_EFFECTS
    # every gate a candidate needs is a gate of its kind's rule
    for lib, rule in ((ARM, ArmKind.rule), (MUSCLE, MuscleKind.rule)):
        for c in lib.values():
            assert set(c.needs) <= set(rule.gates), c.name
    # a declared field names the candidate that declares it; every declarable one is drawn
    assert arm_scenarios.DECLARED_CANDIDATE == {f: n for n, c in ARM.items() for f in c.declares}
    assert set(arm_scenarios.DECLARED_DRAWS) == {n for n, c in ARM.items()
                                                 if c.declare is not None}
    # the shipped seeds' order of the declarable candidates comes first
    assert tuple(arm_scenarios.DECLARED_DRAWS)[:len(arm_scenarios.DECLARED_ORDER)] \
        == arm_scenarios.DECLARED_ORDER


@pytest.mark.parametrize("name", list(ARM))
def test_arm_draw_is_accepted_by_the_generator_and_injects_what_the_fit_writes_back(name):
    c = ARM[name]
    arm = thesis_arm()
    params = {p.name for p in c.parameters}
    for seed in range(8):
        fx, truth = c.draw(np.random.default_rng(seed), arm, 1e-3)
        assert set(truth) <= params and truth, (name, truth)
        plant, dead, meas = hidden_effects(arm, fx)          # the generator accepts them
        values = np.array([truth.get(p.name, np.nan) for p in c.parameters])
        if c.sensor_effect is not None:
            # the injected measurement error is the fault the fitted values describe
            f = c.sensor_effect(values)
            assert meas.pressure_sensor_gain == pytest.approx(f.p_gain)
            assert meas.encoder_offset == pytest.approx(f.q_offset)
            _, _, offset = plant_with(arm, {k: v for k, v in fx.items()
                                            if k == "pressure_sensor_offset"})
            assert offset == pytest.approx(f.p_offset)
        elif c.grid:
            assert dead == pytest.approx(values[0])
        elif np.all(np.isfinite(values)):
            # the plant the draw hides is the plant the fitted values write back
            back = arm.replace(effects=replace(arm.effects, **c.plant_effect(values, arm)))
            # (the plant's values; a switch may differ where a value equals the nominal one)
            values_only = np.ones(PLANT.size, bool)
            for f in PLANT.fields:
                if f.name.endswith("_mode"):
                    values_only[PLANT.slice(f.name)] = False
            np.testing.assert_allclose(packing.pack(plant)[values_only],
                                       packing.pack(back)[values_only], rtol=1e-12, atol=1e-12,
                                       err_msg=name)


@pytest.mark.parametrize("name", [n for n, c in ARM.items() if c.declare is not None])
def test_arm_declared_draw_declares_only_its_own_fields(name):
    c = ARM[name]
    assert set(c.declares) <= set(Effects.__dataclass_fields__)
    for seed in range(8):
        fx = c.declare(np.random.default_rng(seed), thesis_arm())
        assert fx and set(fx) <= set(c.declares), (name, fx)
        thesis_arm().replace(effects=replace(thesis_arm().effects, **fx))   # a valid arm


def test_muscle_draws_are_accepted_by_the_generator_and_name_the_record_s_parameters():
    law = np.asarray(bench_scenarios.random_scenario(3).options["force_law"])
    protocol = {"cycles": 3}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeasuredDataWarning)
        rec = synthesize_actuator({}, seed=1, cycles=3, force_law=tuple(law))
        des = actuator_design(rec)
    for name, c in MUSCLE.items():
        ext = des.extensions.get(name)
        for seed in range(6):
            fx, truth = c.draw(np.random.default_rng(seed), law, protocol)
            assert set(fx) <= set(BENCH_EFFECTS), (name, fx)
            synthesize_actuator(fx, seed=seed, cycles=2, force_law=tuple(law))
            if ext is not None:
                assert set(truth) <= {p.name for p in ext.parameters}, (name, truth)


def test_separating_experiments_name_registered_look_alikes_and_are_symmetric():
    for lib in (ARM, MUSCLE):
        for c in lib.values():
            assert set(c.separating) <= set(lib), c.name
    for (a, b), text in arm_candidates.SEPARATING_EXPERIMENTS.items():
        assert arm_candidates.separating_experiment(a, b) == text \
            == arm_candidates.separating_experiment(b, a)
    assert bench_candidates.separating_experiment(["force_sensor_gain", "force_law_refit"]) \
        == MUSCLE["force_sensor_gain"].separating["force_law_refit"]
    assert "dead-weight" in bench_candidates.separating_experiment(
        ["force_law_refit", "force_sensor_gain"])


def test_a_new_candidate_is_one_object_its_library_reads():
    """The recipe of ``docs/architecture.md`` on a library of its own: one object gives the
    battery its draw, the gates what they need and the look-alike its experiment."""
    lib = Library("toy", vocabulary=("drift", "offset"))

    def draw(rng, *context):
        return {"drift": float(rng.uniform())}, {"rate": 1.0}

    lib.register(Candidate("offset"))
    lib.register(Candidate("drift", draw=draw, needs=("reversals",),
                           separating={"offset": "record twice as long"}))
    assert list(lib.draws()) == ["drift"] and lib.needing("reversals") == ("drift",)
    assert lib.separating_table() == {frozenset({"drift", "offset"}): "record twice as long"}
    with pytest.raises(ValueError, match="already registered"):
        lib.register(Candidate("drift"))
    with pytest.raises(ValueError, match="not in the vocabulary"):
        lib.register(Candidate("gremlin"))
    with pytest.raises(TypeError, match="must be a"):
        lib.register("drift")
    with pytest.raises(TypeError, match="draw must be callable"):
        Candidate("x", draw=3)
    with pytest.raises(ValueError, match="separating"):
        Candidate("x", separating={"x": "itself"})
    with pytest.raises(TypeError, match="needs"):
        Candidate("x", needs=(1,))
    twice = Library("twice")
    twice.register(Candidate("a", separating={"b": "one"}))
    twice.register(Candidate("b", separating={"a": "two"}))
    with pytest.raises(ValueError, match="written twice"):
        twice.separating_table()
    with pytest.raises(ValueError, match="no candidate library"):
        library("toy")
