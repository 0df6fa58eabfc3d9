"""Measures of the Basilisk runs with granudep's own definitions.

    python benchmarks/independent/measures.py [--runs /work/scratch/basilisk/runs]

Reads each run's ``NAME.profile`` (t, then the VOF thickness sum_j f dx of every grid column) and
``NAME.stats`` (t, granular volume, share of it moving at >= 0.1 m/s, ...) written by column.c, and
writes

- ``docs/data/independent_basilisk.csv``: one row per run (final measures, cost, provenance);
- ``docs/data/independent_basilisk_time.csv``: the fronts and moving share every 0.02 s;
- ``docs/data/independent_basilisk_profiles.csv``: the final deposit thickness per column (h > 0).

The same functions measure granudep's runs (:func:`granudep_measures`), so both codes are measured by
the same Python code: fronts by :func:`granudep.front.front_from_profile` (2 mm, 5 mm, 2 d) and
:func:`granudep.front.volume_front` (1 %), the 99 %-of-mass rest time by
:func:`granudep.isph.analysis.time_to_rest_mass_share`, depths by linear interpolation of the cell
depths at x = 0.05 and 0.1 m.
"""
from __future__ import annotations

import argparse
import datetime as dt
import math
import re
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd

from granudep.front import front_from_profile, volume_front
from granudep.isph.analysis import time_to_rest_mass_share

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "docs" / "data"
D_GRAIN = 0.0007          # glass beads (Table 2), for the 2 d front
REST_SPEED, REST_DURATION = 0.1, 0.1
#: run name -> (case, dx); the cases of run_basilisk.sh
CASES = {"flat05": "flat-glass-a0.5", "flat1": "flat-glass-a1", "T22": "T22-A70",
         "T22pf": "T22-A70",   # T22pf_*: diagnostic runs with granudep's pressure floor (column.c, PFLOOR)
         "T22bed": "T22-A70"}  # T22bed_*: the bed face's viscosity at the bed's normal stress (BEDSTRESS)
L0 = {"flat-glass-a0.5": 0.1, "flat-glass-a1": 0.1, "T22-A70": 0.2}
#: the 1 % volume front is also read at these times (s): T22-A70 before any run reaches the box end
FIXED_TIMES = (0.4, 0.8, 1.2)
MEASURES = ("front_2mm", "front_5mm", "front_v99", "t_rest99", "depth_x0.05", "depth_x0.1")


def profile_measures(edges: np.ndarray, depth: np.ndarray) -> dict:
    """Fronts and depths of one depth profile (cells with ``edges``)."""
    centres = 0.5 * (edges[1:] + edges[:-1])
    return {"front_2mm": front_from_profile(edges, depth, 0.002),
            "front_5mm": front_from_profile(edges, depth, 0.005),
            "front_2d": front_from_profile(edges, depth, 2 * D_GRAIN),
            "front_v99": volume_front(edges, depth, 0.01),
            "depth_x0.05": float(np.interp(0.05, centres, depth)),
            "depth_x0.1": float(np.interp(0.1, centres, depth))}


def rest_time_from_share(t: np.ndarray, share: np.ndarray) -> float:
    """granudep's 99 %-of-mass rest rule applied to a moving-share series: a one-'particle' record
    that moves exactly when more than 1 % of the volume moves at >= 0.1 m/s, so that
    time_to_rest_mass_share's test (moving share > 1 - 0.99) is the same test on the Basilisk share."""
    u = (np.asarray(share) > 0.01).astype(float)[:, None]
    return time_to_rest_mass_share(np.asarray(t), u, np.zeros_like(u), 0.99, REST_SPEED, REST_DURATION)


def basilisk_run(runs: Path, name: str) -> tuple[dict, pd.DataFrame, pd.DataFrame]:
    prof = np.loadtxt(runs / f"{name}.profile", ndmin=2)
    stats = np.loadtxt(runs / f"{name}.stats", ndmin=2)
    t, h = prof[:, 0], prof[:, 1:]
    log = (runs / f"{name}.log").read_text()
    m = re.search(r"# dx = ([0-9.eE+-]+) m, (\d+) x (\d+) cells", log)
    dx, nxc, nyc = float(m.group(1)), int(m.group(2)), int(m.group(3))
    edges = np.arange(h.shape[1] + 1) * dx
    kind = name.split("_")[0]
    case = CASES[kind]
    rows = []
    for k in range(t.size):
        rows.append({"case": case, "dx_m": dx, "t_s": t[k], **profile_measures(edges, h[k]),
                     "moving_share": stats[k, 2] if k < stats.shape[0] else float("nan")})
    ts = pd.DataFrame(rows)
    final = profile_measures(edges, h[-1])
    status = ("at rest (every cell with f > 0.5 below 0.1 m/s for 0.1 s)" if "at rest since" in log
              else "t_end (30 t_c) reached" if "t_end" in log else "incomplete")
    cpu = float("nan")
    ct = runs / "cpu_times.txt"
    if ct.exists():
        for line in ct.read_text().splitlines():
            p = line.split()
            if p and p[0] == name and "cpu_user_s" in p:
                cpu = float(p[p.index("cpu_user_s") + 1])
    at = {f"front_v99_t{tt:g}": float(ts.loc[np.argmin(np.abs(t - tt)), "front_v99"]) if t[-1] >= tt - 1e-9
          else float("nan") for tt in FIXED_TIMES}
    variant = ("pressure floor (diagnostic)" if "pf_" in name else
               "bed face at the bed's normal stress (diagnostic)" if "bed_" in name else "granular.h as is")
    row = {"case": case, "run": name, "variant": variant,
           "dx_m": dx, "cells": f"{nxc}x{nyc}", "status": status,
           "t_final_s": float(t[-1]), **final, "t_rest99": rest_time_from_share(t, stats[:, 2]),
           "volume_change": float(stats[-1, 1] / stats[0, 1] - 1.0),
           "domain_length_m": float(edges[-1]),
           "thickness_at_domain_end_m": float(h[-1, -1]), **at, "cpu_user_s": cpu}
    nz = h[-1] > 0
    prof_df = pd.DataFrame({"case": case, "run": name, "dx_m": dx, "x_m": 0.5 * (edges[1:] + edges[:-1])[nz],
                            "h_m": h[-1][nz]})
    return row, ts, prof_df


def granudep_measures(nc: Path) -> tuple[dict, pd.DataFrame, tuple[np.ndarray, np.ndarray]]:
    """The same measures from a granudep run file: the depth profile of every snapshot by
    granudep's own binning (isph.profile.surface_profile: bed cells of width dx, max y + dx/2)."""
    from granudep.io import open_dataset
    from granudep.isph.profile import surface_profile
    ds = open_dataset(nc)
    dx = float(ds.attrs["dx"])
    x = ds["x"].transpose("time", "particle").values
    y = ds["y"].transpose("time", "particle").values
    t = np.asarray(ds["time"].values, dtype=float)
    length = float(np.nanmax(x[np.isfinite(x)])) + 4 * dx

    def prof(k):
        ok = np.isfinite(x[k]) & np.isfinite(y[k])
        return surface_profile(x[k][ok].astype(float), y[k][ok].astype(float), dx, length)

    rows = []
    for k in range(t.size):
        e, d = prof(k)
        rows.append({"t_s": t[k], **profile_measures(e, d), "moving_share": float(ds["moving_share"].values[k])})
    e, d = prof(t.size - 1)
    tsd = pd.DataFrame(rows)
    at = {f"front_v99_t{tt:g}": float(tsd.loc[np.argmin(np.abs(t - tt)), "front_v99"]) for tt in FIXED_TIMES}
    row = {"dx_m": dx, **at, "status": str(ds.attrs.get("status", "")), "t_final_s": float(t[-1]),
           **profile_measures(e, d), "t_rest99": float(ds["time_to_rest_mass99"].values),
           "particles": int(ds.sizes["particle"]), "commit": str(ds.attrs.get("granudep_commit", "")),
           "granudep_final_front_v99": float(ds["final_front_v99"]), "granudep_final_front_5mm": float(ds["final_front_5mm"])}
    return row, tsd, (0.5 * (e[1:] + e[:-1]), d)


def layer_runs(runs: Path) -> pd.DataFrame:
    """The decelerating-layer runs (layer.c: ``layer_h{h}_dx{dx}`` as is, ``layerbed_*`` with the bed
    face at the bed's normal stress): mean and basal speed every 0.01 s, for
    ``benchmarks/decelerating_layer.py --basilisk``."""
    out = []
    for p in sorted(runs.glob("layer*_h*_dx*.stats")):
        m = re.match(r"(layer|layerbed)_h([0-9.]+)_dx([0-9.]+)$", p.stem)
        if not m:
            continue
        st = np.loadtxt(p, comments="#", ndmin=2)
        if st.size == 0:
            continue
        out.append(pd.DataFrame({"run": p.stem, "variant": "granular.h as is" if m.group(1) == "layer" else
                                 "bed face at the bed's normal stress", "h_mm": float(m.group(2)),
                                 "dx_mm": float(m.group(3)), "t": st[:, 0], "mean_speed": st[:, 1],
                                 "base_speed": st[:, 2]}))
    return pd.concat(out, ignore_index=True) if out else pd.DataFrame()


#: x bands (m) of the bed-contact table
BANDS = ((0.0, 0.3), (0.3, 0.6), (0.6, 0.9), (0.9, 1.2), (1.2, 1.92))


def bed_contact(runs: Path) -> pd.DataFrame:
    """Does the granular layer touch the bed? From column.c's field dumps (``NAME.field_t{t}``: x, y,
    f, u, v, p of every cell with f > 0.01): per x band, the mean volume fraction f of the bed cell
    row under the columns holding grains (Σ f Δ > 2 mm), the share of those columns whose bed cell
    holds less than half grains, and the share of the grain volume above such a bed cell."""
    rows = []
    for p in sorted(runs.glob("*.field_t*")):
        name, tt = p.name.split(".field_t")
        log = runs / f"{name}.log"
        if not log.exists():
            continue
        dx = float(re.search(r"# dx = ([0-9.eE+-]+) m", log.read_text()).group(1))
        F = np.loadtxt(p, ndmin=2)
        if F.size == 0:
            continue
        i = np.round(F[:, 0] / dx - 0.5).astype(int)
        j = np.round(F[:, 1] / dx - 0.5).astype(int)
        ncol = int(i.max()) + 1
        vol = np.zeros(ncol)
        np.add.at(vol, i, F[:, 2] * dx)
        fbed = np.zeros(ncol)
        fbed[i[j == 0]] = F[j == 0, 2]
        xc = (np.arange(ncol) + 0.5) * dx
        occ = vol > 0.002
        for a, b in BANDS + ((0.0, 1.92),):
            sel = occ & (xc >= a) & (xc < b)
            if not sel.any():
                continue
            off = sel & (fbed < 0.5)
            rows.append({"run": name, "dx_m": dx, "t_s": float(tt), "x_from_m": a, "x_to_m": b,
                         "columns": int(sel.sum()), "mean_bed_cell_f": float(fbed[sel].mean()),
                         "share_columns_bed_f_below_0.5": float(off.sum() / sel.sum()),
                         "share_volume_over_empty_bed": float(vol[off].sum() / vol[sel].sum()),
                         "mean_thickness_m": float(vol[sel].mean())})
    return pd.DataFrame(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", default="/work/scratch/basilisk/runs", type=Path)
    ap.add_argument("--out", default=DATA, type=Path)
    a = ap.parse_args()
    prov = (a.runs / "provenance.txt").read_text()
    commit = re.search(r"mirror commit: (\w+)", prov)
    gsha = re.search(r"granular.h sha256: (\w+)", prov)
    try:
        ours = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True).stdout.strip()
    except OSError:
        ours = "unknown"
    date = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    rows, tss, profs = [], [], []
    for p in sorted(a.runs.glob("*.stats")):
        name = p.stem
        if not (a.runs / f"{name}.profile").exists() or name.split("_")[0] not in CASES:
            continue
        row, ts, pr = basilisk_run(a.runs, name)
        row.update(solver="Basilisk (qcc, multigrid) + sandbox/M1EMN granular.h, driver benchmarks/independent/column.c",
                   basilisk_mirror="comphy-lab/basilisk-C", basilisk_commit=commit.group(1) if commit else "user source",
                   granular_h_sha256=gsha.group(1) if gsha else "", granudep_commit=ours, date=date)
        rows.append(row)
        tss.append(ts.assign(run=name))
        profs.append(pr)
    a.out.mkdir(parents=True, exist_ok=True)
    head = ("# Basilisk + granular.h (P.-Y. Lagree) runs of granudep's cases with a no-slip bed and back wall "
            f"(independent check of the bed); written {date} by benchmarks/independent/measures.py; lengths m, times s\n")
    lay = layer_runs(a.runs)
    if not lay.empty:
        with open(a.out / "decelerating_layer_basilisk.csv", "w") as fh:
            fh.write(head.replace("runs of granudep's cases with a no-slip bed and back wall (independent check of the bed)",
                                  "decelerating layers (layer.c; benchmarks/decelerating_layer.py)"))
            lay.to_csv(fh, index=False, float_format="%.6g")
        print(f"decelerating layers: {lay.run.nunique()} runs -> {a.out / 'decelerating_layer_basilisk.csv'}")
    if not rows:
        # a layers-only folder (CASES="layers"): the column tables are left as they are
        if lay.empty:
            raise SystemExit(f"no runs in {a.runs}")
        return
    df = pd.DataFrame(rows).sort_values(["case", "dx_m"], ascending=[True, False])
    for c in ("front_2mm", "front_5mm", "front_v99", "front_2d"):
        df[f"{c}_dL_over_L0"] = [(v - L0[cs]) / L0[cs] for v, cs in zip(df[c], df["case"])]
    with open(a.out / "independent_basilisk.csv", "w") as fh:
        fh.write(head)
        df.to_csv(fh, index=False, float_format="%.6g")
    with open(a.out / "independent_basilisk_time.csv", "w") as fh:
        fh.write(head)
        pd.concat(tss).to_csv(fh, index=False, float_format="%.5g")
    with open(a.out / "independent_basilisk_profiles.csv", "w") as fh:
        fh.write(head.replace("runs", "final deposit thickness (VOF sum f dx per column)"))
        pd.concat(profs).to_csv(fh, index=False, float_format="%.5g")
    bc = bed_contact(a.runs)
    if not bc.empty:
        with open(a.out / "independent_basilisk_bed_contact.csv", "w") as fh:
            fh.write(head.replace("runs of granudep's cases", "bed contact of the T22-A70 runs (field dumps)"))
            bc.to_csv(fh, index=False, float_format="%.4g")
        whole = bc[(bc.x_from_m == 0.0) & (bc.x_to_m == 1.92)]
        print(whole[["run", "t_s", "columns", "mean_bed_cell_f", "share_columns_bed_f_below_0.5",
                     "share_volume_over_empty_bed"]].to_string(index=False))
    cols = ["run", "dx_m", "status", "t_final_s", "front_2mm", "front_5mm", "front_v99", "t_rest99",
            "depth_x0.05", "depth_x0.1", "volume_change", "cpu_user_s"]
    with pd.option_context("display.width", 250, "display.max_columns", 30):
        print(df[cols].to_string(index=False))


if __name__ == "__main__":
    main()
