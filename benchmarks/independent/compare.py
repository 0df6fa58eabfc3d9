"""Basilisk (granular.h) against granudep at 2 mm, no-slip bed.

    python benchmarks/independent/compare.py [--granudep-dir /work/scratch/indep_granudep]

Reads the stored Basilisk CSVs (docs/data/independent_basilisk*.csv, written by measures.py) and
granudep's run files (``T22-A70_noslip_dx0.002.nc``, ``flat_glass_a0.5_noslip_dx0.002.nc``,
``flat_glass_a1_noslip_dx0.002.nc`` in --granudep-dir; when a file is absent, the granudep
measures stored by an earlier call in docs/data/independent_granudep_2mm*.csv are used), and writes
docs/data/independent_vs_granudep.csv and docs/figures/independent_vs_granudep.png.
"""
from __future__ import annotations

import argparse
import datetime as dt
import sys
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from measures import DATA, FIXED_TIMES, L0, MEASURES, REPO, granudep_measures  # noqa: E402

GRANUDEP_FILES = {"T22-A70": "T22-A70_noslip_dx0.002.nc", "flat-glass-a0.5": "flat_glass_a0.5_noslip_dx0.002.nc",
                  "flat-glass-a1": "flat_glass_a1_noslip_dx0.002.nc"}
FRONTS = ("front_2mm", "front_5mm", "front_v99")
#: granudep diagnostic runs (T22-A70, no-slip, 4 mm): the bed stress of the first particle layer taken
#: at the bed's normal stress (wall.bed_stress: bed, the default) or at the particle centre (centre,
#: the earlier form; what a cell-centred viscosity at a no-slip bed does in Basilisk)
BEDSTRESS_FILES = {"bed": "T22-A70_noslip_bed_dx0.004.nc", "centre": "T22-A70_noslip_centre_dx0.004.nc",
                   "centre, 2 mm, to t = 1.25 s": "T22-A70_noslip_centre_dx0.002_t1.25.nc"}


def bedstress_table(gdir: Path) -> pd.DataFrame:
    """granudep's bed-stress diagnostic (4 mm): final rows to a CSV; returns the time series (stored too)."""
    rows, tss = [], []
    for bs, fn in BEDSTRESS_FILES.items():
        if (gdir / fn).exists():
            row, ts, _ = granudep_measures(gdir / fn)
            rows.append({"case": "T22-A70", "wall.bed_stress": bs, "file": fn, **row})
            tss.append(ts[["t_s", "front_2mm", "front_5mm", "front_v99", "moving_share"]].assign(bed_stress=bs))
    tpath = DATA / "independent_granudep_bedstress_time.csv"
    if not rows:
        return read_csv(tpath) if tpath.exists() else pd.DataFrame()
    if rows:
        date = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
        with open(DATA / "independent_granudep_bedstress.csv", "w") as fh:
            fh.write(f"# granudep T22-A70, no-slip bed, dx = 4 mm (and 2 mm to t = 1.25 s), wall.bed_stress bed vs centre (diagnostic of the "
                     f"Basilisk disagreement); measured {date} by benchmarks/independent/compare.py; m, s\n")
            pd.DataFrame(rows).to_csv(fh, index=False, float_format="%.6g")
        print(pd.DataFrame(rows)[["wall.bed_stress", "status", "t_final_s", "front_2mm", "front_5mm", "front_v99",
                                  "front_v99_t0.8", "front_v99_t1.2", "t_rest99"]].to_string(index=False))
        with open(tpath, "w") as fh:
            fh.write(f"# granudep T22-A70, no-slip, 4 mm (2 mm to 1.25 s), wall.bed_stress bed vs centre: fronts "
                     f"every 0.01 s; {date}\n")
            pd.concat(tss).to_csv(fh, index=False, float_format="%.5g")
        return pd.concat(tss)


def read_csv(path: Path) -> pd.DataFrame:
    return pd.read_csv(path, comment="#")


def granudep_tables(gdir: Path) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    rows, tss, profs = [], [], []
    for case, fn in GRANUDEP_FILES.items():
        nc = gdir / fn
        if not nc.exists():
            continue
        row, ts, (xc, d) = granudep_measures(nc)
        rows.append({"case": case, "file": fn, **row})
        tss.append(ts.assign(case=case))
        nz = d > 0
        profs.append(pd.DataFrame({"case": case, "dx_m": row["dx_m"], "x_m": xc[nz], "h_m": d[nz]}))
    stored = [DATA / f"independent_granudep_2mm{s}.csv" for s in ("", "_time", "_profiles")]
    old = [read_csv(p) if p.exists() else pd.DataFrame() for p in stored]
    new = [pd.DataFrame(rows), pd.concat(tss) if tss else pd.DataFrame(), pd.concat(profs) if profs else pd.DataFrame()]
    out = []
    for o, n in zip(old, new):   # fresh runs replace the stored rows of their case
        if not n.empty and not o.empty:
            o = o[~o["case"].isin(n["case"].unique())]
        out.append(pd.concat([o, n]) if not o.empty else n)
    date = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    if rows:
        for p, df in zip(stored, out):
            with open(p, "w") as fh:
                fh.write(f"# granudep 2D ISPH at dx = 2 mm, wall.slip no_slip (bed and back wall); measured {date} "
                         "by benchmarks/independent/compare.py with measures.py; lengths m, times s\n")
                df.to_csv(fh, index=False, float_format="%.6g")
    return tuple(out)


def comparison(bas: pd.DataFrame, gd: pd.DataFrame) -> pd.DataFrame:
    out = []
    bas = bas[(bas["status"] != "incomplete") & ~bas["run"].str.contains("pf_")]   # finished runs of granular.h as is
    for case, g in bas.groupby("case"):
        g = g.sort_values("dx_m")
        fin, sec = g.iloc[0], (g.iloc[1] if len(g) > 1 else None)
        gr = gd[gd["case"] == case]
        gv = gr.iloc[0] if len(gr) else None
        for m in MEASURES + tuple(f"front_v99_t{tt:g}" for tt in FIXED_TIMES):
            b = float(fin[m])
            if m.startswith("front_v99_t") and not b == b:
                continue   # the run was over before that time
            s = float(sec[m]) if sec is not None else float("nan")
            v = float(gv[m]) if gv is not None else float("nan")
            row = {"measure": m, "case": case, "basilisk_finest_dx_m": float(fin["dx_m"]), "basilisk_finest": b,
                   "basilisk_second_dx_m": float(sec["dx_m"]) if sec is not None else float("nan"),
                   "basilisk_second": s,
                   "basilisk_change_finest_pair": (b - s) / abs(s) if s == s and s != 0 else float("nan"),
                   "granudep_2mm": v,
                   "rel_diff_granudep_vs_basilisk": (v - b) / abs(b) if b == b and b != 0 else float("nan")}
            if m in FRONTS or m.startswith("front_v99_t"):   # the same, on the runout beyond the gate (x - L0)
                l0 = L0[case]
                row["rel_diff_runout_dL"] = (v - b) / abs(b - l0) if b - l0 != 0 else float("nan")
                row["basilisk_change_runout_dL"] = (b - s) / abs(s - l0) if s == s and s - l0 != 0 else float("nan")
            r = row["rel_diff_granudep_vs_basilisk"]
            row["within_10pct"] = "n/a" if not r == r else ("yes" if abs(r) <= 0.10 else "no")
            note = str(fin["status"])
            if float(fin["thickness_at_domain_end_m"]) > 0.0:
                note += f"; deposit reaches the domain end x = {float(fin['domain_length_m']):.2f} m"
            row["basilisk_finest_status"] = note
            out.append(row)
    return pd.DataFrame(out)


def figure(bas, bts, bpr, gd, gts, gpr, bst, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    cases = ["T22-A70", "flat-glass-a0.5", "flat-glass-a1"]
    done = set(bas.loc[bas["status"] != "incomplete", "run"])
    bpr = bpr[bpr["run"].isin(done)]
    bts = bts[bts["run"].isin(done)]
    fig, ax = plt.subplots(2, 3, figsize=(15, 7), constrained_layout=True)
    for j, case in enumerate(cases):
        a = ax[0, j]
        main = bpr[(bpr["case"] == case) & ~bpr["run"].str.contains("pf_")]
        dxs = sorted(main["dx_m"].unique(), reverse=True)
        for k, dxv in enumerate(dxs):
            p = main[main["dx_m"] == dxv]
            a.plot(p["x_m"], p["h_m"], lw=1.0 + 0.6 * k, color=plt.cm.Blues(0.4 + 0.6 * (k + 1) / len(dxs)),
                   label=f"Basilisk {dxv * 1e3:.3g} mm")
        pf = bpr[(bpr["case"] == case) & bpr["run"].str.contains("pf_")]
        for k, (run, p) in enumerate(pf.groupby("run")):
            a.plot(p["x_m"], p["h_m"], "--", color=f"C{4 + k}", lw=1.0,
                   label=f"Basilisk {run}: granudep's pressure floor (diagnostic)")
        if not gpr.empty and case in set(gpr["case"]):
            p = gpr[gpr["case"] == case]
            a.plot(p["x_m"], p["h_m"], color="C3", lw=1.6, label="granudep 2 mm")
        a.set_title(f"{case}: final deposit (no-slip bed)")
        if case == "T22-A70":
            a.set_ylim(0, 0.07)
        a.set_xlabel("x from the back wall (m)")
        a.set_ylabel("thickness (m)")
        a.legend(fontsize=8)
        a = ax[1, j]
        if dxs and case == "T22-A70":   # the 1 % volume front of every resolution (the box ends at 1.92 m)
            for k, dxv in enumerate(dxs):
                r = bts[(bts["case"] == case) & (bts["dx_m"] == dxv) & ~bts["run"].str.contains("pf_")]
                a.plot(r["t_s"], r["front_v99"], color=plt.cm.Blues(0.4 + 0.6 * (k + 1) / len(dxs)),
                       lw=1.0 + 0.5 * k, label=f"Basilisk {dxv * 1e3:.3g} mm front_v99")
            if not bst.empty:
                for k, bs in enumerate(bst["bed_stress"].unique()):
                    r = bst[bst["bed_stress"] == bs]
                    a.plot(r["t_s"], r["front_v99"], ("-.", "--", ":")[k % 3], color=f"C{1 + k}",
                           label=f"granudep wall.bed_stress {bs}{'' if 'mm' in bs else ', 4 mm'}, front_v99")
        elif dxs:
            fin = bts[(bts["case"] == case) & (bts["dx_m"] == dxs[-1]) & ~bts["run"].str.contains("pf_")]
            for m, ls in (("front_v99", "-"), ("front_5mm", "--"), ("front_2mm", ":")):
                a.plot(fin["t_s"], fin[m], ls, color="C0", label=f"Basilisk {dxs[-1] * 1e3:g} mm {m}")
        if not gts.empty and case in set(gts["case"]):
            g = gts[gts["case"] == case]
            for m, ls in ((("front_v99", "-"),) if case == "T22-A70" else
                          (("front_v99", "-"), ("front_5mm", "--"), ("front_2mm", ":"))):
                a.plot(g["t_s"], g[m], ls, color="C3", label=f"granudep 2 mm {m}")
        a.set_xlabel("t (s)")
        a.set_ylabel("front (m)")
        a.legend(fontsize=7)
    fig.savefig(path, dpi=110)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--granudep-dir", default="/work/scratch/indep_granudep", type=Path)
    a = ap.parse_args()
    bas = read_csv(DATA / "independent_basilisk.csv")
    bts = read_csv(DATA / "independent_basilisk_time.csv")
    bpr = read_csv(DATA / "independent_basilisk_profiles.csv")
    gd, gts, gpr = granudep_tables(a.granudep_dir)
    cmp_ = comparison(bas, gd)
    date = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    with open(DATA / "independent_vs_granudep.csv", "w") as fh:
        fh.write(f"# Basilisk+granular.h (finest and second-finest dx) vs granudep 2 mm, no-slip bed; fronts and depths "
                 f"in m from the back wall, t_rest99 in s; rel_diff = (granudep - basilisk)/|basilisk|; "
                 f"rel_diff_runout_dL on x - L0; written {date} by benchmarks/independent/compare.py\n")
        cmp_.to_csv(fh, index=False, float_format="%.5g")
    with pd.option_context("display.width", 250, "display.max_columns", 30):
        print(cmp_.to_string(index=False))
    bst = bedstress_table(a.granudep_dir)
    figure(bas, bts, bpr, gd, gts, gpr, bst, REPO / "docs" / "figures" / "independent_vs_granudep.png")


if __name__ == "__main__":
    main()
