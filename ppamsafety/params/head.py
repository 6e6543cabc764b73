"""Head contact models: named Hunt-Crossley parameter sets with provenance.

The thesis (§6.3.1) simulates a free 5 kg head and a Hunt-Crossley contact
F = k delta^n + b delta^n d(delta)/dt whose parameters Haddadin et al.
(2007) fitted to LWR-III impacts on a Hybrid III dummy head, but it does not
print k, b, n.  This module holds our reconstruction and alternatives; the
evidence and the fit are in :mod:`ppamsafety.impact.head_fit` and in the
report ("Head contact model").

Users pick a model by name (:func:`head_model`) or build their own
:class:`HeadContactModel`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from .._validation import check_nonnegative, check_range

#: Maxilla fracture tolerance [N] (Haddadin et al. 2007a, quoted in thesis §6.3.3).
MAXILLA_FRACTURE_N = 660.0


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
    """

    name: str
    mass: float
    radius: float
    stiffness: float
    exponent: float
    damping: float
    source: str = ""

    def __post_init__(self):
        check_range(f"{self.name}.mass", self.mass, 0.0, 100.0, lo_open=True, unit="kg")
        check_range(f"{self.name}.radius", self.radius, 0.0, 1.0, lo_open=True, unit="m")
        check_range(f"{self.name}.stiffness", self.stiffness, 0.0, 1e20, lo_open=True,
                    unit="N/m^n")
        check_range(f"{self.name}.exponent", self.exponent, 1.0, 3.0)
        check_nonnegative(f"{self.name}.damping", self.damping, unit="N s/m^(n+1)")

    def replace(self, **changes) -> "HeadContactModel":
        """Return a copy with some fields changed (validated again)."""
        return replace(self, **changes)

    def force(self, delta, delta_dot=0.0):
        """Hunt-Crossley contact force [N] (thesis eq. 6.2), element-wise.

        F = k delta^n + b delta^n d(delta)/dt for delta > 0, clipped at 0 (the
        contact only pushes), and 0 for delta <= 0.  Evaluated by the same
        compiled law as the impact engine
        (:func:`ppamsafety.impact.contact.hunt_crossley_force`).

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
        import numpy as np

        from ..impact.contact import hunt_crossley_force_batch

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


def _models() -> dict:
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
    return {m.name: m for m in (th, iso, face, child)}


def head_model(name: str = "thesis-frontal") -> HeadContactModel:
    """A named head contact model: one of :func:`head_model_names`."""
    models = _models()
    if name not in models:
        raise ValueError(f"unknown head model {name!r}; choose from {sorted(models)}")
    return models[name]


def head_model_names() -> list:
    """Names accepted by :func:`head_model`."""
    return sorted(_models())
