"""ISO/TS 15066 Annex A power and force limiting: the linear-spring two-body model.

Annex A models a transient contact as two bodies -- the robot's effective
mass m_R and the body region's effective mass m_H -- meeting with relative
speed v_rel through a linear spring K (the body region).  All the kinetic
energy of the relative motion is stored in the spring at the peak::

    E = mu v_rel^2 / 2 = F^2 / (2 K) = A^2 p^2 / (2 K),     mu = (1/m_H + 1/m_R)^-1

so the peak force is F = v_rel sqrt(mu K) and the largest permissible relative
speed is v_rel,max = F_max / sqrt(mu K) (F_max the transient limit of the
region).  The robot's effective mass by Annex A.4 is m_R = M/2 + m_L (M the
total mass of the moving parts, m_L the payload); :func:`ppamsafety.impact.effective_mass`
gives the arm's own apparent mass along a direction instead.

Parameters of the head regions: :mod:`ppamsafety.params.iso_ts_15066`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .._validation import as_float_array, check_finite_result, check_instance, check_range
from ..params.iso_ts_15066 import BodyRegion


def _pos_array(name, value, unit, hi=1e12):
    a = as_float_array(name, value)
    if not np.all(np.isfinite(a)) or np.any(a <= 0) or np.any(a > hi):
        raise ValueError(f"{name} = {value!r} [{unit}] must be finite, positive and at most "
                         f"{hi:g}")
    return a


def reduced_mass(m_human, m_robot):
    """Reduced mass mu = (1/m_H + 1/m_R)^-1 [kg] of the two-body model (Annex A).

    Parameters
    ----------
    m_human : float or array_like
        Effective mass of the body region m_H [kg], positive, finite.
    m_robot : float or array_like
        Effective robot mass m_R [kg], positive (``np.inf`` allowed: a
        fixed robot, mu = m_H); broadcast against ``m_human``.

    Returns
    -------
    float or numpy.ndarray
        mu [kg].
    """
    mh = _pos_array("m_human", m_human, "kg")
    mr = as_float_array("m_robot", m_robot)
    if np.any(np.isnan(mr)) or np.any(mr <= 0):
        raise ValueError(f"m_robot = {m_robot!r} [kg] must be positive (inf allowed)")
    try:
        mh, mr = np.broadcast_arrays(mh, mr)
    except ValueError:
        raise ValueError(f"m_human (shape {np.shape(mh)}) and m_robot (shape {np.shape(mr)}) "
                         "do not broadcast") from None
    out = 1.0 / (1.0 / mh + 1.0 / mr)
    return float(out) if out.ndim == 0 else out


def robot_effective_mass_annex_a(total_mass, payload=0.0) -> float:
    """Effective robot mass m_R = M/2 + m_L [kg] (ISO/TS 15066 Annex A.4).

    Parameters
    ----------
    total_mass : float
        Total mass of the moving parts of the robot M [kg], in (0, 1e4].
    payload : float
        Effective payload m_L (tool and workpiece) [kg], in [0, 1e4].
    """
    M = check_range("total_mass", total_mass, 0.0, 1e4, lo_open=True, unit="kg")
    mL = check_range("payload", payload, 0.0, 1e4, unit="kg")
    return M / 2.0 + mL


def transfer_energy(force, spring_constant):
    """Energy E = F^2 / (2K) [J] a linear body-region spring stores at the force F.

    Parameters
    ----------
    force : float or array_like
        Contact force [N], >= 0, finite.
    spring_constant : float
        Effective spring constant K [N/m], positive.
    """
    F = as_float_array("force", force)
    if not np.all(np.isfinite(F)) or np.any(F < 0):
        raise ValueError(f"force = {force!r} [N] must be finite and non-negative")
    k = check_range("spring_constant", spring_constant, 0.0, 1e12, lo_open=True, unit="N/m")
    out = F * F / (2.0 * k)
    return float(out) if out.ndim == 0 else out


def transfer_energy_pressure(pressure, area, spring_constant) -> float:
    """Energy E = A^2 p^2 / (2K) [J] at the pressure p on the contact area A (Annex A).

    Parameters
    ----------
    pressure : float
        Contact pressure [Pa], >= 0.
    area : float
        Contact area A [m^2], in (0, 1].
    spring_constant : float
        Effective spring constant K [N/m], positive.
    """
    p = check_range("pressure", pressure, 0.0, 1e10, unit="Pa")
    A = check_range("area", area, 0.0, 1.0, lo_open=True, unit="m^2")
    return transfer_energy(p * A, spring_constant)


def max_relative_speed(force_limit, spring_constant, mu):
    """Largest permissible relative speed v_rel,max = F_max / sqrt(mu K) [m/s] (Annex A).

    Parameters
    ----------
    force_limit : float or array_like
        Permissible (transient) force F_max [N], positive.
    spring_constant : float
        Effective spring constant K of the body region [N/m], positive.
    mu : float or array_like
        Reduced mass of robot and body region [kg], positive (broadcast).
    """
    F = _pos_array("force_limit", force_limit, "N")
    k = check_range("spring_constant", spring_constant, 0.0, 1e12, lo_open=True, unit="N/m")
    m = _pos_array("mu", mu, "kg")
    out = F / np.sqrt(m * k)
    out = check_finite_result("max_relative_speed", out, f"force_limit = {force_limit!r}")
    return float(out) if np.ndim(out) == 0 else out


def linear_peak_force(speed, spring_constant, mu):
    """Peak force F = v sqrt(mu K) [N] of the undamped linear two-body contact.

    Parameters
    ----------
    speed : float or array_like
        Relative speed at contact [m/s], >= 0, finite.
    spring_constant : float
        K [N/m], positive.
    mu : float or array_like
        Reduced mass [kg], positive (broadcast against ``speed``).
    """
    v = as_float_array("speed", speed)
    if not np.all(np.isfinite(v)) or np.any(v < 0):
        raise ValueError(f"speed = {speed!r} [m/s] must be finite and non-negative")
    k = check_range("spring_constant", spring_constant, 0.0, 1e12, lo_open=True, unit="N/m")
    m = _pos_array("mu", mu, "kg")
    out = v * np.sqrt(m * k)
    return float(out) if np.ndim(out) == 0 else out


def region_limits(region, m_robot, *, transient_factor=None) -> pd.Series:
    """The Annex A numbers of one body region against a robot effective mass.

    Parameters
    ----------
    region : BodyRegion
        Body region (:mod:`ppamsafety.params.iso_ts_15066`).
    m_robot : float
        Effective robot mass m_R [kg], positive.
    transient_factor : float, optional
        Override of the region's transient multiplier, in [1, 10] (e.g. 1 for
        the conservative reading that the head has no transient allowance).

    Returns
    -------
    pandas.Series
        ``region``, ``F_qs`` [N], ``factor``, ``F_transient`` [N], ``K`` [N/m],
        ``m_H``, ``m_R``, ``mu`` [kg], ``E_transfer`` [J] (at F_transient),
        ``E_transfer_qs`` [J] (at F_qs), ``v_max`` [m/s].
    """
    region = check_instance("region", region, BodyRegion)
    fac = region.transient_factor if transient_factor is None else check_range(
        "transient_factor", transient_factor, 1.0, 10.0)
    mu = reduced_mass(region.effective_mass, m_robot)
    Ft = fac * region.force_quasi_static
    return pd.Series({"region": region.name, "F_qs": region.force_quasi_static, "factor": fac,
                      "F_transient": Ft, "K": region.spring_constant,
                      "m_H": region.effective_mass, "m_R": float(m_robot), "mu": mu,
                      "E_transfer": transfer_energy(Ft, region.spring_constant),
                      "E_transfer_qs": transfer_energy(region.force_quasi_static,
                                                       region.spring_constant),
                      "v_max": max_relative_speed(Ft, region.spring_constant, mu)})


__all__ = ["reduced_mass", "robot_effective_mass_annex_a", "transfer_energy",
           "transfer_energy_pressure", "max_relative_speed", "linear_peak_force",
           "region_limits"]
