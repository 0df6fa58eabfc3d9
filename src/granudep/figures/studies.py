"""Convergence and sensitivity figures (beyond the paper).

``convergence``: from a list of files of the same case(s) at several resolutions: 2D ISPH runs
(final runout ΔL/L0 of the robust front measures and the time to rest vs dx), regression
critical.csv files (critical times (t_s)_C vs dx; dx from a ``dx`` column, else from ``dx<number>``
in the path, else paired in order with the 2D runs) and DA runs (final runout and flow time vs particle count).

``sensitivity``: from one or more CSVs with columns ``parameter``, ``value`` and any of ``A``,
``B``, ``final_runout_norm``, ``flow_time`` (one row per swept value; an optional ``baseline``
column of 0/1 marks the paper's value): each quantity against each swept parameter.
"""
from __future__ import annotations

import re
from collections import defaultdict
from pathlib import Path

import numpy as np
import pandas as pd

from ..config import ConfigError
from .common import add_inputs, case_of, classify, hide_unused, load, load_table, new_figure, note, panel_label, register

_DX = re.compile(r"dx([0-9]*\.?[0-9]+)")


def _dx_of_csv(path, df) -> float | None:
    if "dx" in df.columns:
        return float(df["dx"].iloc[0])
    m = _DX.findall(str(path))
    return float(m[-1]) if m else None


#: a thickness threshold is resolved by a run when it spans at least this many particle layers
FRONT_MIN_LAYERS = 2.0


def _front_row(ds) -> dict:
    """ΔL/L0 of the robust front measures of a 2D run and its time to rest t_s/t_c; an
    attached front whose thickness threshold spans fewer than FRONT_MIN_LAYERS particle layers
    (threshold < 2 dx: a sheet one particle thick reads as that thickness) is not resolved: NaN."""
    L0, dx, d = float(ds.attrs["L0"]), float(ds.attrs["dx"]), float(ds.attrs["d"])
    out = {"dx": dx, "t_rest": float(ds.attrs.get("time_to_rest_norm", np.nan))}
    for key, thickness in (("v99", None), ("5mm", 0.005), ("2d", 2.0 * d)):
        var = f"final_front_{key}"
        x = float(ds[var].values) if var in ds else np.nan
        if thickness is not None and thickness < FRONT_MIN_LAYERS * dx:
            x = np.nan
        out[key] = (x - L0) / L0
    return out


def convergence(isph=(), critical=(), da=(), x_norms=(0.2, 0.4, 0.6, 0.8)):
    isph = [load(r) for r in isph]
    da = [load(r) for r in da]
    panels = []
    if isph:
        panels += ["2d_runout", "2d_time"]
    if critical:
        panels += ["critical"]
    if da:
        panels += ["da_runout", "da_time"]
    if not panels:
        raise ConfigError("convergence: no input")
    ncols = min(3, len(panels))
    fig, axes = new_figure(-(-len(panels) // ncols), ncols, panel=(4.4, 3.4))
    ax_of = dict(zip(panels, axes.ravel()))
    dx_list = []
    if isph:
        rows = defaultdict(list)
        for ds in isph:
            dx = float(ds.attrs["dx"])
            dx_list.append(dx)
            rows[case_of(ds)].append(_front_row(ds))
        for j, (case, v) in enumerate(sorted(rows.items())):
            v = sorted(v, key=lambda r: -r["dx"])
            dxs = np.array([r["dx"] for r in v]) * 1e3
            for key, style, label in (("v99", "-o", "1 % volume front"), ("5mm", "--s", "attached front, 5 mm"),
                                      ("2d", ":^", "attached front, 2 d")):
                y = np.array([r[key] for r in v])
                if np.isfinite(y).any():
                    ax_of["2d_runout"].plot(dxs, y, style, color=f"C{j}", label=f"{case}, {label}")
            ax_of["2d_time"].plot(dxs, [r["t_rest"] for r in v], "-o", color=f"C{j}", label=case)
        for key, lab in (("2d_runout", "final runout ΔL/L0 (–)"), ("2d_time", "time to rest t_s/t_c (–)")):
            ax_of[key].set_xlabel("2D particle spacing dx (mm)")
            ax_of[key].set_ylabel(lab)
            ax_of[key].invert_xaxis()
    if critical:
        ax = ax_of["critical"]
        pts = []
        for k, path in enumerate(critical):
            df = load_table(path, ("x_norm", "t_s_critical"), "convergence critical.csv")
            dx = _dx_of_csv(path, df)
            if dx is None:
                if len(critical) != len(dx_list):
                    raise ConfigError(f"convergence: no dx for {path} (no 'dx' column, no dx<number> in the path, "
                                      "and not as many critical.csv files as 2D runs to pair them in order)")
                dx = dx_list[k]
            for xn in x_norms:
                d = np.abs(df["x_norm"].to_numpy(float) - xn)
                if d.size and d.min() <= 1e-3:
                    pts.append((xn, dx, float(df["t_s_critical"].iloc[int(np.argmin(d))])))
        for j, xn in enumerate(x_norms):
            v = np.array(sorted((p[1], p[2]) for p in pts if p[0] == xn))
            if v.size:
                ax.plot(v[:, 0] * 1e3, v[:, 1], "-o", color=f"C{j}", label=f"[x] = {xn:g}")
        ax.set_xlabel("2D particle spacing dx (mm)")
        ax.set_ylabel("critical time (t_s)_C (–)")
        ax.invert_xaxis()
    if da:
        rows = defaultdict(list)
        for ds in da:
            n = int(ds.sizes.get("particle", 0))
            var_ = "deposition" if int(ds.attrs.get("deposition", 1)) else "no deposition"
            rows[(case_of(ds), var_)].append((n, float(ds["final_runout_norm"].values), float(ds["flow_time"].values)))
        for j, ((case, var_), v) in enumerate(sorted(rows.items())):
            v = np.array(sorted(v))
            ls = "-" if var_ == "deposition" else "--"
            for key, col in (("da_runout", 1), ("da_time", 2)):
                ax_of[key].plot(v[:, 0], v[:, col], ls, marker="o", color=f"C{j // 2}", label=f"{case}, {var_}")
        ns = sorted({n for v in rows.values() for n, _, _ in v})
        for key, lab in (("da_runout", "DA final runout ΔL/L0 (–)"), ("da_time", "DA flow time t_F (s)")):
            ax_of[key].set_xscale("log")
            ax_of[key].set_xticks(ns, [str(n) for n in ns])
            ax_of[key].minorticks_off()
            ax_of[key].set_xlabel("DA particle count N")
            ax_of[key].set_ylabel(lab)
    for k, key in enumerate(panels):
        ax_of[key].grid(alpha=0.3)
        if key == "da_time" and "da_runout" in ax_of:
            continue  # one legend for both DA panels (next to them, not over the curves)
        if key == "da_runout" and "da_time" in ax_of:
            ax_of["da_time"].legend(*ax_of[key].get_legend_handles_labels(), fontsize=7, loc="upper left",
                                    bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
        else:
            ax_of[key].legend(fontsize=7)
    for k, key in enumerate(panels):
        panel_label(ax_of[key], k)
    hide_unused(axes, len(panels))
    note(fig, "Finer resolution to the right. 2D fronts (a): the 1 % volume front and the attached fronts at 5 mm and "
              "2 d, each drawn only where its thickness spans >= 2 particle layers; t_s: max speed < 0.1 m/s. "
              "DA fronts: depth >= the file's front_depth_threshold (docs/model.md, Shared definitions).")
    return fig


QUANTITIES = {"A": "A (–)", "B": "B (–)", "final_runout_norm": "DA final runout ΔL/L0 (–)",
              "flow_time": "DA flow time t_F (s)"}
# axis labels of the swept parameters (config keys of the `sensitivity:` section); others as named
PARAMETERS = {"phi_internal_deg": "internal friction angle φ_I (°)", "phi_basal_deg": "basal friction angle φ_B (°)",
              "critical_speed": "critical (deposition) speed (m/s)",
              "divergence_threshold": "F/D interface threshold ∇·r (–)",
              "free_surface_threshold": "ISPH free-surface threshold ∇·r (–)"}


def sensitivity(tables):
    df = pd.concat([load_table(t, ("parameter", "value"), "sensitivity CSV") for t in tables], ignore_index=True)
    qs = [q for q in QUANTITIES if q in df.columns]
    if not qs:
        raise ConfigError(f"sensitivity: the CSV needs at least one of {', '.join(QUANTITIES)}")
    params = list(dict.fromkeys(df["parameter"]))
    fig, axes = new_figure(len(params), len(qs), panel=(3.6, 2.8))
    for i, p in enumerate(params):
        g = df[df["parameter"] == p].sort_values("value")
        for j, q in enumerate(qs):
            ax = axes[i, j]
            ax.plot(g["value"], g[q], "-o", ms=4)
            if "baseline" in g:
                b = g[g["baseline"].astype(bool)]
                ax.plot(b["value"], b[q], "s", ms=8, mfc="none", mec="C3", label="paper value")
                ax.legend(fontsize=7)
            ax.set_xlabel(PARAMETERS.get(str(p), str(p)))
            ax.set_ylabel(QUANTITIES[q])
            # plain tick labels: a nearly flat response must read as such, not as an offset "+1.303e1"
            ax.ticklabel_format(axis="y", useOffset=False, style="plain")
            if ax.get_ylim()[1] - ax.get_ylim()[0] < 1e-3 * max(abs(g[q]).max(), 1e-300):
                lo, hi = float(g[q].min()), float(g[q].max())
                pad = max(0.01 * max(abs(lo), abs(hi)), 1e-12)
                ax.set_ylim(lo - pad, hi + pad)
            ax.grid(alpha=0.3)
    note(fig, "One parameter changed at a time from the paper's value.")
    return fig


def _argsC(p):
    add_inputs(p, "2D runs at several dx, their critical.csv, DA runs at several particle counts")


@register("convergence", "runout, flow time and critical times vs resolution / particle count", _argsC)
def _conv(args):
    k = classify(args.inputs, ("isph", "critical", "da"), "convergence")
    return convergence(k["isph"], k["critical"], k["da"])


def _argsS(p):
    add_inputs(p, "CSV(s) with columns parameter, value and A, B, final_runout_norm and/or flow_time")


@register("sensitivity", "A, B and DA runout vs each swept parameter", _argsS)
def _sens(args):
    paths = [Path(p) for p in args.inputs]
    for p in paths:
        if not p.exists():
            raise ConfigError(f"input: file {str(p)!r} does not exist")
    return sensitivity(paths)
