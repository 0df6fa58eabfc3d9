"""Figs 15, 16, 17: DA runs (with and without deposition) against the references.

Fig 15 runout ΔL/L0 vs time per case (2D reference, DA with and without deposition, flow times
marked); Fig 16 bars of final runout and flow time with relative errors (from ``granudep compare``);
Fig 17 h_T and h_D profiles of a DA deposition run at two times. The paper plots Farin et al.
(2014) measurements here; they are not available to us and are not drawn.
"""
from __future__ import annotations

import math
from collections import defaultdict

import numpy as np
import pandas as pd

from .. import cases
from ..report.da_vs_reference import READINGS, da_reading
from ..report.reference_2d import load_reference, match_table5
from ..config import ConfigError
from .common import (add_inputs, case_of, classify, front_note, hide_unused, load, load_table, need, new_figure,
                     note, panel_label, register)
from ..front import flow_time

NO_FARIN = "Farin et al. (2014) measurements are not available to us: not shown"
DA_STYLE = {1: dict(color="C0", ls="-", label="DA, with deposition"),
            0: dict(color="C3", ls="--", label="DA, no deposition")}


def _grid(n: int):
    ncols = 1 if n == 1 else 2
    nrows = math.ceil(n / ncols)
    return new_figure(nrows, ncols, panel=(5.2, 3.6))


def _ref_case(ds) -> str:
    a = float(ds.attrs["H0"]) / float(ds.attrs["L0"])
    return match_table5(a, float(ds.attrs["theta_deg"])) or case_of(ds)


def fig15(da_runs, reference_runs=(), reference_tables=(), flow_time_tol: float = 1e-3):
    """Runout ΔL/L0 vs time, one panel per case."""
    by_case = defaultdict(list)
    thresholds = set()
    for r in da_runs:
        ds = load(r)
        need(ds, ["runout", "flow_time", "L0", "deposition"], "fig15 DA run")
        by_case[case_of(ds)].append(ds)
        thresholds.add(("DA", ds.attrs.get("front_depth_threshold")))
    refs = defaultdict(list)
    for r in reference_runs:
        ds = load(r)
        need(ds, ["front_position", "L0", "H0", "theta_deg"], "fig15 2D reference")
        refs[_ref_case(ds)].append(ds)
        thresholds.add(("2D", ds.attrs.get("front_depth_threshold")))
    tables = pd.concat([load_reference(t) for t in reference_tables], ignore_index=True) if reference_tables else None
    names = sorted(set(by_case) | set(refs), key=lambda c: (cases.table5().case_id.tolist() + [c]).index(c))
    if not names:
        raise ValueError("fig15: no DA run or reference given")
    fig, axes = _grid(len(names))
    for k, case in enumerate(names):
        ax = axes.ravel()[k]
        meta = (by_case.get(case) or refs.get(case))[0].attrs
        L0 = float(meta["L0"])
        ref_runs = sorted(refs.get(case, []), key=lambda d: -float(d.attrs.get("dx", np.nan)))
        ref_cols = ["k"] if len(ref_runs) <= 1 else [str(0.65 * (1 - j / (len(ref_runs) - 1)))
                                                     for j in range(len(ref_runs))]  # finer = darker
        for ds, rc in zip(ref_runs, ref_cols):
            t = ds["time"].values
            front = ds["front_position"].values
            status = str(ds.attrs.get("status", "ok"))
            at_rest = bool(np.isfinite(float(ds["time_to_rest"].values))) if "time_to_rest" in ds else True
            extra = " – run FAILED, partial" if status.lower().startswith("failed") else (
                "" if at_rest else " – not at rest at t_end")
            # monotone envelope: the attached front drops when a thin tip detaches from the main mass;
            # the envelope (furthest front so far) never steps backwards, the raw front is drawn thin
            ok = np.isfinite(front)
            env = np.full_like(front, np.nan)
            env[ok] = np.maximum.accumulate(front[ok])
            dxmm = 1e3 * float(ds.attrs.get("dx", np.nan))
            if np.any(env[ok] > front[ok] + 1e-9):
                ax.plot(t, (front - L0) / L0, color=rc, lw=0.5, ls=":",
                        label=f"2D raw attached front, dx = {dxmm:g} mm (tip detaches)")
            ax.plot(t, (env - L0) / L0, color=rc, lw=1.8, label=f"2D ISPH (dx = {dxmm:g} mm){extra}")
            if "front_v99" in ds:
                ax.plot(t, (ds["front_v99"].values - L0) / L0, color=rc, lw=0.9, ls="-.",
                        label=f"2D, 1 % volume front (dx = {dxmm:g} mm)")
            if not extra:
                ax.axvline(flow_time(t, front, flow_time_tol), color=rc, lw=0.8, ls=":")
        for ds in sorted(by_case.get(case, []), key=lambda d: -int(d.attrs["deposition"])):
            st = DA_STYLE[int(ds.attrs["deposition"])]
            r = np.asarray(ds["runout"].values, float)
            ok = np.isfinite(r)
            env = r.copy()
            env[ok] = np.maximum.accumulate(r[ok])
            reading = da_reading(ds) if int(ds.attrs["deposition"]) else ""  # plain label, as in comparison.csv
            lab = st["label"] + (f" (A, B: {READINGS.get(reading, reading)})" if reading else "")
            ax.plot(ds["time"].values, env / L0, color=st["color"], ls=st["ls"], lw=1.5, label=lab)
            ax.axvline(float(ds["flow_time"].values), color=st["color"], lw=0.8, ls=":")
        if tables is not None:
            for j, (_, row) in enumerate(tables[tables["case"] == case].iterrows()):
                ax.axhline(float(row["final_runout_norm"]), color="0.5", lw=1, ls="-.",
                           label=f"final runout: {row['provenance']}"[:60])
        ax.set_xlabel("time t (s)")
        ax.set_ylabel("runout ΔL/L0 (–)")
        a = float(meta["H0"]) / L0
        panel_label(ax, k, f"{case}: a = {a:.2f}, θ = {float(meta['theta_deg']):g}°")
        ax.set_ylim(bottom=0)
        ax.set_xlim(left=0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6, loc="best")
    hide_unused(axes, len(names))
    defs = "; ".join(sorted({f"{src} {front_note(th)}" for src, th in thresholds}))
    note(fig, f"ΔL = x_front − L0 (from the gate). {defs}. Curves are the monotone envelope of the front (the "
              "furthest front reached so far): the attached front steps back when a thin tip detaches from the main "
              "mass (raw 2D front dotted where it does). 2D runs shaded by resolution (finer = darker). Dotted verticals: flow time t_F (front moves "
              f"< {1e3 * flow_time_tol:.0f} mm afterwards). {NO_FARIN}.")
    return fig


def fig16(compare_table):
    """Bars of final runout and flow time per case with relative errors vs each reference."""
    t = load_table(compare_table, ("case", "variant", "deposition", "provenance", "final_runout_norm",
                                   "reference_final_runout_norm", "runout_rel_error", "flow_time",
                                   "reference_flow_time", "flow_time_rel_error"), "fig16 compare CSV")
    if "reference" not in t.columns:
        from ..report.reference_2d import source_label
        t = t.assign(reference=[source_label(p) for p in t["provenance"]])
    t = t[t["reference"] != "no reference"]
    if t.empty:
        raise ValueError("fig16: the compare table has no row with a reference")
    use_norm = {"flow_time_norm", "reference_flow_time_norm"} <= set(t.columns) and \
        np.isfinite(t["reference_flow_time_norm"].astype(float)).all()
    ft, rft = ("flow_time_norm", "reference_flow_time_norm") if use_norm else ("flow_time", "reference_flow_time")
    case_list = sorted(t["case"].unique(), key=lambda c: (cases.table5().case_id.tolist() + [c]).index(c))
    provs = list(dict.fromkeys(t["reference"]))
    fig, axes = new_figure(1, 2, panel=(6.2, 4.2))
    bars = [("ref", p) for p in provs] + [("da", 0), ("da", 1)]
    width = 0.8 / len(bars)
    hatch_ref = ["", "//", "xx", ".."]
    for ax, (q, ref_q, err_q, ylabel) in zip(axes[0], (
            ("final_runout_norm", "reference_final_runout_norm", "runout_rel_error", "final runout ΔL∞/L0 (–)"),
            (ft, rft, "flow_time_rel_error", "flow time t_F/t_c (–)" if use_norm else "flow time t_F (s)"))):
        for ci, case in enumerate(case_list):
            g = t[t["case"] == case]
            for bi, (kind, key) in enumerate(bars):
                x = ci - 0.4 + width * (bi + 0.5)
                if kind == "ref":
                    rows = g[g["reference"] == key]
                    if rows.empty:
                        continue
                    ax.bar(x, float(rows[ref_q].iloc[0]), width, color="0.75", edgecolor="k",
                           hatch=hatch_ref[provs.index(key) % 4], label=f"reference: {key}"[:70] if ci == 0 else None)
                    rdx = float(rows["reference_dx"].iloc[0]) if "reference_dx" in rows else math.nan
                    if math.isfinite(rdx):  # each reference bar says its dx (the converged one varies by case)
                        ax.text(x, 0, f"{1e3 * rdx:g} mm", ha="center", va="bottom", fontsize=5, rotation=90)
                else:
                    rows = g[g["deposition"] == key]
                    if rows.empty:
                        continue
                    st = DA_STYLE[key]
                    val = float(rows[q].iloc[0])
                    lab = st["label"]
                    if key and "reading_label" in rows and isinstance(rows["reading_label"].iloc[0], str):
                        lab += f" (A, B: {rows['reading_label'].iloc[0]})"
                    ax.bar(x, val, width, color=st["color"], alpha=0.85, label=lab if ci == 0 else None)
                    errs = [f"{100 * float(e):+.0f}%" for e in rows[err_q] if np.isfinite(float(e))]
                    ax.text(x, val, "\n".join(errs), ha="center", va="bottom", fontsize=7, color=st["color"])
        ax.set_xticks(range(len(case_list)), case_list)
        ax.set_ylabel(ylabel)
        ax.margins(y=0.2)
        ax.grid(axis="y", alpha=0.3)
    panel_label(axes[0, 0], 0, "final runout")
    panel_label(axes[0, 1], 1, "flow time")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside upper center", ncol=2, fontsize=8)
    defs = sorted(set(t["da_front_definition"].astype(str)) | set(t["reference_front_definition"].astype(str))) \
        if "da_front_definition" in t else []
    note(fig, "Numbers above the DA bars: relative error (computed − reference)/reference vs "
              + (" and ".join(f"'{p}'" for p in provs)) + " (in that order). "
              + ("Definitions: " + " | ".join(defs) + ". " if defs else "") + NO_FARIN + ".")
    return fig


def fig17(da_runs, times=None):
    """h_T = h + h_D (line) and h_D (filled) along the slope at two times, one panel per run."""
    runs = [load(r) for r in da_runs]
    for ds in runs:
        need(ds, ["flow_depth", "deposit_depth", "x_grid", "L0", "flow_time"], "fig17 DA run")
    n = len(runs)
    if not n:
        raise ValueError("fig17: no DA run given")
    ncols = 1 if n == 1 else 2
    fig, axes = new_figure(math.ceil(n / ncols), ncols, panel=(5.6, 3.0))
    for k, ds in enumerate(runs):
        ax = axes.ravel()[k]
        time = ds["time"].values
        if times:
            want = list(times)
        else:
            tf = float(ds["flow_time"].values)
            tf = tf if np.isfinite(tf) else float(time[-1])
            want = [0.4 * tf, float(time[-1])]
        xg = ds["x_grid"].values
        L0 = float(ds.attrs["L0"])
        for j, tw in enumerate(want):
            i = int(np.argmin(np.abs(time - tw)))
            hD = ds["deposit_depth"].values[i]
            hT = ds["flow_depth"].values[i] + hD
            c = f"C{j}"
            ax.plot(xg, 1e3 * hT, color=c, lw=1.5, label=f"h_T, t = {time[i]:.2f} s")
            ax.fill_between(xg, 0, 1e3 * hD, color=c, alpha=0.3, label=f"h_D (deposit), t = {time[i]:.2f} s")
            ax.plot(xg, 1e3 * hD, color=c, lw=0.8, ls="--")
        ax.axvline(L0, color="0.4", lw=0.8, ls=":")
        ax.text(L0, ax.get_ylim()[1] * 0.95, " gate", fontsize=7, color="0.4", va="top")
        dep = "with deposition" if int(ds.attrs.get("deposition", 1)) else "no deposition"
        panel_label(ax, k, f"{case_of(ds)} ({dep}), θ = {float(ds.attrs['theta_deg']):g}°")
        ax.set_xlabel("x along the slope from the back wall (m)")
        ax.set_ylabel("depth (mm)")
        occupied = (ds["flow_depth"].values.max(0) + ds["deposit_depth"].values.max(0)) > 0
        ax.set_xlim(0, 1.05 * float(xg[occupied].max() if occupied.any() else xg[-1]))
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    hide_unused(axes, n)
    note(fig, "Bed-normal depths on the DA grid: h_T = h + h_D (total), h_D = deposit (below the F/D interface).")
    return fig


def reading_matrix_figure(matrix):
    """The reading matrix at a glance: runout and flow-time errors (colour, %) of every A, B reading with
    and without deposition, per case and reference; one row of panels per front measure."""
    t = load_table(matrix, ("case", "reference", "reading", "measure", "runout_error", "runout_error_nodep",
                            "flow_time_error", "flow_time_error_nodep"), "reading matrix CSV")
    if t.empty:
        raise ValueError("reading matrix: no row")
    measures = list(dict.fromkeys(t["measure"]))
    cols = list(dict.fromkeys(zip(t["case"], t["reference"])))
    readings = list(dict.fromkeys(t["reading"]))
    rows = ["no deposition"] + [READINGS.get(rd, rd) for rd in readings]  # plain labels (reading_label)
    fig, axes = new_figure(len(measures), 2, panel=(1.2 + 1.25 * len(cols), 0.9 + 0.45 * len(rows)))
    from matplotlib import colormaps
    cmap = colormaps["RdBu_r"]
    for i, m in enumerate(measures):
        tm = t[t["measure"] == m]
        for j, q in enumerate(("runout", "flow_time")):
            ax = axes[i, j]
            z = np.full((len(rows), len(cols)), np.nan)
            for c, (case, ref) in enumerate(cols):
                g = tm[(tm["case"] == case) & (tm["reference"] == ref)]
                if g.empty:
                    continue
                z[0, c] = float(g[f"{q}_error_nodep"].iloc[0])
                for r, rd in enumerate(readings, start=1):
                    gr = g[g["reading"] == rd]
                    if len(gr):
                        z[r, c] = float(gr[f"{q}_error"].iloc[0])
            im = ax.imshow(100 * z, cmap=cmap, vmin=-100, vmax=100, aspect="auto")
            for r in range(len(rows)):
                for c in range(len(cols)):
                    txt = "–" if not np.isfinite(z[r, c]) else f"{100 * z[r, c]:+.0f}"
                    ax.text(c, r, txt, ha="center", va="center", fontsize=8,
                            color="w" if np.isfinite(z[r, c]) and abs(z[r, c]) > 0.6 else "k")
            ax.set_xticks(range(len(cols)), [f"{cs}\n{rf.replace('2D ', '')}" for cs, rf in cols], fontsize=6,
                          rotation=30, ha="right")
            ax.set_yticks(range(len(rows)), rows, fontsize=7)
            panel_label(ax, 2 * i + j, f"{q.replace('_', ' ')} error (%), front {m}")
            fig.colorbar(im, ax=ax, shrink=0.8, label="(DA − 2D)/2D (%)")
    note(fig, "Rows: DA without deposition, and with deposition for each A, B reading (computed: our regression; "
              "paper normalised: Table 5 as printed; paper dimensional: Table 5 as m²/s). Columns: case and 2D reference "
              "(labelled with its dx). Front 2d: attached front at 2 grain diameters; v99: 1 % volume front; the "
              "same rule on both models' depth profiles. " + NO_FARIN + ".")
    return fig


# ---- CLI -------------------------------------------------------------------------------------------

def _args15(p):
    add_inputs(p, "DA runs (with/without deposition), 2D ISPH reference runs, reference tables (CSV)")
    p.add_argument("--flow-time-tol", type=float, default=1e-3, metavar="M",
                   help="2D flow time: front moves less than this afterwards (m)")


@register("fig15", "runout ΔL/L0 vs time: 2D reference, DA with/without deposition (flow times marked)", _args15)
def _fig15(args):
    k = classify(args.inputs, ("da", "isph", "reference"), "fig15")
    return fig15(k["da"], k["isph"], k["reference"], args.flow_time_tol)


def _args16(p):
    add_inputs(p, "the output of granudep compare (CSV)")


@register("fig16", "final runout and flow time bars with relative errors vs each reference", _args16)
def _fig16(args):
    k = classify(args.inputs, ("compare",), "fig16")
    if len(k["compare"]) != 1:
        raise ConfigError("fig16: give exactly one compare CSV")
    return fig16(k["compare"][0])


def _argsrm(p):
    p.add_argument("matrix", help="compare/reading_matrix.csv (granudep compare --matrix)")


@register("reading-matrix", "runout and flow-time errors of every A, B reading x reference at a glance", _argsrm)
def _reading_matrix(args):
    return reading_matrix_figure(args.matrix)


def _args17(p):
    add_inputs(p, "DA runs with deposition")
    p.add_argument("--times", nargs="+", type=float, metavar="T", help="times (s); default 0.4 t_F and the end")


@register("fig17", "h_T and h_D profiles of DA deposition runs at two times", _args17)
def _fig17(args):
    k = classify(args.inputs, ("da",), "fig17")
    return fig17(k["da"], args.times)
