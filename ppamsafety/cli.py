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
    i = sub.add_parser("info", help="print the thesis arm's key parameters")
    i.set_defaults(func=_cmd_info)
    return p


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except ValueError as exc:          # bad input: clear message, non-zero exit
        print(f"ppamsafety: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
