"""The studies' sections of the summary: convergence (2D spacings, DA particle counts) and sensitivity."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from .markdown import md_table, not_available, open_lazily, read_csv
from .reference_2d import reference_row


def _study_rows_isph(folder: Path, dx=None) -> pd.DataFrame:
    """One row per 2D run in ``folder``; with ``dx`` (m) only the runs at those resolutions (the
    configured list: a run left over from an earlier list is not a convergence result)."""
    rows = []
    for f in sorted(folder.glob("*.nc")):
        with open_lazily(f) as ds:
            if not _selected(float(ds.attrs.get("dx", math.nan)), dx):
                continue
            status = str(ds.attrs.get("status", ""))
            row = {"run": f.stem, "dx_mm": 1e3 * float(ds.attrs.get("dx", math.nan)), "status": status,
                   "time_to_rest": float(ds["time_to_rest"].values) if "time_to_rest" in ds else math.nan,
                   "n_outflow": int(ds.attrs.get("n_outflow", 0))}
            if not status.lower().startswith("failed"):
                r = reference_row(ds)
                row.update(final_runout_norm=r["final_runout_norm"], flow_time=r["flow_time"],
                           flow_time_norm=r["flow_time_norm"])
                l0 = float(ds.attrs.get("L0", math.nan))
                for k in ("front_5mm", "front_v99", "front_tail"):     # robust fronts
                    if f"final_{k}" in ds:
                        row[f"runout_{k}"] = (float(ds[f"final_{k}"].values) - l0) / l0
                row["energy_max_excess"] = float(ds.attrs.get("energy_max_excess", math.nan))
        rows.append(row)
    return pd.DataFrame(rows)


def _selected(value: float, wanted) -> bool:
    """True without a selection, else when ``value`` is one of ``wanted`` (to 1e-9 relative)."""
    if wanted is None:
        return True
    return any(math.isclose(value, float(w), rel_tol=1e-9) for w in wanted)


def _drift(values: pd.Series) -> str:
    """Change between the two finest resolutions (last two rows), relative to the finest."""
    v = pd.to_numeric(values, errors="coerce").to_numpy(float)
    if v.size < 2 or not np.all(np.isfinite(v[-2:])) or v[-1] == 0:
        return "–"
    return f"{100 * (v[-1] - v[-2]) / abs(v[-1]):+.1f} %"


def section_convergence(folder, dx=None, n_particles=None) -> str:
    """Convergence target (``results/convergence``): 2D runout, flow time, critical times vs dx; DA vs N.
    ``dx`` (m) and ``n_particles`` restrict the tables to the configured runs (default: every file)."""
    out = ["## Convergence (beyond the paper)\n"]
    root = Path(folder) if folder is not None else None
    if root is None or not (root / "isph").is_dir():
        return "\n".join(out) + not_available("convergence runs (`snakemake -j2 convergence`)", root)
    iso = _study_rows_isph(root / "isph", dx)
    if not iso.empty:
        iso = iso.sort_values("dx_mm", ascending=False)
        out.append(f"2D ISPH runs in `{root / 'isph'}` (finer to the bottom). Flow time: the front moves < 1 mm "
                   "afterwards; time to rest: every particle slower than 0.1 m/s for 0.1 s; outflow: particles "
                   "that left through the downstream end of the bed.\n")
        cols = {"run": ("run", ""), "dx_mm": ("dx (mm)", ".1f"), "final_runout_norm": ("ΔL/L0 (2 d front)", ".3f")}
        for k, lab in (("runout_front_5mm", "ΔL/L0 (5 mm front)"), ("runout_front_v99", "ΔL/L0 (1 % volume)"),
                       ("runout_front_tail", "ΔL/L0 (thin tail)")):
            if k in iso:
                cols[k] = (lab, ".3f")
        out.append(md_table(iso, {**cols, "flow_time": ("t_F (s)", ".3f"),
                                  "flow_time_norm": ("t_F/t_c", ".2f"), "time_to_rest": ("time to rest (s)", ".3f"),
                                  "n_outflow": ("outflow particles", ""),
                                  "energy_max_excess": ("max energy rise / E_ref", ".4f"), "status": ("status", "")}))
        empty = pd.Series(dtype=float)
        out.append(f"\nChange between the two finest dx: runout {_drift(iso.get('final_runout_norm', empty))}, "
                   f"flow time {_drift(iso.get('flow_time', empty))}.\n")
        from ..richardson import observed_order
        for k, lab in (("final_runout_norm", "2 d front"), ("runout_front_v99", "1 % volume front")):
            if k in iso and iso[k].notna().sum() >= 3:
                r = observed_order(iso["dx_mm"], iso[k])
                txt = (f"observed order {r['order']:.2f}, Richardson estimate {r['extrapolated']:.2f}"
                       if r["converging"] else "no observed order")
                out.append(f"Runout ({lab}), three finest dx: {txt}{'; ' + r['reason'] if r['reason'] else ''}.\n")
    crit = []
    files = sorted((root / "regression").glob("*/critical.csv")) if (root / "regression").is_dir() else []
    for f in files:
        df = pd.read_csv(f)
        if {"x_norm", "t_s_critical", "dx"} <= set(df.columns) and len(df) and _selected(float(df["dx"].iloc[0]), dx):
            for xn in (0.2, 0.4, 0.6, 0.8):
                sel = df[np.isclose(df["x_norm"], xn, atol=1e-6)]
                if len(sel):
                    crit.append({"dx_mm": 1e3 * float(sel["dx"].iloc[0]), "x_norm": xn,
                                 "t_s_critical": float(sel["t_s_critical"].iloc[0])})
    if crit:
        ct = pd.DataFrame(crit).pivot(index="dx_mm", columns="x_norm", values="t_s_critical")
        ct = ct.sort_index(ascending=False).reset_index()
        ct.columns = ["dx_mm"] + [f"x{c:g}" for c in ct.columns[1:]]
        out.append("Critical times (t_s)_C (onset of deposition) at [x] = 0.2 … 0.8:\n")
        cols = {"dx_mm": ("dx (mm)", ".1f")}
        cols.update({c: (f"[x] = {c[1:]}", ".2f") for c in ct.columns[1:]})
        out.append(md_table(ct, cols))
        out.append("")
    rows = []
    for f in sorted((root / "da").glob("*.nc")) if (root / "da").is_dir() else []:
        with open_lazily(f) as ds:
            if not _selected(float(ds.sizes.get("particle", 0)), n_particles):
                continue
            rows.append({"case": str(ds.attrs.get("case", f.stem.split("_n")[0])),
                         "variant": "deposition" if int(ds.attrs.get("deposition", 1)) else "no deposition",
                         "n": int(ds.sizes.get("particle", 0)),
                         "final_runout_norm": float(ds["final_runout_norm"].values),
                         "flow_time": float(ds["flow_time"].values)})
    if rows:
        da = pd.DataFrame(rows)
        ns = sorted(da["n"].unique())
        tab = da[["case", "variant"]].drop_duplicates().sort_values(["case", "variant"]).reset_index(drop=True)
        cols = {"case": ("case", ""), "variant": ("variant", "")}
        for q, head in (("final_runout_norm", "ΔL/L0"), ("flow_time", "t_F (s)")):
            for n in ns:
                sel = da[da["n"] == n].set_index(["case", "variant"])[q]
                tab[f"{q}{n}"] = [sel.get((c, v), math.nan) for c, v in zip(tab["case"], tab["variant"])]
                cols[f"{q}{n}"] = (f"{head} N={n}", ".3f")
        if len(ns) >= 2:
            a, b = ns[-2], ns[-1]
            tab["change"] = 100 * (tab[f"final_runout_norm{b}"] - tab[f"final_runout_norm{a}"]) / tab[
                f"final_runout_norm{b}"].abs()
            cols["change"] = (f"runout change N={a}→{b} %", "+.1f")
        out.append(f"DA runs in `{root / 'da'}`: final runout ΔL/L0 and flow time t_F per particle count N.\n")
        out.append(md_table(tab, cols))
        out.append("")
    return "\n".join(out)


def section_sensitivity(table) -> str:
    """Sensitivity target (``results/sensitivity/sensitivity.csv``): A, B and the DA runout per swept value."""
    out = ["## Sensitivity (beyond the paper)\n"]
    df = read_csv(table)
    if df is None:
        return "\n".join(out) + not_available("sensitivity table (`snakemake -j2 sensitivity`)", table)
    out.append(f"Source: `{table}`. One parameter at a time away from the paper's value; changes relative to "
               "the run at the paper's value.\n")
    df = df.copy()
    if "baseline" in df:
        df["baseline"] = df["baseline"].astype(bool)
        for q in ("A", "B", "final_runout_norm", "flow_time"):
            if q not in df:
                continue
            ref = {p: float(g[q].iloc[0]) for p, g in df[df["baseline"]].groupby("parameter")}
            df[f"{q}_change"] = [100 * (v - ref[p]) / abs(ref[p]) if ref.get(p) else math.nan
                                 for p, v in zip(df["parameter"], df[q])]
    out.append(md_table(df, {"parameter": ("parameter", ""), "value": ("value", ".4g"),
                             "baseline": ("paper value", ""), "A": ("A", ".4f"), "A_change": ("ΔA %", "+.0f"),
                             "B": ("B", ".4f"), "B_change": ("ΔB %", "+.0f"),
                             "final_runout_norm": ("DA ΔL/L0", ".3f"),
                             "final_runout_norm_change": ("Δ runout %", "+.1f"),
                             "flow_time": ("DA t_F (s)", ".3f"), "flow_time_change": ("Δ t_F %", "+.1f")}))
    out.append("")
    return "\n".join(out)
