"""Sliding mode control with feedback linearisation of the pressure dynamics.

Thesis §4.3 and Appendix C.  Each link is a 4th-order input-affine system in
x_i = (q_i, qd_i, p_2i-1, p_2i) with input u_i = Delta p_i and relative
degree 3: with xi3 = qdd_i (no input), b_i = d(qdd_i)/dt along the drift and
a_i = its sensitivity to u_i,

    qddd_i = b_i + a_i u_i                                     (4.33)
    s_i    = edd_i + alpha1 ed_i + alpha0 e_i,  e = q_d - q     (4.35)
    u_i    = (qddd_d - b_i + alpha1 edd_i + alpha0 ed_i + K_i sat(s_i/Gamma_i)) / a_i   (4.41)

so that on the model ds_i/dt = -K_i sat(s_i/Gamma_i): reaching at rate K_i
outside the boundary layer, exponential decay with rate K_i/Gamma_i inside.

The Lie derivatives are evaluated numerically (central differences of the
model's forward dynamics) rather than from the thesis' symbolic expressions.
``coupling="siso"`` reproduces the thesis (each link linearised with respect
to its own states only; the other link's motion is a disturbance);
``coupling="mimo"`` uses all states and the 2x2 input matrix, which cancels
the modelled dynamics exactly.

The model is the physically consistent plant by default (the identified
Table 3.5 inertia matrix is indefinite and cannot be inverted); its valve
time constants can be set independently of the plant's (§4.4.2: the thesis
chose them 20-50 % lower than measured to reduce chattering).
"""

from __future__ import annotations


import numpy as np

from .._validation import check_instance, check_vector
from ..layouts import check_flag
from ..params.inertia import LinkInertia
from ..plant import packing
from .base import Controller, pair
from .dispatch import DECLARED
from .kinds import KIND_SMC
from .laws.smc import SMCCoupling, SMC_PARAMS


#: Largest pole accepted [1/s] (alpha0 = poles^2; 1e4 1/s is ten times the control rate).
POLE_MAX = 1.0e4
#: Largest switching gain K [rad/s^3] and boundary layer Gamma [rad/s^2] accepted.
SMC_GAIN_MAX = 1.0e9
#: Shortest model valve time constant accepted [s], as for the valves themselves
#: (:class:`~ppamsafety.params.valves.Valve`): the 1 kHz controller cannot act faster.
MODEL_T_MIN = 1.0e-3


class SlidingModeControl(Controller):
    """Sliding mode control with boundary layer (§4.3, App. C).

    Parameters
    ----------
    poles : float or pair, keyword-only
        The error dynamics on s = 0 get a double pole at -poles [1/s]:
        alpha1 = 2 poles, alpha0 = poles^2 (Hurwitz, (4.35)); in (0, 1e4].
    gain : float or pair
        Switching gain K [rad/s^3], in [0, 1e9].
    boundary_layer : float or pair
        Boundary-layer width Gamma [rad/s^2] (sgn replaced by sat(s/Gamma)),
        in (0, 1e9].
    coupling : {"siso", "mimo"}
        Per-link linearisation as in the thesis, or full MIMO.
    model_time_constants : sequence of 4 float, optional
        Valve time constants the controller assumes [s], each in
        [1e-3, 10] s like the valves' own; default the arm's.
    model_links : LinkInertia, optional
        Link parameters of the model; default the plant's (exact model).

    Notes
    -----
    The thesis gives no SMC gains.  The defaults (poles 40 1/s, K = 3000
    rad/s^3, Gamma = 10 rad/s^2, i.e. a gain K/Gamma = 300 1/s inside the
    boundary layer) were chosen by simulation (:mod:`ppamsafety.sections.smc`,
    which repeats the search and reports it): circle with period 5 s as in
    §4.4.1, realistic sensors (encoder, inter-pulse-timing velocity), SISO
    coupling, exact valve model; on a grid poles {10, 20, 40, 80} x K/Gamma
    {30, 100, 300} x Gamma {3, 10, 30}, the setting that minimises the
    product of the worst-case mean tracking error and the worst-case
    chattering index (RMS of the commanded Delta p above 5 Hz) over the
    nominal plant and a plant with 20 % heavier links (the mismatch of
    §4.4.1).  Ties (within 1 %) go to the smaller K, then the smaller Gamma.
    """

    kind = KIND_SMC
    name = "SMC"
    PARAMS, STATE, INTERNALS, SCRATCH = DECLARED[KIND_SMC]

    def __init__(self, *, poles=40.0, gain=3000.0, boundary_layer=10.0, coupling: str = "siso",
                 model_time_constants=None, model_links=None):
        super().__init__()
        p = pair("SlidingModeControl.poles", poles, lo=0.0, lo_open=True, hi=POLE_MAX,
                 unit="1/s")
        self.alpha0 = tuple(x * x for x in p)
        self.alpha1 = tuple(2 * x for x in p)
        self.gain = pair("SlidingModeControl.gain", gain, hi=SMC_GAIN_MAX, unit="rad/s^3")
        self.boundary_layer = pair("SlidingModeControl.boundary_layer", boundary_layer,
                                   lo=0.0, lo_open=True, hi=SMC_GAIN_MAX, unit="rad/s^2")
        code = check_flag(SMCCoupling, coupling, "SlidingModeControl.coupling")
        self.coupling = SMCCoupling(code).name.lower()
        if model_time_constants is not None:
            # as the valves themselves (params.valves): at least 1 ms, at most 10 s
            model_time_constants = check_vector("SlidingModeControl.model_time_constants",
                                                model_time_constants, 4, MODEL_T_MIN, 10.0,
                                                unit="s")
        self.model_time_constants = model_time_constants
        if model_links is not None:
            check_instance("SlidingModeControl.model_links", model_links, LinkInertia)
        self.model_links = model_links

    def pack(self) -> np.ndarray:
        """Parameter row of the compiled step function (layout ``SMC_PARAMS``, SI units)."""
        return SMC_PARAMS.pack(
            alpha0=self.alpha0, alpha1=self.alpha1, gain=self.gain,
            boundary_layer=self.boundary_layer,
            coupling=check_flag(SMCCoupling, self.coupling, "SlidingModeControl.coupling"))

    def model_row(self, arm) -> np.ndarray:
        """Packed arm parameters the controller believes in (its model).

        Parameters
        ----------
        arm : ArmParameters
            The plant; its valves get ``model_time_constants`` and its links
            ``model_links`` where those are set.

        Returns
        -------
        numpy.ndarray
            The model row (layout ``PLANT``).
        """
        a = arm
        if self.model_time_constants is not None:
            a = a.replace(valves=a.valves.with_time_constants(self.model_time_constants))
        links = arm.links if self.model_links is None else self.model_links
        return packing.pack(a, links.base_parameters(arm.geometry.L1))

    def describe(self) -> dict:
        """Parameters as a flat dict for result tables.

        Returns
        -------
        dict
            ``controller``, ``Ki_bar_per_rad_s`` and ``lambda_s`` (NaN),
            ``boundary_layer`` of joint 1 [rad/s^2].
        """
        return {"controller": self.name, "Ki_bar_per_rad_s": np.nan, "lambda_s": np.nan,
                "boundary_layer": self.boundary_layer[0]}
