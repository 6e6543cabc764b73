"""The top-level namespace: ``import ppamsafety`` is fast and offers the everyday entry points."""

import importlib
import inspect
import subprocess
import sys

import pytest

import ppamsafety
from ppamsafety import _ENTRY_POINTS


def test_importing_the_package_loads_no_physics():
    """The names are loaded on first use: importing the package imports neither numpy nor
    numba nor any subpackage."""
    code = ("import sys, ppamsafety; "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in "
            "('numpy', 'numba', 'pandas', 'scipy') or m.startswith('ppamsafety.')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "['ppamsafety._version']"


@pytest.mark.parametrize("name", sorted(_ENTRY_POINTS))
def test_every_entry_point_is_the_documented_object(name):
    module, attribute = _ENTRY_POINTS[name]
    expected = importlib.import_module(module)
    if attribute is not None:
        expected = getattr(expected, attribute)
    assert getattr(ppamsafety, name) is expected
    assert name in ppamsafety.__all__ and name in dir(ppamsafety)
    assert callable(getattr(ppamsafety, name))


def test_diagnose_is_the_front_door_whichever_way_it_is_reached():
    """``ppamsafety.diagnose`` is both the subpackage and the front door: calling it calls
    :func:`ppamsafety.diagnose.diagnosis.diagnose` (with its signature), and the
    subpackage still imports as a module."""
    import ppamsafety.diagnose as package
    from ppamsafety.diagnose.diagnosis import diagnose

    assert ppamsafety.diagnose is package
    assert inspect.signature(ppamsafety.diagnose) == inspect.signature(diagnose)
    with pytest.raises(TypeError, match="data"):
        ppamsafety.diagnose(object())


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'simulat'"):
        ppamsafety.simulat


def test_version_on_the_command_line():
    out = subprocess.run([sys.executable, "-m", "ppamsafety.cli", "--version"],
                         capture_output=True, text=True, check=True).stdout
    assert out.strip() == f"ppamsafety {ppamsafety.__version__}"


def test_load_arm_is_the_front_door_every_command_uses():
    """``ps.load_arm`` checks an arm's physics too (the likely unit slip named), as the
    commands do, not only its data."""
    import ppamsafety.design
    assert ppamsafety.load_arm is ppamsafety.design.load_arm
