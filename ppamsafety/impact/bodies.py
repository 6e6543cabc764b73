"""Body regions as contacts, and the head's own certification test.

A body region enters the impact physics as a :class:`~ppamsafety.params.contact.BodyContact`:
an effective mass, the radius of curvature of its surface and its layers (soft tissue, bone).
This module builds them from the toolkit's other descriptions of a body --

* :func:`body_from_head`: a Hunt-Crossley head model (:mod:`ppamsafety.impact.head`, e.g. the
  thesis' ``thesis-frontal``) as a one-layer body: the same law, bit for bit;
* :func:`body_from_region`: a body region of ISO/TS 15066 Annex A as its two-body model (the
  region's effective mass m_H and a linear spring of its effective spring constant K, no
  damping) --

and holds the test a head model must pass on its own, the **Hybrid III head drop** of
49 CFR 572.32 (:func:`hybrid3_drop`): the head (4.54 kg) dropped from 376 mm (14.8 in) onto a
rigidly supported flat horizontal steel plate; the peak resultant acceleration at the head's
accelerometers (its centre of gravity, §572.36) must lie between 225 g and 275 g, the pulse
must be unimodal (oscillations after it below 10 % of the peak) and the lateral acceleration
below 15 g.  The head here is rigid behind its layers, so the accelerometers read F / m (an
accelerometer reads the contact force per mass; gravity adds no reading), and a centric drop
has no lateral component.  The peak is reported raw and filtered at channel frequency class
1000 (SAE J211, the class of head accelerations in crash tests), :func:`cfc_filter`.  Gravity
during the ~3 ms of contact is neglected (it adds m g delta_max, under 1 % of the energy).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..plots.impact import plot_drop_test
from ..results import Result
from .._validation import check_instance, check_range
from ..params.contact import BodyContact, Layer
from ..units import G0
from .head import resolve_head
from .layers import _two_body_run, series_contact, two_body_series

#: The Hybrid III head drop of 49 CFR 572.32: head mass [kg] (10 lb), drop height [m]
#: (14.8 in), and the corridor of the peak resultant acceleration [g].
HYBRID3_HEAD_MASS = 4.54
HYBRID3_DROP_HEIGHT = 0.376
HYBRID3_CORRIDOR_G = (225.0, 275.0)
#: Unimodality: oscillations after the main pulse below this share of the peak (§572.32(b)).
HYBRID3_UNIMODAL = 0.10
#: Channel frequency class of head accelerations (SAE J211-1, class 1000).
CFC_HEAD = 1000.0


def body_from_head(head) -> BodyContact:
    """A Hunt-Crossley head model as a one-layer body (the same law, bit for bit).

    Parameters
    ----------
    head : str, path-like or HeadContactModel
        A head model, its name or a head file (:func:`~ppamsafety.impact.head.resolve_head`).

    Returns
    -------
    BodyContact
        Mass and radius of the head model; one ``"power"`` layer with its k, n and b.
    """
    hm = resolve_head(head)
    return BodyContact(
        name=hm.name, mass=hm.mass, radius=hm.radius,
        layers=(Layer(f"{hm.name} contact", "power", stiffness=hm.stiffness,
                      exponent=hm.exponent, damping=hm.damping, source=hm.source),),
        source=f"head model {hm.name!r}: {hm.source}")


def body_from_region(region, *, radius: float) -> BodyContact:
    """The two-body model of an ISO/TS 15066 Annex A body region as a body contact.

    The region's effective mass m_H and effective spring constant K (a linear spring: one
    ``"power"`` layer with n = 1, no damping), so that the engine's linear-spring limit is
    the Annex A model (peak force v sqrt(mu K)).

    Parameters
    ----------
    region : object
        A body region with ``name``, ``effective_mass`` [kg] and ``spring_constant`` [N/m]
        (:class:`ppamsafety.params.iso_ts_15066.BodyRegion`).
    radius : float, keyword-only
        Radius of curvature of the region's surface [m], in [5 mm, 1 m] (sets where the body
        centre starts and the contact area; the spring itself is the region's constant).

    Returns
    -------
    BodyContact
    """
    for attr in ("name", "effective_mass", "spring_constant"):
        if not hasattr(region, attr):
            raise TypeError(f"region must be a body region with name, effective_mass and "
                            f"spring_constant (ISO/TS 15066 Annex A), got "
                            f"{type(region).__name__}")
    k = check_range("region.spring_constant", region.spring_constant, 0.0, 1e9, lo_open=True,
                    unit="N/m")
    src = getattr(region, "source", "ISO/TS 15066:2016 Annex A")
    return BodyContact(
        name=str(region.name), mass=float(region.effective_mass), radius=radius,
        layers=(Layer(f"{region.name} (Annex A spring)", "power", stiffness=k, exponent=1.0,
                      damping=0.0, source=src),),
        source=f"ISO/TS 15066 Annex A two-body model of {region.name}: m_H and K ({src})")


def cfc_filter(a, dt: float, cfc: float = CFC_HEAD) -> np.ndarray:
    """Channel frequency class filter of SAE J211-1 (Appendix C): a phaseless 4-pole Butterworth.

    A 2-pole Butterworth low-pass (its corner at 2.0775 x CFC, so that the forward-backward
    pass is 3 dB down at 1.65 x CFC) run forward and then backward over the record, which
    starts at rest (zero initial conditions, zero padding before and after).

    Parameters
    ----------
    a : array_like, shape (n,)
        Samples (e.g. an acceleration [g]).
    dt : float
        Sample spacing [s], at most 1 / (10 CFC).
    cfc : float
        Channel frequency class [Hz] (1000 for head accelerations).

    Returns
    -------
    numpy.ndarray
        The filtered samples.
    """
    from scipy.signal import lfilter

    x = np.asarray(a, dtype=float)
    cfc = check_range("cfc", cfc, 1.0, 1e5, unit="Hz")
    dt = check_range("dt", dt, 1e-9, 0.1 / cfc, unit="s")
    wd = 2.0 * math.pi * cfc * 2.0775
    wa = math.tan(wd * dt / 2.0)
    den = 1.0 + math.sqrt(2.0) * wa + wa * wa
    a0 = wa * wa / den
    b1 = -2.0 * (wa * wa - 1.0) / den
    b2 = (-1.0 + math.sqrt(2.0) * wa - wa * wa) / den
    num, dnm = [a0, 2.0 * a0, a0], [1.0, -b1, -b2]
    pad = int(math.ceil(0.01 / dt))                     # 10 ms of rest before and after
    y = lfilter(num, dnm, np.concatenate([np.zeros(pad), x, np.zeros(pad)]))
    y = lfilter(num, dnm, y[::-1])[::-1]
    return y[pad:pad + x.size]


@dataclass(frozen=True)
class DropTest(Result):
    """Result of :func:`hybrid3_drop`: the head drop of 49 CFR 572.32.

    Attributes
    ----------
    body : BodyContact
        The head tested (with the standard's mass).
    speed : float
        Impact speed sqrt(2 g0 h) [m/s].
    peak_g, peak_g_cfc : float
        Peak resultant acceleration [g], raw and filtered at CFC 1000.
    t_peak : float
        Time of the raw peak after first touch [s].
    restitution : float
        Rebound speed over impact speed [-].
    unimodal : float
        Largest filtered acceleration after the main pulse (from the end of contact on)
        over the peak [-] (<= 0.10 required).
    passed : bool
        The filtered peak is inside 225-275 g and the curve unimodal.
    history : pandas.DataFrame
        ``t`` [s], ``a_g`` (raw) and ``a_g_cfc`` (filtered) [g].
    """

    body: BodyContact
    speed: float
    peak_g: float
    peak_g_cfc: float
    t_peak: float
    restitution: float
    unimodal: float
    passed: bool
    history: pd.DataFrame

    def to_pandas(self) -> pd.DataFrame:
        """The test as a one-row table (SI units, g)."""
        lo, hi = HYBRID3_CORRIDOR_G
        return pd.DataFrame([{"body": self.body.name, "mass": self.body.mass,
                              "drop_height": HYBRID3_DROP_HEIGHT, "speed": self.speed,
                              "peak_g": self.peak_g, "peak_g_cfc1000": self.peak_g_cfc,
                              "corridor_low_g": lo, "corridor_high_g": hi,
                              "t_peak": self.t_peak, "restitution": self.restitution,
                              "after_pulse_share": self.unimodal, "passed": self.passed}])

    def plot(self, *, title: str = ""):
        """Head acceleration [g] against time, raw and CFC 1000, with the corridor; a Figure.

        Parameters
        ----------
        title : str, keyword-only
            Axes title (default names the test and the body).
        """
        return plot_drop_test(self.history, corridor_g=HYBRID3_CORRIDOR_G,
                              peak_g_cfc=self.peak_g_cfc,
                              title=title or f"Hybrid III head drop (49 CFR 572.32): "
                                             f"{self.body.name}")


def hybrid3_drop(body: BodyContact, *, mass: float = HYBRID3_HEAD_MASS,
                 height: float = HYBRID3_DROP_HEIGHT, dt: float = 1e-6) -> DropTest:
    """The Hybrid III head drop of 49 CFR 572.32 with a body's contact (module docstring).

    The head (the body's layers, its radius, the standard's mass) falls ``height`` onto a flat
    rigid plate: a two-body impact with an infinite plate mass through the body's layers
    alone (bare, flat plate).

    Parameters
    ----------
    body : BodyContact
        The head contact model.
    mass : float
        Head mass [kg] (default the standard's 4.54 kg), in (0, 100].
    height : float
        Drop height [m] (default the standard's 0.376 m), in (0, 10].
    dt : float
        Integration and sample step [s], in [1e-8, 1e-5].

    Returns
    -------
    DropTest
    """
    body = check_instance("body", body, BodyContact)
    mass = check_range("mass", mass, 0.0, 100.0, lo_open=True, unit="kg")
    height = check_range("height", height, 0.0, 10.0, lo_open=True, unit="m")
    dt = check_range("dt", dt, 1e-8, 1e-5, unit="s")
    head = body.replace(mass=mass)
    v = math.sqrt(2.0 * G0 * height)
    c = series_contact(body=head)
    n = int(math.ceil(0.05 / dt))
    r = two_body_series([v], c, arm_mass=math.inf, dt=dt, duration=n * dt)
    _, a = _two_body_run(np.array([v]), np.array([mass]), c, dt, n)
    af = cfc_filter(a, dt)
    i = int(np.argmax(af))
    # after the main pulse: from the end of contact (the raw record back at 0) on, the largest
    # filtered magnitude (the filter's own ringing included) over the peak
    end = np.nonzero(a[int(np.argmax(a)):] <= 0.0)[0]
    after = float(np.abs(af[int(np.argmax(a)) + end[0]:]).max() / af[i]) if end.size else 1.0
    lo, hi = HYBRID3_CORRIDOR_G
    row = r.iloc[0]
    return DropTest(head, v, float(row["a_max_g"]), float(af[i]), float(row["t_Fmax"]),
                    float(row["separation_speed"] / v), after,
                    bool(lo <= af[i] <= hi and after <= HYBRID3_UNIMODAL),
                    pd.DataFrame({"t": np.arange(n + 1) * dt, "a_g": a, "a_g_cfc": af}))


def calibrate_soft_tissue(body: BodyContact, *, target_g: float = 250.0, layer: int = 0,
                          bracket=(1e7, 1e8)) -> float:
    """The modulus of a body's material layer that puts its drop peak at ``target_g``.

    Used to set the forehead soft tissue's modulus on the middle of the Hybrid III corridor
    (:data:`ppamsafety.params.contact.FOREHEAD_TISSUE_MODULUS`).

    Parameters
    ----------
    body : BodyContact
        The head; layer ``layer`` must be a material law (``"thin-layer"`` or ``"hertz"``).
    target_g : float
        Raw peak acceleration of the drop [g], in (0, 1000].
    layer : int
        Index of the layer whose modulus is set.
    bracket : (float, float)
        Moduli [Pa] between which the peak crosses the target (a softer tissue bottoms out
        on the bone and the peak rises again, so the bracket must exclude that branch).

    Returns
    -------
    float
        The modulus [Pa].
    """
    from scipy.optimize import brentq

    body = check_instance("body", body, BodyContact)
    target_g = check_range("target_g", target_g, 0.0, 1000.0, lo_open=True, unit="g")
    if not (isinstance(layer, int) and 0 <= layer < len(body.layers)):
        raise ValueError(f"layer = {layer!r}: an index of body.layers (0..{len(body.layers) - 1})")
    if body.layers[layer].law == "power":
        raise ValueError(f"layer {layer} of {body.name!r} is a 'power' law (no modulus)")
    head = body.replace(mass=HYBRID3_HEAD_MASS)
    v = math.sqrt(2.0 * G0 * HYBRID3_DROP_HEIGHT)

    def peak(e):
        lays = list(head.layers)
        lays[layer] = lays[layer].replace(modulus=e)
        c = series_contact(body=head.replace(layers=tuple(lays)))
        return float(two_body_series([v], c, arm_mass=math.inf)["a_max_g"].iloc[0]) - target_g

    return float(brentq(peak, *bracket, xtol=1.0, rtol=1e-9))


__all__ = ["body_from_head", "body_from_region", "hybrid3_drop", "DropTest", "cfc_filter",
           "calibrate_soft_tissue", "HYBRID3_HEAD_MASS", "HYBRID3_DROP_HEIGHT",
           "HYBRID3_CORRIDOR_G"]
