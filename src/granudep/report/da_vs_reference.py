"""Fig 15/16 comparison: DA runs against reference runouts and flow times.

Two steps, both plain tables:

* :func:`granudep.report.reference_2d.reference_from_isph` turns 2D ISPH runs of the Table 5 geometries into a *reference
  table* (one row per run): ``case`` (the Table 5 name, e.g. ``1D-A70``), ``a``, ``theta_deg``,
  ``final_runout_norm`` (ΔL/L0 with ΔL = x_front,final − L0), ``flow_time`` [s],
  ``flow_time_norm`` (t_F/t_c), ``front_definition`` and ``provenance``.
* :func:`compare` matches every DA run (attrs ``case``, ``deposition``) with every reference row of
  the same case and gives the relative errors (computed − reference)/reference of the final runout
  and of the flow time, one row per (run, reference provenance).

Any reference table with the columns ``case``, ``final_runout_norm``, ``flow_time`` (or
``flow_time_norm``) and ``provenance`` can be dropped in (e.g. a user's measurements);
:func:`load_reference` refuses others naming the missing column. The paper's Farin et al. (2014)
measurements are not available to us and are never invented nor back-computed.

Front and flow time are the shared definitions of :mod:`granudep.front` for both models, so the
2D reference and the DA runs are compared like with like; the front definition travels with every
number (column ``front_definition``).
"""
from __future__ import annotations

import math
from typing import Iterable

import numpy as np
import pandas as pd
import xarray as xr

from ..config import ConfigError
from .reference_2d import (FLOW_TIME_TOL, MEASURES, _as_dataset, _attr, _robust_fronts, front_definition,
                           load_reference)

#: the maximum relative errors the paper states in Section 4.3 (vs Farin et al. 2014 measurements)
PAPER_MAX_ERRORS = {
    # variant: (runout error, case a, flow-time error, case a)
    "no deposition": {"runout": 0.55, "runout_a": 0.7, "flow_time": 1.07, "flow_time_a": 1.24},
    "deposition": {"runout": 0.17, "runout_a": 0.45, "flow_time": 0.69, "flow_time_a": 1.24},
}

#: the measure whose runout the reading matrix and the scorecard read first (the paper's front is a
#: thickness threshold; the 1 % volume front does not jump when a thin tip detaches)
MAIN_MEASURES = ("2d", "v99")


def _rel(value: float, ref: float) -> float:
    if not (math.isfinite(value) and math.isfinite(ref)) or ref == 0.0:
        return float("nan")
    return (value - ref) / ref


def da_summary(run) -> dict:
    """The scalars of a DA run used in the comparison."""
    ds, name = _as_dataset(run)
    where = f"DA run {name}"
    if "case" not in ds.attrs:
        raise ConfigError(f"{where}: global attribute 'case' missing (data contract)")
    dep = int(_attr(ds, "deposition", where))
    out = {"case": str(ds.attrs["case"]), "deposition": dep,
           "variant": "deposition" if dep else "no deposition", "da_file": name}
    for key in ("final_runout_norm", "flow_time", "flow_time_norm"):
        if key not in ds:
            raise ConfigError(f"{where}: variable {key!r} missing (data contract)")
        out[key] = float(ds[key].values)
    out["a"] = float(ds.attrs["H0"]) / float(ds.attrs["L0"]) if {"H0", "L0"} <= set(ds.attrs) else float("nan")
    out["da_front_definition"] = front_definition(ds.attrs.get("front_depth_threshold"))
    out["reading"] = da_reading(ds)
    out["reading_label"] = READINGS.get(out["reading"], out["reading"])
    out["A"] = float(ds.attrs.get("A", math.nan)) if dep else float("nan")
    out["B"] = float(ds.attrs.get("B", math.nan)) if dep else float("nan")
    out["x_inf_warning"] = str(ds.attrs.get("x_inf_warning", "")) if dep else ""
    time = np.asarray(ds["time"].values, dtype=float)
    L0 = float(ds.attrs.get("L0", math.nan))
    tol = float(ds.attrs.get("flow_time_tolerance", FLOW_TIME_TOL))
    out.update(_robust_fronts(ds, time, L0, tol))
    return out


#: the A, B readings of the reading matrix, by name
#: plain labels (column ``reading_label`` of comparison.csv and the reading matrix, the summary, the figures)
#: (computed: our regression, normalised, eq 36; paper normalised: Table 5 as printed; paper dimensional:
#: Table 5 read as (hu)_C = A[x] + B in m²/s)
READINGS = {"computed": "computed", "paper": "paper normalised", "paper-dimensional": "paper dimensional",
            "computed-dimensional": "computed dimensional", "none": "no deposition"}


def da_reading(ds: xr.Dataset) -> str:
    """Which A, B reading a DA run used: a :data:`READINGS` key ("none" without deposition)."""
    if not int(ds.attrs.get("deposition", 0)):
        return "none"
    src = str(ds.attrs.get("ab_source", "")).split(" ", 1)[0].strip().lower() or "unknown"
    units = str(ds.attrs.get("coefficient_units", "normalised"))
    return src if units == "normalised" else f"{src}-dimensional"


COMPARE_COLUMNS = ("case", "a", "variant", "deposition", "reading", "reading_label", "A", "B", "reference",
                   "provenance", "reference_dx", "reference_basis", "final_runout_norm",
                   "reference_final_runout_norm", "runout_rel_error", "flow_time", "reference_flow_time",
                   "flow_time_norm", "reference_flow_time_norm", "flow_time_rel_error", "flow_time_basis",
                   *[c for m in MEASURES for c in (f"final_runout_norm_{m}", f"reference_final_runout_norm_{m}",
                                                   f"runout_rel_error_{m}")],
                   "flow_time_v99", "reference_flow_time_v99", "flow_time_v99_rel_error",
                   "da_front_definition", "reference_front_definition", "reference_note", "x_inf_warning", "da_file")


def compare(da_runs: Iterable, references: Iterable) -> pd.DataFrame:
    """Relative errors of every DA run against every reference row of the same case.

    Flow time is compared in seconds when the reference gives ``flow_time``, otherwise as
    t_F/t_c (``flow_time_basis`` says which). DA runs without any reference row are listed with
    NaN errors and ``provenance`` "no reference" so they are not silently dropped.
    """
    refs = [load_reference(r) for r in references]
    if not refs:
        raise ConfigError("--reference: at least one reference table is required")
    ref = pd.concat(refs, ignore_index=True)
    rows = []
    for run in da_runs:
        d = da_summary(run)
        match = ref[ref["case"] == d["case"]]
        if match.empty:
            rows.append({**d, "reference": "no reference", "provenance": "no reference", "reference_dx": np.nan,
                         "reference_basis": "",
                         "reference_final_runout_norm": np.nan,
                         "runout_rel_error": np.nan, "reference_flow_time": np.nan,
                         "reference_flow_time_norm": np.nan, "flow_time_rel_error": np.nan,
                         "flow_time_basis": "", "reference_front_definition": "", "reference_note": ""})
            continue
        for _, r in match.iterrows():
            rft, rftn = float(r["flow_time"]), float(r["flow_time_norm"])
            if math.isfinite(rft):
                basis, err = "s", _rel(d["flow_time"], rft)
            else:
                basis, err = "t/t_c", _rel(d["flow_time_norm"], rftn)
            robust = {}
            for m in MEASURES:
                rv = float(r.get(f"final_runout_norm_{m}", np.nan))
                robust[f"reference_final_runout_norm_{m}"] = rv
                robust[f"runout_rel_error_{m}"] = _rel(d[f"final_runout_norm_{m}"], rv)
            rv99 = float(r.get("flow_time_v99", np.nan))
            robust["reference_flow_time_v99"] = rv99
            robust["flow_time_v99_rel_error"] = _rel(d["flow_time_v99"], rv99)
            rows.append({**d, **robust, "reference": str(r["reference"]), "provenance": str(r["provenance"]),
                         "reference_dx": float(r.get("dx", np.nan)), "reference_basis": str(r["reference_basis"]),
                         "reference_final_runout_norm": float(r["final_runout_norm"]),
                         "runout_rel_error": _rel(d["final_runout_norm"], float(r["final_runout_norm"])),
                         "reference_flow_time": rft, "reference_flow_time_norm": rftn,
                         "flow_time_rel_error": err, "flow_time_basis": basis,
                         "reference_front_definition": str(r["front_definition"]),
                         "reference_note": str(r["note"])})
    if not rows:
        raise ConfigError("compare: no DA run given")
    out = pd.DataFrame(rows)
    for c in COMPARE_COLUMNS:
        if c not in out.columns:
            out[c] = np.nan
    return out[list(COMPARE_COLUMNS)].sort_values(["case", "reference", "deposition", "reading"], kind="stable",
                                                  ignore_index=True)


def improvement(table: pd.DataFrame) -> pd.DataFrame:
    """Case by case (and per reference): does deposition bring the DA prediction closer?

    Columns: case, reference, runout_error_nodep, runout_error_dep, runout_improved,
    flow_time_error_nodep, flow_time_error_dep, flow_time_improved (improved = |error| smaller
    with deposition; NaN where either variant is missing).
    """
    rows = []
    t = table[table["reference"] != "no reference"]
    for (case, prov), g in t.groupby(["case", "reference"], sort=True):
        row = {"case": case, "reference": prov}
        for q, col in (("runout", "runout_rel_error"), ("flow_time", "flow_time_rel_error")):
            nd = g.loc[g["deposition"] == 0, col]
            de = g.loc[g["deposition"] == 1, col]
            e_nd = float(nd.iloc[0]) if len(nd) else float("nan")
            e_de = float(de.iloc[0]) if len(de) else float("nan")
            row[f"{q}_error_nodep"] = e_nd
            row[f"{q}_error_dep"] = e_de
            row[f"{q}_improved"] = (abs(e_de) < abs(e_nd)) if math.isfinite(e_nd) and math.isfinite(e_de) else None
        rows.append(row)
    return pd.DataFrame(rows, columns=["case", "reference", "runout_error_nodep", "runout_error_dep",
                                       "runout_improved", "flow_time_error_nodep", "flow_time_error_dep",
                                       "flow_time_improved"])


def max_errors(table: pd.DataFrame) -> pd.DataFrame:
    """Largest |relative error| per (reference, variant, quantity) next to the paper's stated one."""
    rows = []
    t = table[table["reference"] != "no reference"]
    for (prov, variant), g in t.groupby(["reference", "variant"], sort=True):
        for q, col in (("runout", "runout_rel_error"), ("flow_time", "flow_time_rel_error")):
            e = g[col].astype(float)
            if not np.isfinite(e).any():
                continue
            i = e.abs().idxmax()
            paper = PAPER_MAX_ERRORS.get(variant, {})
            rows.append({"reference": prov, "variant": variant, "quantity": q,
                         "max_abs_rel_error": abs(float(e[i])), "signed_error": float(e[i]),
                         "case": g.loc[i, "case"], "a": float(g.loc[i, "a"]),
                         "paper_max_error": paper.get(q, np.nan), "paper_case_a": paper.get(f"{q}_a", np.nan)})
    return pd.DataFrame(rows, columns=["reference", "variant", "quantity", "max_abs_rel_error",
                                       "signed_error", "case", "a", "paper_max_error", "paper_case_a"])


MATRIX_COLUMNS = ["case", "a", "reference", "reference_dx", "reference_basis", "reading", "reading_label", "A", "B", "measure",
                  "final_runout_norm", "final_runout_norm_nodep", "reference_final_runout_norm",
                  "runout_error", "runout_error_nodep", "runout_improved",
                  "flow_time", "flow_time_nodep", "reference_flow_time",
                  "flow_time_error", "flow_time_error_nodep", "flow_time_improved", "x_inf_warning"]


def reading_matrix(table: pd.DataFrame, measures: Iterable[str] = MAIN_MEASURES) -> pd.DataFrame:
    """The reading matrix: per (case, reference, A/B reading, front measure), the runout and
    flow-time errors with deposition beside those without (the no-deposition run is shared by every
    reading) and whether deposition improved them (smaller |error|).

    ``measure`` "2d" is the default front (2 grain diameters, the ``final_runout_norm`` and
    ``flow_time`` of the files); "v99" the 1 % volume front and its flow time. Rows only for the
    readings present in ``table`` (a run per reading), never filled in.
    """
    t = table[table["reference"] != "no reference"]
    rows = []
    for (case, ref), g in t.groupby(["case", "reference"], sort=True):
        nd = g[g["deposition"] == 0]
        for reading, gr in g[g["deposition"] == 1].groupby("reading", sort=True):
            r = gr.iloc[0]
            n = nd.iloc[0] if len(nd) else None
            for m in measures:
                if m == "2d":
                    cols = ("final_runout_norm", "reference_final_runout_norm", "runout_rel_error",
                            "flow_time", "reference_flow_time", "flow_time_rel_error")
                else:
                    cols = (f"final_runout_norm_{m}", f"reference_final_runout_norm_{m}", f"runout_rel_error_{m}",
                            f"flow_time_{m}", f"reference_flow_time_{m}", f"flow_time_{m}_rel_error")
                fr, rfr, er, ft, rft, ef = cols

                def get(row, c):
                    return float(row[c]) if row is not None and c in row.index else float("nan")
                row = {"case": case, "a": float(r["a"]), "reference": ref, "reference_dx": get(r, "reference_dx"),
                       "reference_basis": str(r.get("reference_basis", "") or ""),
                       "reading": reading, "reading_label": READINGS.get(reading, reading),
                       "A": get(r, "A"), "B": get(r, "B"), "measure": m,
                       "final_runout_norm": get(r, fr), "final_runout_norm_nodep": get(n, fr),
                       "reference_final_runout_norm": get(r, rfr),
                       "runout_error": get(r, er), "runout_error_nodep": get(n, er),
                       "flow_time": get(r, ft), "flow_time_nodep": get(n, ft), "reference_flow_time": get(r, rft),
                       "flow_time_error": get(r, ef), "flow_time_error_nodep": get(n, ef),
                       "x_inf_warning": str(r.get("x_inf_warning", "") or "")}
                for q in ("runout", "flow_time"):
                    e_d, e_n = row[f"{q}_error"], row[f"{q}_error_nodep"]
                    row[f"{q}_improved"] = (abs(e_d) < abs(e_n)) if math.isfinite(e_d) and math.isfinite(e_n) else None
                rows.append(row)
    return pd.DataFrame(rows, columns=MATRIX_COLUMNS)


def matrix_maxima(matrix: pd.DataFrame) -> pd.DataFrame:
    """Per (reference, reading, measure): the largest |error| over the cases with and without
    deposition, and the reduction (no deposition − deposition, in error units) — the paper's
    "improves by up to 38 %" is 55 % − 17 % (runout) = 107 % − 69 % (flow time) = 38 points."""
    rows = []
    for (ref, reading, m), g in matrix.groupby(["reference", "reading", "measure"], sort=True):
        row = {"reference": ref, "reading": reading, "reading_label": READINGS.get(reading, reading), "measure": m,
               "n_cases": int(len(g))}
        for q in ("runout", "flow_time"):
            for kind, col in (("dep", f"{q}_error"), ("nodep", f"{q}_error_nodep")):
                e = g[col].astype(float).abs()
                ok = np.isfinite(e)
                row[f"max_{q}_error_{kind}"] = float(e[ok].max()) if ok.any() else float("nan")
                row[f"max_{q}_case_{kind}"] = str(g.loc[e[ok].idxmax(), "case"]) if ok.any() else ""
            row[f"{q}_max_reduction"] = row[f"max_{q}_error_nodep"] - row[f"max_{q}_error_dep"]
            imp = g[f"{q}_improved"].dropna()
            row[f"{q}_improved_cases"] = f"{int(imp.astype(bool).sum())}/{len(imp)}"
        rows.append(row)
    return pd.DataFrame(rows)


def _pct(x) -> str:
    try:
        x = float(x)
    except (TypeError, ValueError):
        return "n/a"
    return "n/a" if not math.isfinite(x) else f"{100 * x:+.1f} %"


def _yes_no(v) -> str:
    return "n/a" if v is None or (isinstance(v, float) and math.isnan(v)) else ("yes" if bool(v) else "no")


def report_text(table: pd.DataFrame) -> str:
    """Plain-text report: the table, the case-by-case verdict and the maxima vs the paper's."""
    lines = ["DA runs vs reference (relative error = (computed − reference)/reference)", ""]
    show = table[["case", "variant", "reference", "final_runout_norm", "reference_final_runout_norm",
                  "runout_rel_error", "flow_time", "reference_flow_time", "flow_time_rel_error"]].copy()
    show["runout_rel_error"] = show["runout_rel_error"].map(_pct)
    show["flow_time_rel_error"] = show["flow_time_rel_error"].map(_pct)
    with pd.option_context("display.width", 200, "display.max_colwidth", 60, "display.max_rows", 500):
        lines.append(show.to_string(index=False, float_format=lambda v: f"{v:.3f}"))
    defs = sorted(set(table["da_front_definition"]) | set(d for d in table["reference_front_definition"] if d))
    lines += ["", "Front definitions: " + " | ".join(defs), "", "Does deposition improve the prediction?"]
    imp = improvement(table)
    if imp.empty:
        lines.append("  not available (no case has a reference)")
    for _, r in imp.iterrows():
        lines.append(f"  {r['case']} vs {r['reference']}: runout {_pct(r['runout_error_nodep'])} → "
                     f"{_pct(r['runout_error_dep'])} (improved: {_yes_no(r['runout_improved'])}); flow time "
                     f"{_pct(r['flow_time_error_nodep'])} → {_pct(r['flow_time_error_dep'])} "
                     f"(improved: {_yes_no(r['flow_time_improved'])})")
    lines += ["", "Maximum |error| (ours) vs the paper's stated maximum (vs Farin et al. 2014):"]
    mx = max_errors(table)
    if mx.empty:
        lines.append("  not available")
    for _, r in mx.iterrows():
        lines.append(f"  {r['variant']}, {r['quantity']}: ours {100 * r['max_abs_rel_error']:.1f} % "
                     f"({r['case']}, vs {r['reference']}); paper {100 * r['paper_max_error']:.0f} % "
                     f"(a = {r['paper_case_a']:g})")
    return "\n".join(lines)
