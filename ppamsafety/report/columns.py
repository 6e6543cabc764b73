"""The units of the columns of the report's tables: its CSV files and Markdown tables.

A column either says its unit in its name (``F_max [N]``, ``q1_deg``, ``chattering_Pa``:
:func:`unit_in_name`) or is declared here: :data:`COMMON` for the names the sections share,
:data:`BY_SECTION` for a name a section uses in a sense of its own.  ``"-"`` declares a
dimensionless number (a ratio, a count, HIC), :data:`PER_ROW` a column whose unit changes from
row to row and stands in the row's ``unit`` column.  Text and flag columns need no unit.

The report writes every CSV column of every section with its unit to ``columns.csv`` (its data
dictionary: the CSV files themselves keep their names, which scripts read) and shows the
units in the headers of its Markdown tables (:func:`with_header_units`);
``tests/test_readable_outputs.py`` fails on a numeric column that has none.
"""

from __future__ import annotations

import re

from ..sweep_cases import column_unit as sweep_column_unit

#: The unit of a column whose rows are in different units: the row's ``unit`` column.
PER_ROW = "see column unit"

#: Unit suffixes of column names (``F_max_N``, ``t0_s``, ``mean_error_m``): suffix -> unit.
SUFFIXES = {"N": "N", "kN": "kN", "kg": "kg", "m": "m", "mm": "mm", "s": "s", "ms": "ms",
            "deg": "deg", "rad": "rad", "bar": "bar", "Pa": "Pa", "Nm": "N m", "J": "J",
            "g": "g", "Hz": "Hz", "kgm2": "kg m^2", "Nm_per_rad": "N m/rad",
            "Nm_per_Pa": "N m/Pa", "m_s": "m/s", "rad_s": "rad/s", "rad_s2": "rad/s^2",
            "rad_s3": "rad/s^3", "pct": "%", "kg_m2": "kg m^2"}

#: Column name -> unit, for the names several sections share.
COMMON = {
    "F_max": "N", "HIC36": "-", "HIC15": "-", "HIC": "-", "tcp_speed": "m/s",
    "K1": "N m/rad", "K2": "N m/rad", "lambda": "s", "lam": "s", "t0": "s", "t0_HIC": "s",
    "q1": "rad", "q2": "rad", "qd1": "rad/s", "qd2": "rad/s", "E_balance_error": "-",
    "HIC_thesis": "-", "Fmax_thesis": "N", "HIC_ratio": "-", "Fmax_ratio": "-",
    "ratio_mean": "-", "ratio_max": "-", "circle_duration": "s", "circle_err_mean": "m",
    "circle_err_max": "m", "thesis_mean_m": "m", "thesis_max_m": "m", "ki_bar": "bar/(rad s)",
    "lambda_s": "s", "period_s": "s", "count": "-", "precision": "-", "wilson_low": "-",
    "required": "-", "right": "-", "names": "-", "seconds": "s", "n": "-",
    "sigma_log": "-", "ratio_nominal": "-", "interval_low": PER_ROW, "interval_high": PER_ROW,
    "nominal": PER_ROW, "value": PER_ROW, "hidden": PER_ROW, "fitted": PER_ROW,
    "ci_low": PER_ROW, "ci_high": PER_ROW, "limit": PER_ROW, "limit_named": PER_ROW,
    "rho_before": "-", "rho_after": "-", "column_norm": "-", "divergence_reason": None,
    "contact_time": "s", "dt": "s",
}

#: Section -> {column: unit}: a name in a section's own sense (it wins over :data:`COMMON`).
BY_SECTION = {
    "as_built": {
        "thesis": PER_ROW, "as_built": PER_ROW, "ratio_as_built": "-", "z_nominal": "-",
        "z_as_built": "-", "theta": "-", "theta_sd": "-", "theta_low": "-", "theta_high": "-",
        "numbers": "-", "chi2_nominal": "-", "chi2_as_built": "-", "ln_ratio_sd_as_built": "-",
        "pivot_ratio": "-", "abs_cos": "-", "weakest_loading": "-", "iteration": "-",
        "chi2": "-", "objective": "-", "radius": "-", "strength": "-",
        # the pull of each statistic on each effect: shares, dimensionless
        "valve_time_constant_factor": "-", "valve_dead_time": "-",
        "friction_coulomb_factor": "-", "hysteresis_delta": "-", "payload_mass": "-",
    },
    "cylinder_friction": {
        "precision_wilson_low": "-", "stability": "-", "held_out_gain": "-", "samples": "-",
        "used": "-", "strokes": "-", "rho_left_out": "-",
    },
    "diagnose_cases": {
        "before": PER_ROW, "after": PER_ROW, "noise": PER_ROW, "before_over_noise": "-",
        "after_over_noise": "-", "ratio_best": "-", "best_theta": "-", "best_value": PER_ROW,
        "chi2_min": "-", "chi2_per_stat": "-", "chi2_reduction": "-", "ratio_geo_mean": "-",
        "diverged_points": "-",
        # cosines between the effects' columns: dimensionless
        "payload_mass": "-", "friction_coulomb_factor": "-", "friction_viscous_factor": "-",
        "valve_offset_delta": "-", "valve_gain_factor": "-", "valve_time_constant_factor": "-",
        "polytropic_n": "-", "hysteresis_delta": "-", "valve_dead_time": "-",
    },
    "diagnose_sawtooth": {"rest point": "-"},
    "diagnose_trust": {
        "above_limit": "-", "named_when_above": "-", "high_when_above": "-",
        "confounded_when_hidden": "-", "named_when_below": "-", "high_names": "-",
        "high_right": "-", "ratio_from": "-", "ratio_to": "-", "effects": "-", "named": "-",
        "named_rate": "-", "high": "-", "high_rate": "-", "confounded": "-",
        "named_right": "-", "nothing": "-", "other": "-", "unexplained": "-", "hits": "-",
        "target": "-", "hidden": "-", "value": "-",
    },
    "effects": {
        "median |ln ratio|": "-", "median ratio": "-", "min ratio": "-", "max ratio": "-",
        "cells": "-", "level": "-", **{f"eps{k}": "-" for k in range(1, 5)},
        "median hysteresis / nominal": "-", "min": "-", "max": "-",
        **{f"F{k}_model": "N" for k in range(1, 5)}, **{f"F{k}_plant": "N" for k in range(1, 5)},
        **{f"F{k}_ratio": "-" for k in range(1, 5)},
        "pattern_q1": "-", "steps_q1": "-", "pattern_unbiased_q1": "-", "pattern_q2": "-",
        "steps_q2": "-", "pattern_unbiased_q2": "-", "q2_rising": "-", "q2_falling": "-",
        "F3_below_q2_rising": "-", "F4_above_q2_rising": "-", "F3_above_q2_falling": "-",
        "F4_below_q2_falling": "-", "contracting_below": "-", "extending_above": "-",
        "moving_groups": "-",
    },
    "head_model": {"k": "N/m^n", "b": "N s/m^(n+1)", "HIC_model": "-", "residual_sigma": "-"},
    "interaction": {"ss_error_rls_rel": "-", "ss_error_mo_rel": "-"},
    "iso_15066": {
        "F_free": "N", "F_clamped": "N", "F_wall": "N", "clamp_ratio": "-", "m_eff_own": "kg",
        "F_engine_linear": "N", "F_formula_own_mass": "N", "F_formula_annex_mass": "N",
        "F_engine_hunt_crossley": "N", "factor": "-", "F_limit": "N", "lambda_min_force": "s",
        "v_max_annex": "m/s", "lambda_min_speed": "s", "F_at_lambda_0.4": "N", "F_qs": "N",
        "F_transient": "N", "K": "N/m", "m_H": "kg", "m_R": "kg", "mu": "kg",
        "E_transfer": "J", "E_transfer_qs": "J", "v_max": "m/s", "t_clamp": "s",
        "t_hold": "s", "F_steady": "N", "F_normal": "N", "F_tangential": "N",
        "F_2s_earlier": "N", "bound_same_dir": "N", "tensile_fraction": "-",
        "F_clamped_forehead": "N", "F_clamped_face": "N", "F_clamped_thesis_HC": "N",
        "F_clamped_head_HC": "N", "Fmax_thesis_free": "N", "clamped_HC_over_thesis": "-",
        "F_quasi_static": "N", "lambda_min_force_hc": "s", "F_at_lambda_0.4_hc": "N",
        # iso_question.csv: force criteria only (the ISO/TS 15066 transient and quasi-static)
        "limit": "N", "margin": "N",
    },
    "reaction": {
        "F_max_rel_diff": "-", "max_dF_over_Fmax": "-", "HIC36_closed_loop": "-",
        "HIC36_engine": "-", "margin": "-", "HIC36_1": "-", "HIC36_2": "-", "impacts": "-",
        "energy_error": "-", "valve_fraction_by_contact_end": "-",
        "span_over_contact_torque": "-", "Fmax_1_spread_rel": "-",
    },
    "safety_summary": {"margin": PER_ROW, "covered_value": PER_ROW, "variants": "-",
                       "variants_passing": "-"},
    "person": {"margin": PER_ROW, "passing": "-", "impacts": "-", "rms_sigma": "-",
               "restitution": "-", "after_pulse_share": "-", "covering_strain": "-"},
    "safety": {
        "margin": PER_ROW,
        "HIC36 4 instants": "-", "HIC36 every instant": "-", "HIC miss %": "%",
        "F_max 4 instants": "N", "F_max every instant": "N", "F_max miss %": "%",
        "t0 of worst": "s",
    },
    "smc": {"gamma": "rad/s^2", "plant_T": "s", "model_T": "s", "t_scale": "-",
            "K_over_gamma": "1/s", "cost": "m bar", "rank": "-"},
    "stiffness": {
        "B": "kg m^2", "k": "N m/rad", "F/F_thesis": "-", "F_k1": "N", "F_k6000": "N",
        "max |E error|": "-", "B1": "kg m^2", "B2": "kg m^2", "m_eff": "kg", "F_rigid": "N",
        "F_two_body": "N", "two-body/rigid - 1": "-", "k_max": "N m/rad", "F_flex_kmax": "N",
        "flex(k_max)/rigid - 1": "-", "frozen": "N", "flexible, B = 0 (PPAM)": "N",
        "flexible, B = PPAM bound": "N", "flexible, B = 0.01": "N", "flexible, B = 0.1": "N",
        "flexible, B = 1": "N",
    },
    "worst_direction": {
        "F_max_along_velocity": "N", "t0_F_max_along_velocity": "s", "F_max_worst": "N",
        "t0_F_max_worst": "s", "ratio_F_max": "-", "F_max_same_instant": "N",
        "ratio_F_max_same_instant": "-", "HIC36_along_velocity": "-",
        "t0_HIC36_along_velocity": "s", "HIC36_worst": "-", "t0_HIC36_worst": "s",
        "ratio_HIC36": "-", "HIC36_same_instant": "-", "ratio_HIC36_same_instant": "-",
        "instants": "-", "bound_pruned": "-", "envelope_pruned": "-",
        "simulated_instants": "-", "searched": "-", "engine_runs": "-", "rho": "-",
        "HIC_table_6_1": "-", "Fmax_table_6_1": "N",
    },
}

#: Sections whose tables are safety sweeps: a column no table here declares takes the unit the
#: sweep gives it (:func:`ppamsafety.sweep_cases.column_unit`).
SWEEP_SECTIONS = ("lambda_sweep",)

_BRACKET = re.compile(r"\[([^\]]+)\]")


def unit_in_name(column: str):
    """The unit a column name states itself: ``F_max [N]`` -> ``N``, ``q1_deg`` -> ``deg``.

    Parameters
    ----------
    column : str
        A column name.

    Returns
    -------
    str or None
    """
    m = _BRACKET.search(str(column))
    if m:
        return m.group(1)
    for suf in sorted(SUFFIXES, key=len, reverse=True):
        if str(column).endswith("_" + suf):
            return SUFFIXES[suf]
    return None


def unit_of(column: str, section: str | None = None):
    """The unit of a column of a section's table: in its name, declared for the section, or
    declared for every section.

    Parameters
    ----------
    column : str
        The column name.
    section : str, optional
        The section (:data:`ppamsafety.sections.REGISTRY`).

    Returns
    -------
    str or None
        The unit (``"-"`` dimensionless, :data:`PER_ROW`), or None if nothing declares one.
    """
    u = unit_in_name(column)
    if u is not None:
        return u
    own = BY_SECTION.get(section, {})
    if column in own:
        return own[column]
    if column not in COMMON and section in SWEEP_SECTIONS:
        return sweep_column_unit(column)         # a sweep's verdict columns (<criterion>_margin)
    return COMMON.get(column)


def with_header_units(markdown: str, section: str | None = None) -> str:
    """A section's Markdown with the unit of every declared column in its tables' headers.

    A header cell that states no unit itself and is declared (:func:`unit_of`) gets
    `` [unit]`` (``[-]`` dimensionless, ``[per row]`` where a ``unit`` column says it); a
    header cell not declared is left as it is.

    Parameters
    ----------
    markdown : str
        The section's Markdown.
    section : str, optional
        Its name.

    Returns
    -------
    str
    """
    lines = markdown.split("\n")
    for i, line in enumerate(lines):
        s = line.strip()
        nxt = lines[i + 1].strip() if i + 1 < len(lines) else ""
        if not (s.startswith("|") and s.endswith("|") and re.fullmatch(r"\|(\s*:?-{3,}:?\s*\|)+",
                                                                       nxt)):
            continue
        cells = [c.strip() for c in s[1:-1].split("|")]
        out = []
        for c in cells:
            u = unit_of(c, section) if c and unit_in_name(c) is None else None
            out.append(c if u is None else f"{c} [{'per row' if u == PER_ROW else u}]")
        lines[i] = line[:len(line) - len(line.lstrip())] + "| " + " | ".join(out) + " |"
    return "\n".join(lines)


__all__ = ["PER_ROW", "SUFFIXES", "COMMON", "BY_SECTION", "unit_in_name", "unit_of",
           "with_header_units"]
