"""Importing ppamsafety changes no global state of the user's process (issue 7).

In particular no matplotlib backend is selected and pyplot is not imported:
the report's figures are pyplot-free ``matplotlib.figure.Figure`` objects.
Checked in a fresh interpreter, after importing every module of the package.
"""

import json
import subprocess
import sys

_SCRIPT = r"""
import importlib, json, pkgutil, sys
import matplotlib
before = dict.__getitem__(matplotlib.rcParams, "backend")   # raw value, resolves nothing
import ppamsafety
names = [m.name for m in pkgutil.walk_packages(ppamsafety.__path__, "ppamsafety.")]
for n in names:
    importlib.import_module(n)
after = dict.__getitem__(matplotlib.rcParams, "backend")
print(json.dumps({"modules": names, "pyplot": "matplotlib.pyplot" in sys.modules,
                  "same_backend": before is after or before == after}))
"""


def test_importing_every_module_leaves_matplotlib_alone():
    r = subprocess.run([sys.executable, "-c", _SCRIPT], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout.strip().splitlines()[-1])
    assert "ppamsafety.plots.figure" in out["modules"]
    assert "ppamsafety.plots.control" in out["modules"]
    assert not out["pyplot"], "some ppamsafety module imports matplotlib.pyplot"
    assert out["same_backend"], "some ppamsafety module selects a matplotlib backend"


def test_figures_need_no_pyplot(tmp_path):
    """A study figure renders to PNG in a process where pyplot was never imported."""
    script = r"""
import sys
from ppamsafety import design
from ppamsafety.params import thesis_arm
fig = design.torque_function_curves(thesis_arm(), n=21).plot()
fig.savefig(sys.argv[1], dpi=50)
print("matplotlib.pyplot" in sys.modules)
"""
    png = tmp_path / "tf.png"
    r = subprocess.run([sys.executable, "-c", script, str(png)], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip().splitlines()[-1] == "False"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
