"""The reference row: what a controller reads of the desired motion at each sample.

One row per 1 kHz sample (thesis §5.3.4): the joint reference and its first
three time derivatives, the task-space reference of the tool centre point and
its velocity.  The controller kernels read it by the offsets below; the
reference trajectories that fill it (:mod:`ppamsafety.experiments.trajectories`)
are built one layer up.
"""

from __future__ import annotations

from ..layouts import Field, Layout

#: One reference sample (thesis §5.3.4): joint reference and its first three
#: time derivatives (elbow-up inverse kinematics of the task-space path),
#: task-space reference of the tool centre point and its velocity.
REFERENCE_ROW = Layout("reference row", [
    Field("q_d", 2, "rad", "desired link angles q1_d, q2_d", columns=("q1_d", "q2_d")),
    Field("qd_d", 2, "rad/s", "desired joint velocities", columns=("qd1_d", "qd2_d")),
    Field("qdd_d", 2, "rad/s^2", "desired joint accelerations", columns=("qdd1_d", "qdd2_d")),
    Field("qddd_d", 2, "rad/s^3", "desired joint jerks", columns=("qddd1_d", "qddd2_d")),
    Field("r_d", 2, "m", "desired tool-centre-point position (x, y)", columns=("x_d", "y_d")),
    Field("rd_d", 2, "m/s", "desired tool-centre-point velocity", columns=("xd_d", "yd_d")),
])
#: Offsets of the fields of :data:`REFERENCE_ROW` (module constants for the kernels).
R_Q_D, R_QD_D, R_QDD_D, R_QDDD_D, R_R_D, R_RD_D = REFERENCE_ROW.offsets(
    "q_d", "qd_d", "qdd_d", "qddd_d", "r_d", "rd_d")
#: Length of a reference row.
NREF = REFERENCE_ROW.size
#: Column names of a reference table (generated from :data:`REFERENCE_ROW`).
REF_COLUMNS = REFERENCE_ROW.columns()

#: Offsets of single slots, as the controller kernels read them.
R_Q, R_QD, R_QDD, R_QDDD = R_Q_D, R_QD_D, R_QDD_D, R_QDDD_D   #: q_d, its 1st..3rd derivatives
R_X, R_Y = R_R_D, R_R_D + 1          #: x_d, y_d [m] (the two slots of the r_d field)
R_XD, R_YD = R_RD_D, R_RD_D + 1      #: xd_d, yd_d [m/s] (the two slots of rd_d)


__all__ = ["REFERENCE_ROW", "R_Q_D", "R_QD_D", "R_QDD_D", "R_QDDD_D", "R_R_D", "R_RD_D", "NREF",
           "REF_COLUMNS", "R_Q", "R_QD", "R_QDD", "R_QDDD", "R_X", "R_Y", "R_XD",
           "R_YD"]
