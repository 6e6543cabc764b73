"""Command-line interface: ``ppamsafety report``, ``ppamsafety info``."""

from __future__ import annotations

import argparse
import sys


def _cmd_report(args) -> int:
    from .report.build import build_report

    only = args.only.split(",") if args.only else None
    index = build_report(args.outdir, quick=args.quick, only=only)
    print(f"report written to {index}")
    return 0


def _cmd_impact(args) -> int:
    import numpy as np

    from .impact.model import simulate_impacts
    from .params import thesis_arm
    from .units import DEG

    arm = thesis_arm()
    q = np.array(args.q, dtype=float) * DEG
    res = simulate_impacts(arm, q, args.qd, args.stiffness, head=args.head, dt=args.dt,
                           history=bool(args.history))
    s = res.summary.iloc[0]
    print(f"head model      {res.head.name}")
    print(f"tool speed      {s.tcp_speed:.4g} m/s")
    print(f"F_max           {s.F_max:.4g} N at {1e3 * s.t_Fmax:.3g} ms")
    print(f"HIC36           {s.HIC36:.4g}  window [{1e3 * s.HIC36_t1:.3g}, {1e3 * s.HIC36_t2:.3g}] ms")
    print(f"HIC15           {s.HIC15:.4g}  window [{1e3 * s.HIC15_t1:.3g}, {1e3 * s.HIC15_t2:.3g}] ms")
    print(f"max penetration {1e3 * s.delta_max:.4g} mm, peak head acceleration {s.a_max_g:.4g} g")
    print(f"energy to head  {s.E_head_final:.4g} J of {s.E_initial:.4g} J")
    if args.history:
        res.histories[0].to_csv(args.history, index=False)
        print(f"time history written to {args.history}")
    return 0


def _cmd_info(args) -> int:
    import numpy as np

    from .params import thesis_arm
    from .units import BAR

    arm = thesis_arm()
    L = arm.links
    print("thesis arm (plant):")
    print(f"  link masses m1 = {L.m1:.3f} kg, m2 = {L.m2:.3f} kg")
    print(f"  mean pressures p_m = {np.array(arm.pneumatics.p_mean) / BAR} bar")
    print(f"  valve time constants = {[v.time_constant for v in arm.valves.valves]} s")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argparse parser of the ``ppamsafety`` command."""
    p = argparse.ArgumentParser(
        prog="ppamsafety",
        description="Safety and impact analysis of a 2-DOF arm driven by pleated pneumatic "
                    "artificial muscles (PPAMs).")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("report", help="regenerate the report folder from scratch")
    r.add_argument("--outdir", default="reports", help="output folder (default: reports)")
    r.add_argument("--quick", action="store_true", help="coarse grids and short sweeps")
    r.add_argument("--only", default="", help="comma-separated study names to run")
    r.set_defaults(func=_cmd_report)
    m = sub.add_parser("impact", help="simulate one impact of the thesis arm with a head")
    m.add_argument("--q", nargs=2, type=float, required=True, metavar=("Q1", "Q2"),
                   help="link angles at impact [deg]")
    m.add_argument("--qd", nargs=2, type=float, required=True, metavar=("QD1", "QD2"),
                   help="link angular velocities at impact [rad/s]")
    m.add_argument("--stiffness", nargs=2, type=float, default=(43.0, 27.0),
                   metavar=("K1", "K2"), help="joint stiffnesses [Nm/rad] (default 43 27)")
    m.add_argument("--head", default="thesis-frontal", help="head model name")
    m.add_argument("--dt", type=float, default=2e-5, help="integration step [s]")
    m.add_argument("--history", default="", help="write the time history to this CSV file")
    m.set_defaults(func=_cmd_impact)
    i = sub.add_parser("info", help="print the thesis arm's key parameters")
    i.set_defaults(func=_cmd_info)
    return p


def main(argv=None) -> int:
    """Entry point of the ``ppamsafety`` command; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except ValueError as exc:          # bad input: clear message, non-zero exit
        print(f"ppamsafety: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
