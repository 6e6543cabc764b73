"""Identification from a measured record (``ppamsafety identify``).

:func:`identify_measured` runs the estimators of :mod:`ppamsafety.identify` on
a :class:`~ppamsafety.data.measured.MeasuredData`:

static (``kind="static"``)
    * arm ``static-sawtooth`` records (equilibrium readings): the gravity
      parameters (3.13)-(3.16) from q1, q2 and the joint torques, taken from
      the forces F1..F4 through the lever arms (3.17) when present, otherwise
      from the pressures p1..p4 through the torque functions (2.17) of the
      nominal muscle law; with u1..u4 and p1..p4 also the four valve models
      (3.12).
    * actuator records: the muscle law (3.9)-(3.11) from force, pressure and
      contraction (or position and ``force_law.l0``), compared with the
      nominal law of the metadata.
dynamic (``kind="dynamic"``)
    arm ``open-loop`` / ``closed-loop`` records with q, qd and p: the base
    parameters (B.6) by the acceleration-free filtered LS or WLS (3.28), the
    torques from the pressures through the torque functions (2.17); every
    gap-free segment is one record (filtered separately, first ``drop``
    samples dropped).

The known geometry and the nominal muscle law are those of ``arm`` (default
:func:`ppamsafety.params.thesis_arm`).  :meth:`Identification.write` writes
``identification.json``, ``identification.csv`` and the figures through
:class:`ppamsafety.output.OutputFolder` (kind ``"identify"``).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ..results import Result
from .._validation import check_bool, check_choice, check_instance, check_int, check_range
from .._version import __version__
from ..identify.dynamic import DynamicData, identify_dynamic
from ..identify.static import (identify_gravity, identify_muscle, identify_valves,
                               torques_from_forces)
from ..output import OutputFolder
from ..params import thesis_arm
from ..params.arm import ArmParameters
from ..params.arm_file import arm_fingerprint
from ..plant.torque import joint_torques
from .measured import F, P, Q, QD, U, MeasuredData

KINDS = ("static", "dynamic")
METHODS = ("LS", "WLS")
#: Name of the main result file, table and figure.
JSON_NAME, CSV_NAME, PNG_NAME = "identification.json", "identification.csv", "identification.png"


def _num(x):
    """JSON-safe float (None for NaN/inf: the file never holds NaN)."""
    x = float(x)
    return x if math.isfinite(x) else None


def _lsq_dict(res) -> dict:
    """Estimates and statistics of an LSQResult as a JSON-ready dict."""
    return {
        "method": res.method,
        "quantity": res.quantity,
        "confidence": _num(res.confidence),
        "condition_number": _num(res.condition_number),
        "residual_rms": _num(res.residual_rms),
        "sigma": _num(res.sigma),
        "dof": int(res.dof),
        "n_equations": int(res.measured.size),
        "parameters": [
            {"name": n, "unit": u, "estimate": _num(e), "std_error": _num(s),
             "ci_low": _num(lo), "ci_high": _num(hi)}
            for n, u, e, s, lo, hi in zip(res.names, res.units, res.estimates, res.std_errors,
                                          res.ci_low, res.ci_high)],
    }


@dataclass(frozen=True, eq=False)
class Identification(Result):
    """Estimates identified from one measured record.

    Attributes
    ----------
    source : str
        The data file (or label) identified.
    kind : str
        ``"static"`` or ``"dynamic"``.
    results : dict
        Problem name (``"gravity"``, ``"valve1"``.., ``"muscle"``,
        ``"dynamic"``) -> :class:`~ppamsafety.identify.lsq.LSQResult` or
        :class:`~ppamsafety.identify.dynamic.DynamicResult`.
    main : str
        The problem shown in ``identification.png``.
    settings : dict
        Options and data description (JSON-ready).
    extra : dict
        Per-problem additional numbers (e.g. the nominal law's RMS error).
    notes : tuple of str
        Warnings and remarks (data validation and identification).
    """

    source: str
    kind: str
    results: dict
    main: str
    settings: dict
    extra: dict = field(default_factory=dict)
    notes: tuple = ()

    def _lsq(self, name):
        r = self.results[name]
        return getattr(r, "lsq", r)

    def to_pandas(self) -> pd.DataFrame:
        """One row per (problem, parameter): estimate, std_error, ci_low, ci_high, unit."""
        frames = []
        for name in self.results:
            df = self._lsq(name).to_pandas().reset_index()
            df.insert(0, "problem", name)
            frames.append(df)
        return pd.concat(frames, ignore_index=True)

    def to_dict(self) -> dict:
        """Everything as a JSON-ready dict (no NaN: non-finite numbers become None)."""
        problems = {}
        for name in self.results:
            d = _lsq_dict(self._lsq(name))
            d.update(self.extra.get(name, {}))
            problems[name] = d
        return {"tool": "ppamsafety", "version": __version__, "source": self.source,
                "kind": self.kind, "main": self.main, "settings": self.settings,
                "problems": problems, "notes": list(self.notes)}

    def figures(self) -> dict:
        """{file name: matplotlib Figure}: the main problem as ``identification.png``, the
        others as ``identification_<problem>.png``."""
        out = {}
        for name, res in self.results.items():
            fname = PNG_NAME if name == self.main else f"identification_{name}.png"
            fig = res.plot()
            fig.suptitle(f"{name}: {Path(self.source).name}", fontsize=9)
            out[fname] = fig
        return out

    def write(self, outdir, *, overwrite: bool = False, replace_kind: bool = False) -> list:
        """Write ``identification.json``, ``.csv`` and the PNGs into ``outdir``.

        Through :class:`ppamsafety.output.OutputFolder` (kind ``"identify"``):
        a folder holding files ppamsafety did not write is refused; a previous
        identification is replaced only with ``overwrite``.

        Parameters
        ----------
        outdir : path-like
            Output folder (created if missing).
        overwrite : bool, keyword-only
            Replace a previous ppamsafety identification in ``outdir``.
        replace_kind : bool, keyword-only
            Allow replacing a previous ppamsafety output of another kind (refused by
            default, even with ``overwrite``).

        Returns
        -------
        list of pathlib.Path
            The files written.
        """
        check_bool("overwrite", overwrite)
        check_bool("replace_kind", replace_kind)
        text = json.dumps(self.to_dict(), indent=1, allow_nan=False, ensure_ascii=False) + "\n"
        table = self.to_pandas()
        figs = self.figures()
        folder = OutputFolder(outdir, kind="identify", overwrite=overwrite,
                              replace_kind=replace_kind)
        with folder as st:
            (st / JSON_NAME).write_text(text, encoding="utf-8")
            table.to_csv(st / CSV_NAME, index=False)
            for name, fig in figs.items():
                fig.savefig(st / name, dpi=110)
        return [folder.path / f for f in folder.written]


def _static(data: MeasuredData, arm, method, confidence, notes):
    results, extra, settings = {}, {}, {}
    if data.kind == "actuator":
        if method == "WLS":
            notes.append("the muscle law is fitted by ordinary LS (WLS applies to gravity and "
                         "dynamic identification)")
        eps = data.contraction()
        res = identify_muscle(data.column("force"), data.column("pressure"), eps,
                              confidence=confidence)
        nominal = np.asarray(data.meta["force_law"]["a"], dtype=float)
        f_nom = data.nominal_force()
        extra["muscle"] = {"nominal": [float(x) for x in nominal],
                           "nominal_residual_rms": _num(np.sqrt(np.mean(
                               (data.column("force") - f_nom) ** 2))),
                           "contraction_from": "contraction" if data.has("contraction")
                           else "position"}
        results["muscle"] = res
        return results, "muscle", extra, settings
    if data.experiment != "static-sawtooth":
        raise ValueError(f"{data.source}: --kind static needs an arm static-sawtooth record "
                         f"(equilibrium readings) or an actuator record; this is an arm "
                         f"{data.experiment} record (use --kind dynamic)")
    q = data.column(*Q)
    if data.has(*F):
        tau = torques_from_forces(q, data.column(*F), arm)
        settings["torques_from"] = "forces F1..F4 through the lever arms (3.17)"
    else:
        tau = joint_torques(q, data.column(*P), arm)
        settings["torques_from"] = ("pressures p1..p4 through the torque functions (2.17) of "
                                    "the nominal muscle law")
    weighting = "joint" if method == "WLS" else "none"
    results["gravity"] = identify_gravity(q, tau, gravity_acc=arm.gravity, weighting=weighting,
                                          confidence=confidence)
    if data.has(*U) and data.has(*P):
        for i, r in enumerate(identify_valves(data.column(*U), data.column(*P),
                                              confidence=confidence)):
            results[f"valve{i + 1}"] = r
    else:
        notes.append("no valve model: it needs the set values u1..u4 and pressures p1..p4")
    return results, "gravity", extra, settings


def _dynamic(data: MeasuredData, arm, method, friction, drop, confidence, sign_velocity, notes):
    if data.kind != "arm" or data.experiment not in ("open-loop", "closed-loop"):
        raise ValueError(f"{data.source}: --kind dynamic needs an arm open-loop or closed-loop "
                         f"record; this is a {data.kind} {data.experiment} record")
    missing = [c for c in (*Q, *QD, *P) if not data.has(c)]
    if missing:
        raise ValueError(f"{data.source}: dynamic identification needs q1, q2, qd1, qd2 and "
                         f"p1..p4; missing {', '.join(missing)}")
    stem = Path(data.source).stem
    records = []
    for a, b in data.segments:
        seg = data.frame.iloc[a:b]
        if b - a <= drop:
            notes.append(f"segment rows {a}..{b - 1} ({b - a} samples) skipped: not more than "
                         f"drop = {drop} samples")
            continue
        q = seg[list(Q)].to_numpy(dtype=float)
        tau = joint_torques(q, seg[list(P)].to_numpy(dtype=float), arm)
        dt = float(np.median(np.diff(seg["t"].to_numpy())))
        records.append(DynamicData(q=q, qd=seg[list(QD)].to_numpy(dtype=float), tau=tau, dt=dt,
                                   name=stem if len(data.segments) == 1 else f"{stem}[{a}:{b}]"))
    if not records:
        raise ValueError(f"{data.source}: no segment is long enough for dynamic identification: "
                         f"the longest has {max(b - a for a, b in data.segments)} samples and "
                         f"the first drop = {drop} filtered samples of each are dropped (thesis "
                         f"R = 300); record longer or lower --drop")
    res = identify_dynamic(records, arm, friction=friction, method=method, drop=drop,
                           confidence=confidence, sign_velocity=sign_velocity)
    extra = {"dynamic": {"joint_sigma": [_num(x) for x in res.joint_sigma],
                         "records": list(res.datasets), "omega": _num(res.omega)}}
    settings = {"torques_from": "pressures p1..p4 through the torque functions (2.17) of the "
                                "nominal muscle law",
                "samples_used": int(sum(len(r) - drop for r in records))}
    return {"dynamic": res}, "dynamic", extra, settings


def identify_measured(data, kind: str, *, method: str = "LS", friction: bool = True,
                      drop: int = 300, confidence: float = 0.95, arm=None,
                      sign_velocity: float | None = None) -> Identification:
    """Identify the parameters a measured record can give (see the module docstring).

    Parameters
    ----------
    data : MeasuredData
        A validated record (:func:`ppamsafety.data.load_measured`).
    kind : {"static", "dynamic"}
        Which identification.
    method : {"LS", "WLS"}, keyword-only
        Ordinary LS, or two-step WLS with per-joint weights (gravity and
        dynamic; the muscle law and valves are always LS).
    friction : bool, keyword-only
        Dynamic: model with Coulomb + viscous friction (10 parameters) or not (6).
    drop : int, keyword-only
        Dynamic: filtered samples R dropped at the start of every segment (300).
    confidence : float, keyword-only
        Level of the confidence intervals, in (0, 1).
    arm : ArmParameters, optional, keyword-only
        Known geometry and nominal muscle law (default the thesis arm).
    sign_velocity : float, optional, keyword-only
        Dynamic with friction: smooth sign tanh(qd/v) in the Coulomb columns [rad/s], in
        (0, 1000]; None the ideal sgn (thesis (3.30)).  Refused for a static identification
        or without friction (it would change nothing).

    Returns
    -------
    Identification
    """
    check_instance("data", data, MeasuredData)
    kind = check_choice("kind", kind, KINDS)
    method = check_choice("method", method, METHODS)
    friction = check_bool("friction", friction)
    drop = check_int("drop", drop, 0, 10 ** 7)
    confidence = check_range("confidence", confidence, 0.0, 1.0, lo_open=True, hi_open=True)
    if sign_velocity is not None:
        sign_velocity = check_range("sign_velocity", sign_velocity, 0.0, 1e3, lo_open=True,
                                    unit="rad/s")
        if kind == "static" or not friction:
            raise ValueError(f"sign_velocity = {sign_velocity:g} rad/s shapes the Coulomb "
                             f"friction columns of a dynamic identification with friction; it "
                             f"has no meaning "
                             f"{'in a static one' if kind == 'static' else 'without friction'}")
    arm = thesis_arm() if arm is None else check_instance("arm", arm, ArmParameters)
    arm_label = ("thesis_arm()" if arm is thesis_arm() else
                 f"{arm.name or 'unnamed arm'} (sha256 {arm_fingerprint(arm)[:16]})")
    notes = list(data.notes)
    if kind == "static":
        results, main, extra, settings = _static(data, arm, method, confidence, notes)
    else:
        results, main, extra, settings = _dynamic(data, arm, method, friction, drop, confidence,
                                                  sign_velocity, notes)
    settings = {"kind": kind, "method": method, "confidence": confidence,
                **({"friction": friction, "drop": drop,
                    "sign_velocity": sign_velocity} if kind == "dynamic" else {}),
                "arm": arm_label,
                **settings,
                "data": {"kind": data.kind, "experiment": data.experiment, "rows": len(data),
                         "segments": [list(s) for s in data.segments],
                         "gaps_s": [list(g) for g in data.gaps],
                         "dropped_rows": data.dropped_rows, "dt_s": _num(data.dt),
                         "description": data.meta.get("description", ""),
                         "source": data.meta.get("source", "")}}
    return Identification(source=data.source, kind=kind, results=results, main=main,
                          settings=settings, extra=extra, notes=tuple(notes))


__all__ = ["Identification", "identify_measured", "KINDS", "METHODS"]
