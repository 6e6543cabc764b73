"""Study files name covering and contact point files like ``ppamsafety impact`` does.

A study's ``covering`` and ``contact`` keys take a built-in name or a file (read relative to
the study file, validated when the study is loaded, the same messages as ``impact
--covering FILE``); the result table shows the file as the study file names it.
"""

import os
from pathlib import Path

import pandas as pd
import pytest

from ppamsafety.cli import main
from ppamsafety.params.contact import covering
from ppamsafety.params.contact_files import covering_to_toml
from ppamsafety.study_files import StudyFileError, load_study, run_study_file
from ppamsafety.sweep_cases import check_case, safety_case

FOAM = '''format = "ppamsafety-covering/1"
name = "10 mm PU foam"
source = "a test"
[[layer]]
name = "PU foam"
law = "thin-layer"
modulus = { value = 1.2, unit = "MPa" }
thickness = { value = 10, unit = "mm" }
strain_limit = 0.8
hysteresis = { value = 2.0, unit = "s/m" }
source = "a test"
'''

EDGE = '''format = "ppamsafety-contact/1"
name = "gripper edge"
link = 2
position = { value = 320, unit = "mm" }
shape = "edge"
radius = { value = 2, unit = "mm" }
covering = "foam.toml"
source = "a test"
'''

#: One short step case at the instant of largest speed (about 0.5 s of work).
CASE = ('[case]\nexperiment = "step"\nduration = 3.0\ncontroller = "PSMC joint"\nlam = 0.4\n'
        '[impact]\ninstants = "max TCP speed"\n')


@pytest.fixture
def folder(tmp_path, monkeypatch):
    """A study folder with a covering file, a contact point file and the thesis-implied
    covering written as a file; the working directory is elsewhere."""
    d = tmp_path / "study"
    d.mkdir()
    (d / "foam.toml").write_text(FOAM)
    (d / "edge.toml").write_text(EDGE)
    (d / "implied.toml").write_text(covering_to_toml(covering("thesis-implied")))
    elsewhere = tmp_path / "cwd"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    return d


def _study(d, grid, name="s.toml"):
    p = d / name
    p.write_text(CASE + "[grid]\n" + grid + '[output]\ncsv = "r.csv"\n')
    return p


def test_files_relative_to_the_study_file_give_what_their_names_give(folder, tmp_path):
    st = load_study(_study(folder, 'covering = ["thesis-implied", "implied.toml", "foam.toml"]\n'
                                   'contact = ["forearm", "edge.toml"]\n'))
    assert len(st.cases) == 6
    df = run_study_file(st, tmp_path / "out", processes=1, progress=False).table
    assert (df.status == "ok").all()
    F = df.set_index(["covering", "contact"])["F_max"]
    implied = str(folder / "implied.toml")
    # a covering file holding the thesis-implied covering gives its numbers exactly
    assert F[(implied, "forearm")] == F[("thesis-implied", "forearm")]
    assert F[(implied, str(folder / "edge.toml"))] == \
        F[("thesis-implied", str(folder / "edge.toml"))]
    # a softer covering lowers the force; the file's names reach the result columns
    foam = str(folder / "foam.toml")
    assert F[(foam, "forearm")] < F[("thesis-implied", "forearm")]
    row = df[(df.covering == foam) & (df.contact == str(folder / "edge.toml"))].iloc[0]
    assert row.covering_name == "10 mm PU foam" and row.contact_point == "gripper edge"
    # the same case through the library (the study's file resolved) gives the same numbers
    direct = safety_case(experiment="step", duration=3.0, controller="PSMC joint", lam=0.4,
                         instants="max TCP speed", covering=foam,
                         contact=str(folder / "edge.toml"))
    assert direct["F_max"] == row.F_max
    # the CSV names the files as the study file does
    csv = pd.read_csv(tmp_path / "out" / "r.csv")
    assert set(csv.covering) == {"thesis-implied", "implied.toml", "foam.toml"}
    assert set(csv.contact) == {"forearm", "edge.toml"}


def test_a_contact_point_file_brings_its_covering(folder, tmp_path):
    """Without a covering key the point file's own covering is used; a covering key
    replaces it."""
    st = load_study(_study(folder, 'contact = ["edge.toml"]\n'))
    own = run_study_file(st, tmp_path / "a", processes=1, progress=False).table.iloc[0]
    assert own.covering_name == "10 mm PU foam"
    st = load_study(_study(folder, 'contact = ["edge.toml"]\ncovering = ["bare metal"]\n',
                           name="t.toml"))
    bare = run_study_file(st, tmp_path / "b", processes=1, progress=False).table.iloc[0]
    assert bare.covering_name == "bare metal" and bare.F_max > own.F_max


@pytest.mark.parametrize("grid, words", [
    ('covering = ["nofile.toml"]\n', ["grid.covering[0] = 'nofile.toml'", "does not exist",
                                      "allowed", "bare metal", "covering file"]),
    ('covering = ["adir.toml"]\n', ["grid.covering[0] = 'adir.toml'", "folder"]),
    ('covering = ["kg.toml"]\n', ["grid.covering[0] = 'kg.toml'", "thickness.unit = 'kg'",
                                  "mm"]),
    ('contact = ["badlink.toml"]\n', ["grid.contact[0] = 'badlink.toml'", "link = 3",
                                      "contact point file"]),
    ('contact = ["foam.toml"]\n', ["grid.contact[0] = 'foam.toml'",
                                   "'ppamsafety-covering/1' is not 'ppamsafety-contact/1'"]),
    ('contact = ["elbw"]\n', ["grid.contact[0] = 'elbw'", "did you mean 'elbow'",
                              "contact point file"]),
    ('covering = ["foam"]\n', ["grid.covering[0] = 'foam'", "bare metal", "covering file"]),
])
def test_bad_files_are_refused_when_the_study_loads(folder, grid, words, capsys):
    (folder / "adir.toml").mkdir()
    (folder / "kg.toml").write_text(FOAM.replace('unit = "mm" }', 'unit = "kg" }'))
    (folder / "badlink.toml").write_text(EDGE.replace("link = 2", "link = 3"))
    path = _study(folder, grid)
    with pytest.raises(StudyFileError) as e:
        load_study(path)
    assert all(w in str(e.value) for w in words), str(e.value)
    out = folder.parent / "out"
    assert main(["sweep", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ppamsafety: error:") and err.count("\n") == 1, err
    assert all(w in err for w in words[:1]), err
    assert not out.exists()


def test_the_library_names_the_key_of_a_bad_file(tmp_path):
    with pytest.raises(ValueError, match=r"covering = '.*missing.toml'.*does not exist"):
        check_case(covering=str(tmp_path / "missing.toml"))
    with pytest.raises(ValueError, match=r"contact = 'nowhere'.*contact point file"):
        check_case(contact="nowhere")


def test_an_edited_covering_file_is_not_served_from_the_cache(folder):
    path = _study(folder, 'covering = ["foam.toml"]\n')
    before = load_study(path).cache_name
    (folder / "foam.toml").write_text(FOAM.replace("value = 1.2", "value = 2.4"))
    after = load_study(path).cache_name
    assert before != after and before.startswith("s [files ")
    assert load_study(_study(folder, 'covering = ["bare metal"]\n', name="n.toml")).cache_name \
        == "n"


def test_covering_values_with_units_are_shown_in_them(folder, tmp_path):
    """covering_* values written with a unit run in SI and come back in that unit."""
    path = _study(folder, 'covering_thickness = { values = [2, 8], unit = "mm" }\n')
    path.write_text(path.read_text().replace(
        '[impact]', 'covering_modulus = { value = 5, unit = "MPa" }\ncontact = "tool point"\n'
                    '[impact]'))
    st = load_study(path)
    assert [c["covering_thickness"] for c in st.cases] == [0.002, 0.008]
    assert all(c["covering_modulus"] == 5e6 for c in st.cases)
    df = run_study_file(st, tmp_path / "u", processes=1, progress=False).table
    assert df.F_max.iloc[1] < df.F_max.iloc[0]              # the thicker layer is softer
    csv = pd.read_csv(tmp_path / "u" / "r.csv")
    assert list(csv["covering_thickness [mm]"]) == [2.0, 8.0]
    assert list(csv["covering_modulus [MPa]"]) == [5.0, 5.0]
    assert "covering_thickness [mm]" in (tmp_path / "u" / "summary.html").read_text()


@pytest.mark.parametrize("line, words", [
    ('covering_thickness = { values = [2, 5], unit = "kg" }',
     ["grid.covering_thickness[0]", "'kg' is not a unit of this quantity", "mm"]),
    ('covering_thickness = { values = [2, 5000], unit = "mm" }',
     ["grid.covering_thickness[1] = '5000 mm'", "beyond the physical limit 0.2 m"]),
    ('covering_modulus = { values = [1], unit = "MPa", x = 1 }', ["grid.covering_modulus"]),
])
def test_covering_values_with_a_wrong_unit_are_refused(folder, line, words):
    with pytest.raises(StudyFileError) as e:
        load_study(_study(folder, line + "\n"))
    assert all(w in str(e.value) for w in words), str(e.value)
