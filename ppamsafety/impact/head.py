"""Head contact models: a free head and its Hunt-Crossley contact, named sets with provenance.

The thesis (§6.3.1) simulates a free 5 kg head and a Hunt-Crossley contact
F = k delta^n + b delta^n d(delta)/dt whose parameters Haddadin et al.
(2007) fitted to LWR-III impacts on a Hybrid III dummy head, but it does not
print k, b, n.  This module holds our reconstruction and alternatives; the
evidence and the fit are in :mod:`ppamsafety.impact.head_fit` and in the
report ("Head contact model").  A model is checked on construction against the
contact law it parametrises (:mod:`.contact`): it must stop a tool before the
head centre, in a contact the engines can integrate.

Users pick a model by name (:func:`head_model`) or build their own
:class:`HeadContactModel`.
"""

from __future__ import annotations

import functools
import types
from dataclasses import dataclass, replace

import numpy as np

from .._validation import check_range, check_str
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
    models pass with margin (thesis-frontal: 12 mm, 2.4 ms; iso15066-face: 41 mm,
    8 ms).
    """

    name: str
    mass: float
    radius: float
    stiffness: float
    exponent: float
    damping: float
    source: str = ""

    def __post_init__(self):
        check_str("HeadContactModel.name", self.name)
        check_str("HeadContactModel.source", self.source)
        model = f" (model {self.name!r})"
        for field, lo, hi, lo_open, unit in (
                ("mass", 0.0, 100.0, True, "kg"),
                ("radius", MIN_RADIUS, 1.0, False, "m"),
                ("stiffness", 0.0, 1e20, True, "N/m^n"),
                ("exponent", 1.0, 3.0, False, ""),
                ("damping", 0.0, 1e20, False, "N s/m^(n+1)")):
            object.__setattr__(self, field, check_range(
                f"HeadContactModel.{field}{model}", getattr(self, field), lo, hi, lo_open=lo_open,
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


#: Reconstructed thesis head model (frontal bone, Hybrid III); see module doc and
#: ppamsafety.impact.head_fit.  Values are the output of fit_thesis_head(), rounded.
THESIS_FRONTAL = dict(stiffness=9.5e5, exponent=1.5, damping=3.3e6)


@functools.lru_cache(maxsize=1)
def _models() -> types.MappingProxyType:
    th = HeadContactModel(
        name="thesis-frontal", mass=5.0, radius=0.1, **THESIS_FRONTAL,
        source="Reconstructed: Hunt-Crossley fit to the (HIC, F_max) pairs of thesis Table 6.1 "
               "and the Hybrid III head drop certification (49 CFR 572.32); see "
               "ppamsafety.impact.head_fit")
    iso = HeadContactModel(
        name="iso15066-forehead", mass=5.0, radius=0.1, stiffness=150.0e3, exponent=1.0,
        damping=0.0, source="ISO/TS 15066:2016 Annex A, Table A.3: skull/forehead effective "
                            "spring constant 150 N/mm, linear, undamped")
    face = iso.replace(name="iso15066-face", stiffness=75.0e3,
                       source="ISO/TS 15066:2016 Annex A, Table A.3: face 75 N/mm, linear")
    child = th.replace(name="child-frontal", mass=3.0,
                       source="thesis-frontal contact with a 3 kg head (illustrative child "
                              "variant; the contact stiffness is kept, only the mass changes)")
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
        raise ValueError(f"unknown head model {name!r}; choose from {sorted(models)}")
    return models[name]


def head_model_names() -> list:
    """Names accepted by :func:`head_model`."""
    return sorted(_models())
