"""Argument checks shared by the public NumPy functions of :mod:`ppamsafety.plant`.

Ranges (where the model is meaningful, wide enough for every legitimate use):

* angles |q| <= :data:`ANGLE_MAX` = 2 pi rad (one turn; the joints cannot turn further);
* joint speeds |qd| <= :data:`SPEED_MAX` = 1000 rad/s (the closed loop's divergence threshold);
* accelerations |qdd| <= :data:`ACC_MAX` = 1e6 rad/s^2;
* gauge pressures in [-:data:`P_ATM_MAX`, :data:`PRESSURE_MAX`] = [-1 atm, 100 bar];
* torques |tau| <= :data:`TORQUE_MAX` = 1e4 N m.
"""

from __future__ import annotations

import functools
import inspect

import numpy as np

from .._validation import as_float_array, check_instance, check_range_array
from ..params.arm import ArmParameters
from ..params.inertia import BaseParameters

ANGLE_MAX = 2 * np.pi
SPEED_MAX = 1.0e3
ACC_MAX = 1.0e6
P_ATM_MAX = 1.01325e5
PRESSURE_MAX = 1.0e7
TORQUE_MAX = 1.0e4


def check_arm(arm, name: str = "arm"):
    """``arm`` if it is an :class:`~ppamsafety.params.ArmParameters`, else ``TypeError``."""
    return check_instance(name, arm, ArmParameters)


def check_params(params, name: str = "params"):
    """``params`` if None or a :class:`~ppamsafety.params.BaseParameters`, else ``TypeError``."""
    if params is None:
        return None
    return check_instance(name, params, BaseParameters)


def angles(name: str, q, tail: int = 2) -> np.ndarray:
    """Joint angles (..., ``tail``) [rad], finite, |q| <= ANGLE_MAX."""
    q = as_float_array(name, q, shape_tail=(tail,))
    return check_range_array(name, q, -ANGLE_MAX, ANGLE_MAX, unit="rad")


def speeds(name: str, qd) -> np.ndarray:
    """Joint speeds (..., 2) [rad/s], finite, |qd| <= SPEED_MAX."""
    qd = as_float_array(name, qd, shape_tail=(2,))
    return check_range_array(name, qd, -SPEED_MAX, SPEED_MAX, unit="rad/s")


def accelerations(name: str, qdd) -> np.ndarray:
    """Joint accelerations (..., 2) [rad/s^2], finite, |qdd| <= ACC_MAX."""
    qdd = as_float_array(name, qdd, shape_tail=(2,))
    return check_range_array(name, qdd, -ACC_MAX, ACC_MAX, unit="rad/s^2")


def check_pressures(name: str, p, tail: int = 4) -> np.ndarray:
    """Gauge pressures (..., ``tail``) [Pa] in [-P_ATM_MAX, PRESSURE_MAX]."""
    p = as_float_array(name, p, shape_tail=(tail,))
    return check_range_array(name, p, -P_ATM_MAX, PRESSURE_MAX, unit="Pa")


def torques(name: str, tau) -> np.ndarray:
    """Joint torques (..., 2) [N m], |tau| <= TORQUE_MAX."""
    tau = as_float_array(name, tau, shape_tail=(2,))
    return check_range_array(name, tau, -TORQUE_MAX, TORQUE_MAX, unit="N m")


def checks_arm(func):
    """Decorator: check the ``arm`` argument (and ``params`` if any) before ``func`` runs."""
    sig = inspect.signature(func)
    names = list(sig.parameters)
    i_arm = names.index("arm")
    has_params = "params" in names

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        arm = args[i_arm] if len(args) > i_arm else kwargs.get("arm")
        check_arm(arm)
        if has_params:
            check_params(kwargs.get("params"))
        return func(*args, **kwargs)
    return wrapper
