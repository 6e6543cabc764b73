"""Head contact models: a free head and its Hunt-Crossley contact, named sets with provenance.

The thesis (§6.3.1) simulates a free 5 kg head and a Hunt-Crossley contact
F = k delta^n + b delta^n d(delta)/dt whose parameters Haddadin et al.
(2007) fitted to LWR-III impacts on a Hybrid III dummy head, but it does not
print k, b, n.  This module holds our reconstruction and alternatives; the
evidence and the fit are in :mod:`ppamsafety.impact.head_fit` and in the
report ("Head contact model").  A model is checked on construction against the
contact law it parametrises (:mod:`.contact`): it must stop a tool before the
head centre, in a contact the engines can integrate.

Users pick a model by name (:func:`head_model`), build their own
:class:`HeadContactModel`, or describe it in a head file (TOML, the same rules as an
arm file, :mod:`ppamsafety.params.arm_file`)::

    format = "ppamsafety-head/1"
    name = "my dummy"
    source = "drop tests of 2025-02-10, lab notebook p. 12"
    mass = { value = 4.54, unit = "kg" }
    radius = { value = 0.1, unit = "m" }
    stiffness = { value = 9.5e5, unit = "N/m^n" }      # Hunt-Crossley k
    exponent = 1.5                                     # n
    damping = { value = 3.3e6, unit = "N s/m^(n+1)" }  # lambda (b of eq. 6.2)

    [checks]       # optional: what the model is claimed to meet (head_fit.head_checks)
    hybrid_iii_drop = { met = false, note = "softer than a bare dummy on steel" }

read by :func:`load_head` / :meth:`HeadContactModel.from_toml` and written by
:meth:`HeadContactModel.to_toml` (exact round trip).  :func:`resolve_head` takes a name,
a file or a model, as every ``head=`` argument and ``--head`` option do.
"""

from __future__ import annotations

import functools
import types
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .._inputfiles import read_text
from .._validation import check_range, check_str, did_you_mean
from ..params.arm_file import ArmFileError, Key, _literal, parse_document, read_value
from ..params.iso_ts_15066 import FACE, SKULL_FOREHEAD
from .contact import hunt_crossley_force_batch, hunt_crossley_max_penetration

#: Approach speed [m/s] at which a head model is checked on construction: the
#: impact engine puts the head centre at distance ``radius`` from the tool point,
#: so the model must stop a tool that hits a free head at this speed before it
#: reaches the centre, in a contact long enough to integrate.  5 m/s is well
#: above the arm's impact speeds (thesis §6.3, Table 6.1: below 2 m/s) and the
#: ISO/TS 15066 transient-contact speeds.
CHECK_SPEED = 5.0
#: Smallest head surface radius [m]: a human head's frontal bone has a radius of
#: curvature of several cm (thesis: 0.1 m); 5 mm admits local features (nose,
#: brow) and refuses degenerate values.
MIN_RADIUS = 5.0e-3
#: Shortest admissible contact time scale delta_max / v at :data:`CHECK_SPEED` [s]:
#: ten steps of the impact engine's default 10 us RK4 step.  Stiffer or more
#: damped contacts end within a few steps and give meaningless forces and HIC.
MIN_CONTACT_TIME = 1.0e-4
#: The ``format`` string of a head file (optional on reading; refused if different).
HEAD_FORMAT = "ppamsafety-head/1"
#: The checks a head model can claim to meet (:func:`ppamsafety.impact.head_fit.head_checks`
#: computes them): the Hybrid III head drop (49 CFR 572.32), the ISO/TS 15066 effective
#: spring constants of the forehead and face (Annex A, Table A.3), the (HIC, F_max) pairs
#: of thesis Table 6.1.
CHECK_NAMES = ("hybrid_iii_drop", "iso_ts_15066", "table_6_1")


@dataclass(frozen=True)
class HeadContactModel:
    """A free head and its Hunt-Crossley contact with the robot's tool.

    Attributes
    ----------
    name : str
        Label.
    mass : float
        Head mass [kg] (thesis: 5 kg, neck neglected).
    radius : float
        Radius of the spherical head surface the tool point hits [m].
    stiffness : float
        k [N/m^n].
    exponent : float
        n [-].
    damping : float
        b [N s/m^(n+1)] (thesis eq. 6.2 writes F = k delta^n + b delta^n delta_dot).
    source : str
        Provenance of the values.
    checks : tuple of (str, bool, str)
        What the model is claimed to meet: ``(check, met, note)`` per check of
        :data:`CHECK_NAMES` (:func:`ppamsafety.impact.head_fit.head_checks`
        recomputes them and flags a wrong claim).  Not compared (like ``source``).

    Notes
    -----
    Ranges: mass (0, 100] kg, radius [5 mm, 1 m] (:data:`MIN_RADIUS`),
    stiffness (0, 1e20] N/m^n, exponent [1, 3] (Hertz: 1.5), damping
    [0, 1e20].  With F = delta^n (k + b d(delta)/dt) the force is positive
    whenever the tool approaches, so damping never makes it negative; what
    goes wrong with absurd values is the geometry and the time scale.  The
    engine starts the head centre at distance ``radius`` from the tool point,
    so construction requires that a tool hitting the free head (rigid arm) at
    :data:`CHECK_SPEED` = 5 m/s stops before the centre (maximum penetration
    < radius; refuses e.g. ``radius=1e-9``) and that this takes at least
    :data:`MIN_CONTACT_TIME` = 0.1 ms (delta_max / v; refuses e.g.
    ``damping=1e15``, which stops the tool within about 1 us).  The named
    models pass with margin (thesis-frontal: 12 mm, 2.4 ms; iso15066-face: 38 mm,
    8 ms).
    """

    name: str
    mass: float
    radius: float
    stiffness: float
    exponent: float
    damping: float
    source: str = field(default="", compare=False)
    checks: tuple = field(default=(), compare=False)

    def __post_init__(self):
        check_str("HeadContactModel.name", self.name)
        check_str("HeadContactModel.source", self.source)
        object.__setattr__(self, "checks", _check_claims(self.checks))
        model = f" (model {self.name!r})"
        for attr, lo, hi, lo_open, unit in (
                ("mass", 0.0, 100.0, True, "kg"),
                ("radius", MIN_RADIUS, 1.0, False, "m"),
                ("stiffness", 0.0, 1e20, True, "N/m^n"),
                ("exponent", 1.0, 3.0, False, ""),
                ("damping", 0.0, 1e20, False, "N s/m^(n+1)")):
            object.__setattr__(self, attr, check_range(
                f"HeadContactModel.{attr}{model}", getattr(self, attr), lo, hi, lo_open=lo_open,
                unit=unit))
        d = hunt_crossley_max_penetration(self.mass, CHECK_SPEED, self.stiffness, self.exponent,
                                          self.damping)
        params = (f"mass = {self.mass:g} kg, stiffness = {self.stiffness:g} N/m^n, "
                  f"exponent = {self.exponent:g}, damping = {self.damping:g} N s/m^(n+1)")
        if not d < self.radius:
            raise ValueError(
                f"HeadContactModel{model}: a tool hitting the free head at {CHECK_SPEED:g} m/s "
                f"would penetrate {d:.3g} m, beyond HeadContactModel.radius = {self.radius:g} m "
                f"(the head centre): HeadContactModel.stiffness too small for this radius ({params})")
        if not d / CHECK_SPEED >= MIN_CONTACT_TIME:
            raise ValueError(
                f"HeadContactModel{model}: at {CHECK_SPEED:g} m/s the contact stops the tool "
                f"within {d:.3g} m, i.e. in about {d / CHECK_SPEED:.3g} s, shorter than "
                f"{MIN_CONTACT_TIME:g} s (10 impact-engine steps): HeadContactModel.stiffness or "
                f"HeadContactModel.damping too large (or .mass too small) to be integrated ({params})")

    def replace(self, **changes) -> "HeadContactModel":
        """Return a copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            New values of fields of :class:`HeadContactModel`, by field name (as for
            :func:`dataclasses.replace`); the copy is checked like a newly
            constructed object.
        """
        return replace(self, **changes)

    def to_toml(self) -> str:
        """The TOML text of a head file describing this model (exact round trip).

        Returns
        -------
        str
            ``HeadContactModel.from_toml(model.to_toml()) == model`` (source and
            checks included).
        """
        lines = [f"format = {_literal(HEAD_FORMAT)}", f"name = {_literal(self.name)}"]
        if self.source:
            lines.append(f"source = {_literal(self.source)}")
        for key in HEAD_KEYS:
            v = getattr(self, key.attr)
            val = _literal(v) if key.unit is None else (
                f"{{ value = {_literal(v)}, unit = {_literal(key.unit)} }}")
            lines.append(f"{key.key} = {val}  # {key.doc}")
        if self.checks:
            lines += ["", "[checks]  # claimed; ppamsafety info --head FILE recomputes them"]
            for name, met, note in self.checks:
                lines.append(f"{name} = {{ met = {_literal(met)}, note = {_literal(note)} }}")
        return "\n".join(lines) + "\n"

    @classmethod
    def from_toml(cls, text: str, *, where: str = "") -> "HeadContactModel":
        """Parse and validate the TOML text of a head file (see the module docstring).

        Parameters
        ----------
        text : str
            TOML text.
        where : str
            How to name the file in error messages (its path).

        Returns
        -------
        HeadContactModel

        Raises
        ------
        ArmFileError
            A ``ValueError`` naming the key, its value and what is allowed.
        """
        return parse_document(text, _head_from_dict, where=where)

    def force(self, delta, delta_dot=0.0):
        """Hunt-Crossley contact force [N] (thesis eq. 6.2), element-wise.

        F = k delta^n + b delta^n d(delta)/dt for delta > 0, clipped at 0 (the
        contact only pushes), and 0 for delta <= 0.  Evaluated by the same
        compiled law as the impact engine
        (:func:`.contact.hunt_crossley_force`).

        Parameters
        ----------
        delta : float or array_like
            Penetration [m] (negative: gap).
        delta_dot : float or array_like
            Penetration rate [m/s]; broadcast against ``delta``.

        Returns
        -------
        numpy.ndarray
            Force [N], shape of ``delta`` and ``delta_dot`` broadcast (0-d for scalars).

        Raises
        ------
        ValueError
            For non-finite values or shapes that do not broadcast.
        """
        d = np.asarray(delta, dtype=float)
        dd = np.asarray(delta_dot, dtype=float)
        for name, a in (("delta", d), ("delta_dot", dd)):
            if not np.all(np.isfinite(a)):
                raise ValueError(f"{name} = {a!r} must be finite [m, m/s]")
        try:
            d, dd = np.broadcast_arrays(d, dd)
        except ValueError:
            raise ValueError(f"delta (shape {d.shape}) and delta_dot (shape {dd.shape}) "
                             "do not broadcast") from None
        out = np.empty(d.shape)
        hunt_crossley_force_batch(np.ascontiguousarray(d).ravel(),
                                  np.ascontiguousarray(dd).ravel(), float(self.stiffness),
                                  float(self.exponent), float(self.damping), out.reshape(-1))
        return out


def _check_claims(checks) -> tuple:
    """``HeadContactModel.checks`` as (name, met, note) triples of :data:`CHECK_NAMES`."""
    if isinstance(checks, (str, bytes)) or not isinstance(checks, (tuple, list)):
        raise TypeError(f"HeadContactModel.checks must be a tuple of (check, met, note), got "
                        f"{checks!r:.80}")
    out = []
    for i, c in enumerate(checks):
        if not (isinstance(c, (tuple, list)) and len(c) == 3 and isinstance(c[0], str)
                and isinstance(c[1], bool) and isinstance(c[2], str)):
            raise TypeError(f"HeadContactModel.checks[{i}] must be (check name, met: bool, "
                            f"note: str), got {c!r:.80}")
        if c[0] not in CHECK_NAMES:
            raise ValueError(f"HeadContactModel.checks[{i}]: unknown check {c[0]!r}; allowed: "
                             f"{list(CHECK_NAMES)}")
        out.append((c[0], c[1], c[2]))
    names = [c[0] for c in out]
    if len(set(names)) != len(names):
        raise ValueError(f"HeadContactModel.checks names a check twice: {names}")
    return tuple(out)


#: The keys of a head file (besides ``format``, ``name``, ``source`` and ``[checks]``).
HEAD_KEYS = (
    Key("mass", "mass", "kg", doc="head mass; in (0, 100] kg"),
    Key("radius", "radius", "m", doc="radius of the head surface hit; in [5 mm, 1 m]"),
    Key("stiffness", "stiffness", "N/m^n", doc="Hunt-Crossley k (n = exponent); in (0, 1e20]"),
    Key("exponent", "exponent", None, doc="Hunt-Crossley n; in [1, 3] (Hertz: 1.5)"),
    Key("damping", "damping", "N s/m^(n+1)",
        doc="Hunt-Crossley damping lambda (b of eq. 6.2); in [0, 1e20]"),
)


def _contact_unit(dotted, raw, symbolic, n, numeric):
    """A stiffness/damping value whose unit depends on the exponent n: its SI value."""
    if isinstance(raw, dict) and set(raw) == {"value", "unit"}:
        u = raw["unit"]
        accepted = {symbolic: 1.0, numeric(n): 1.0}
        if n == 1.0 and symbolic.startswith("N/"):
            accepted.update({"N/m": 1.0, "N/mm": 1.0e3})
        if n == 1.0 and symbolic.startswith("N s/"):
            accepted.update({"N s/m^2": 1.0})
        norm = {k.replace(" ", "").replace("*", ""): f for k, f in accepted.items()}
        key = u.replace(" ", "").replace("*", "") if isinstance(u, str) else None
        if key not in norm:
            raise ArmFileError(f"{dotted} unit = {u!r} is not allowed; give {list(accepted)}")
        raw = {"value": raw["value"], "unit": symbolic}
        value = read_value(dotted, Key(dotted, dotted, symbolic), raw)
        return value * norm[key]
    return read_value(dotted, Key(dotted, dotted, symbolic), raw)


def _head_from_dict(data) -> "HeadContactModel":
    fmt = data.get("format", HEAD_FORMAT)
    if fmt != HEAD_FORMAT:
        what = " (an arm file?)" if isinstance(fmt, str) and "arm" in fmt else ""
        raise ArmFileError(f"format = {fmt!r} is not {HEAD_FORMAT!r}{what}")
    allowed = ["format", "name", "source", "checks", *[k.key for k in HEAD_KEYS]]
    for k in data:
        if k not in allowed:
            raise ArmFileError(f"unknown key {k!r} in a head file; allowed: {allowed}")
    for k in ("name", *[k.key for k in HEAD_KEYS]):
        if k not in data:
            unit = next((f" [{x.unit}]" for x in HEAD_KEYS if x.key == k and x.unit), "")
            raise ArmFileError(f"missing key {k}{unit}")
    for k in ("name", "source"):
        if k in data and not isinstance(data[k], str):
            raise ArmFileError(f"{k} = {data[k]!r}: must be a string")
    n = read_value("exponent", HEAD_KEYS[3], data["exponent"])
    kw = {"mass": read_value("mass", HEAD_KEYS[0], data["mass"]),
          "radius": read_value("radius", HEAD_KEYS[1], data["radius"]), "exponent": n,
          "stiffness": _contact_unit("stiffness", data["stiffness"], "N/m^n", n,
                                     lambda x: f"N/m^{x:g}"),
          "damping": _contact_unit("damping", data["damping"], "N s/m^(n+1)", n,
                                   lambda x: f"N s/m^{x + 1:g}")}
    checks = data.get("checks", {})
    if not isinstance(checks, dict):
        raise ArmFileError(f"checks must be a table ([checks]), got {checks!r:.60}")
    claims = []
    for name, c in checks.items():
        if name not in CHECK_NAMES:
            raise ArmFileError(f"unknown check checks.{name}; allowed: {list(CHECK_NAMES)}")
        if not (isinstance(c, dict) and set(c) <= {"met", "note"} and "met" in c
                and isinstance(c["met"], bool) and isinstance(c.get("note", ""), str)):
            raise ArmFileError(f"checks.{name} = {c!r}: must be {{ met = true|false, note = "
                               f"\"...\" }}")
        claims.append((name, c["met"], c.get("note", "")))
    try:
        return HeadContactModel(name=data["name"], source=data.get("source", ""),
                                checks=tuple(claims), **kw)
    except (TypeError, ValueError) as exc:
        msg = str(exc)
        for k in ("mass", "radius", "stiffness", "exponent", "damping"):
            prefix = f"HeadContactModel.{k}"
            if msg.startswith(prefix):
                rest = msg[len(prefix):]
                rest = rest[rest.index(")") + 1:] if rest.startswith(" (model") else rest
                rest = rest.replace(" is outside ", ": must be in ", 1)
                raise ArmFileError(f"{k}{rest}") from None
        raise ArmFileError(msg.replace("HeadContactModel.", "")) from None


def load_head(path) -> "HeadContactModel":
    """Read and validate a head file (see the module docstring).

    Parameters
    ----------
    path : path-like
        The ``.toml`` file.

    Returns
    -------
    HeadContactModel
    """
    p, text = read_text(path, what="head file", error=ArmFileError)
    return HeadContactModel.from_toml(text, where=str(p))


def resolve_head(head) -> "HeadContactModel":
    """A head model from a name, a head file or a model (what ``head=`` and ``--head`` take).

    Parameters
    ----------
    head : str, path-like, HeadContactModel or None
        None: ``"thesis-frontal"``; a name of :func:`head_model_names`; the path of a
        head file (a string ending in ``.toml`` or an existing file); or a model.

    Returns
    -------
    HeadContactModel
    """
    if head is None:
        return head_model()
    if isinstance(head, HeadContactModel):
        return head
    if isinstance(head, Path) or (isinstance(head, str) and (head.endswith(".toml")
                                                             or Path(head).is_file())):
        return load_head(head)
    if isinstance(head, str):
        return head_model(head)
    raise TypeError(f"head must be a head model name, a head file or a HeadContactModel, got "
                    f"{type(head).__name__} {head!r:.60}")


#: Reconstructed thesis head model (frontal bone, Hybrid III); see module doc and
#: ppamsafety.impact.head_fit.  Values are the output of fit_thesis_head(), rounded.
THESIS_FRONTAL = dict(stiffness=9.5e5, exponent=1.5, damping=3.3e6)


@functools.lru_cache(maxsize=1)
def _models() -> types.MappingProxyType:
    soft = ("softer than a bare dummy head on steel: the contact includes the robot's link, "
            "which complies and dissipates in series")
    iso_note = ("ISO/TS 15066's spring constant is a body-model value from quasi-static "
                "pain-onset data, not a fit to impacts")
    th = HeadContactModel(
        name="thesis-frontal", mass=5.0, radius=0.1, **THESIS_FRONTAL,
        source="Reconstructed: Hunt-Crossley fit to the (HIC, F_max) pairs of thesis Table 6.1 "
               "and the Hybrid III head drop certification (49 CFR 572.32); see "
               "ppamsafety.impact.head_fit",
        checks=(("table_6_1", True, "fitted to the pairs (n fixed at the Hertz 1.5)"),
                ("hybrid_iii_drop", False, soft),
                ("iso_ts_15066", False, "softer than the forehead and face springs; " + iso_note)))
    def annex(region):                # the Annex A body model of a head region (Table A.3)
        mass_by = region.source_of("effective_mass").rsplit("(", 1)[-1].rstrip(")")
        return (f"{region.source_of('spring_constant')}: effective spring constant K = "
                f"{region.spring_constant / 1e3:g} N/mm; effective mass m_H = "
                f"{region.effective_mass:g} kg, same table ({mass_by}); linear, undamped")
    iso = HeadContactModel(
        name="iso15066-forehead", mass=SKULL_FOREHEAD.effective_mass, radius=0.1,
        stiffness=SKULL_FOREHEAD.spring_constant, exponent=1.0, damping=0.0,
        source=annex(SKULL_FOREHEAD),
        checks=(("iso_ts_15066", True, "is the Annex A skull/forehead body model"),
                ("hybrid_iii_drop", False, "a linear body-model spring, not a dummy head"),
                ("table_6_1", False, "not the contact the thesis used")))
    face = iso.replace(name="iso15066-face", mass=FACE.effective_mass,
                       stiffness=FACE.spring_constant, source=annex(FACE),
                       checks=(("iso_ts_15066", True, "is the Annex A face body model"),
                               *iso.checks[1:]))
    child = th.replace(name="child-frontal", mass=3.0,
                       source="thesis-frontal contact with a 3 kg head (illustrative child "
                              "variant; the contact stiffness is kept, only the mass changes)",
                       checks=(("table_6_1", False, "the thesis' contact with a lighter head: "
                                                    "an illustration, not a fit"),
                               ("hybrid_iii_drop", False, soft),
                               ("iso_ts_15066", False, iso_note)))
    # built once (frozen models; a read-only mapping): every impact call resolves its head
    return types.MappingProxyType({m.name: m for m in (th, iso, face, child)})


def head_model(name: str = "thesis-frontal") -> HeadContactModel:
    """A named head contact model: one of :func:`head_model_names`.

    Parameters
    ----------
    name : str
        Model name (default ``"thesis-frontal"``).

    Raises
    ------
    ValueError
        For an unknown name (the message lists the choices).
    """
    check_str("name", name)
    models = _models()
    if name not in models:
        raise ValueError(f"unknown head model {name!r}{did_you_mean(name, list(models))}; "
                         f"choose from {sorted(models)} (or give a head file, .toml)")
    return models[name]


def head_model_names() -> list:
    """Names accepted by :func:`head_model`."""
    return sorted(_models())
