"""Decelerating μ(I) layers below the static friction: how each code treats the bed of a sheet a few
particles (cells) thick, against a converged 1D reference.

    NUMBA_NUM_THREADS=1 python benchmarks/decelerating_layer.py [--heights 4 6 10 20] [--dx 2 1 0.5]
        [--bed-stress bed centre wall] [-o docs/data/decelerating_layer.csv]
        [--basilisk docs/data/decelerating_layer_basilisk.csv] [--figure docs/figures/decelerating_layer.png]
    python benchmarks/decelerating_layer.py --from-csv docs/data/decelerating_layer.csv   # re-plot

The problem: a uniform layer of glass beads (Table 2, the 2D solver's μ(I) law) h thick on a periodic
22° bed, no-slip, launched with Bagnold's profile shape at a mean speed of 1 m/s. tan 22° = 0.404 is
below μ_s = tan 25.5° = 0.477, so the layer decelerates and stops (the regime of the T22 deposits).
Reference: :func:`granudep.isph.layer_reference.uniform_layer` (1D finite volumes, 40 cells, converged
to 4 digits; the bed stress at the bed's normal stress and shear rate). granudep: the 2D ISPH solver
with ``wall.slip: no_slip`` and each ``wall.bed_stress``. Basilisk (optional, ``--basilisk``):
``benchmarks/independent/run_basilisk.sh`` with ``CASES="layers"`` (granular.h as is, and with the bed
face's viscosity at the bed's normal stress), read against the reference with granular.h's viscosity
floor ρ D sqrt(g D) = 0.129 Pa s (``LayerMaterial.eta_min``; it brakes 4–6 mm sheets, a model
difference) and, in a second row each, against the plain one.

Measures per run: the mean speed at 0.1, 0.2, 0.3, 0.5 s; the stop time (mean speed < 0.01 m/s,
0.05 s output resolution); ``max_err``: the largest |ū − ū_ref| over t ≤ 1 s (m/s, on a launch speed
of 1 m/s).
"""
from __future__ import annotations

import argparse
import math
import os
import time
from pathlib import Path

import numpy as np
import pandas as pd

THETA = 22.0
U0 = 1.0
T_END = 1.2
OUT = 0.05
TIMES = (0.1, 0.2, 0.3, 0.5)


def basilisk_eta_min() -> float:
    """granular.h's viscosity floor ρ D sqrt(g D) in Pa s, D = d sqrt(ρ_s/ρ) (its grain size in units
    ρ = g = 1, run_basilisk.sh's D_eff): 0.13 Pa s for the glass beads."""
    from granudep.isph.config import load_config
    m = load_config("T22-A70").material
    dd = m.d * math.sqrt(m.rho_s / m.rho)
    return m.rho * dd * math.sqrt(9.81 * dd)


def reference(h: float, eta_min: float = 0.0) -> pd.DataFrame:
    from granudep.isph.layer_reference import LayerMaterial, uniform_layer
    r = uniform_layer(h, THETA, U0, n_cells=40, t_end=T_END, dt=5e-4, out_every=OUT,
                      mat=LayerMaterial(eta_min=eta_min))
    return pd.DataFrame({"t": np.round(r.t, 4), "mean_speed": r.mean_speed}), r.t_stop


def granudep_layer(h: float, dx: float, bed_stress: str) -> pd.DataFrame:
    """The 2D solver's periodic layer (:func:`granudep.isph.verification.decelerating_layer_history`)."""
    from granudep.isph.verification import decelerating_layer_history
    t, m = decelerating_layer_history(h, dx, bed_stress, THETA, U0, T_END, OUT)
    return pd.DataFrame({"t": np.round(t, 4), "mean_speed": m})


def summarise(code: str, variant: str, h: float, dx: float, hist: pd.DataFrame, ref: pd.DataFrame,
              t_stop_ref: float, cpu: float, ref_name: str = "1D, no viscosity floor") -> dict:
    m = hist.set_index("t").mean_speed
    r = ref.set_index("t").mean_speed
    common = [t for t in r.index if t <= 1.0 + 1e-9 and t in m.index]
    below = hist[hist.mean_speed < 0.01]
    row = {"code": code, "variant": variant, "h_mm": h * 1e3, "dx_mm": dx * 1e3, "layers": h / dx,
           "t_stop": float(below.t.iloc[0]) if not below.empty else math.nan, "t_stop_ref": t_stop_ref,
           "max_err": float(np.max(np.abs(m[common].to_numpy() - r[common].to_numpy()))), "cpu_s": cpu,
           "reference": ref_name}
    for t in TIMES:
        row[f"u_t{t:g}"] = float(m.get(t, math.nan))
        row[f"ref_t{t:g}"] = float(r.get(t, math.nan))
    return row


def figure(df: pd.DataFrame, refs: dict, path: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.ticker  # noqa: F401
    import matplotlib.pyplot as plt

    hs = sorted(df.h_mm.unique())
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.2))
    ax = axes[0]
    own = (df.code != "Basilisk") | df.reference.astype(str).str.contains("granular.h's floor")
    for code_var, g in df[own].groupby(["code", "variant"], sort=False):
        for dxv, mk in zip(sorted(g.dx_mm.unique(), reverse=True), ("o", "s", "^", "v")):
            gg = g[g.dx_mm == dxv].sort_values("layers")
            lab = f"{code_var[0]} {code_var[1]} dx {dxv:g} mm" + (" (vs floor ref.)" if code_var[0] == "Basilisk" else "")
            ax.plot(gg.layers, gg.max_err, mk + ("--" if code_var[0] == "Basilisk" else "-"), label=lab, ms=4)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ticks = [2, 3, 4, 5, 6, 8, 10, 20, 40]
    ax.set_xticks(ticks)
    ax.set_xticklabels([str(t) for t in ticks])
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xlabel("layer thickness / dx (particles or cells across the layer)")
    ax.set_ylabel("max |ū − ū_ref| over t ≤ 1 s (m/s; launch 1 m/s)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=6, ncol=2)
    ax = axes[1]
    for k, h in enumerate(hs):
        if h in refs:
            rf = refs[h]
            ax.plot(rf.t, rf.mean_speed, "k-", lw=2 if k == 0 else 1)
            ms = rf.mean_speed.to_numpy()
            mid = int(np.argmin(np.abs(ms - 0.1 * (k + 1))))
            ax.annotate(f"h = {h:g} mm", (float(rf.t.iloc[mid]), float(ms[mid])), xytext=(8, 4),
                        textcoords="offset points", fontsize=7)
        if (h, "floor") in refs:
            rf = refs[(h, "floor")]
            ax.plot(rf.t, rf.mean_speed, "k--", lw=0.8, label="with granular.h's η floor" if k == 0 else None)
    if any(isinstance(k, tuple) for k in refs):
        ax.legend(fontsize=7)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("mean speed (m/s)")
    ax.set_title("1D reference (converged) for each thickness", fontsize=9)
    ax.grid(alpha=0.3)
    fig.suptitle(f"Uniform μ(I) layer decelerating on a {THETA:g}° no-slip bed (tan θ < μ_s): error of each bed "
                 "treatment against the 1D reference", fontsize=9)
    fig.tight_layout()
    tmp = f"{path}.tmp.png"
    fig.savefig(tmp, dpi=130)
    os.replace(tmp, path)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--heights", nargs="+", type=float, default=[4.0, 6.0, 10.0, 20.0], help="layer thickness, mm")
    ap.add_argument("--dx", nargs="+", type=float, default=[2.0, 1.0, 0.5], help="particle spacing, mm")
    ap.add_argument("--bed-stress", nargs="+", default=["bed", "centre", "wall"],
                    choices=["bed", "centre", "wall", "hydrostatic"])
    ap.add_argument("-o", "--output", default="docs/data/decelerating_layer.csv")
    ap.add_argument("--basilisk", default=None, help="CSV of Basilisk's layer runs (t, mean speed per run)")
    ap.add_argument("--figure", default="docs/figures/decelerating_layer.png")
    ap.add_argument("--from-csv", default=None)
    a = ap.parse_args(argv)
    for h in a.heights:
        if not 1.0 <= h <= 100.0:
            raise SystemExit(f"--heights: each thickness must be in [1, 100] mm (got {h:g})")
    for dx in a.dx:
        if not 0.25 <= dx <= 10.0:
            raise SystemExit(f"--dx: each spacing must be in [0.25, 10] mm (got {dx:g})")
    refs, rows = {}, []
    for h in a.heights:
        ref, ts_ref = reference(h * 1e-3)
        refs[h] = ref
        if a.from_csv:
            continue
        rows.append(summarise("reference", "1D FV 40 cells", h * 1e-3, h * 1e-3 / 40, ref, ref, ts_ref, 0.0))
        for dx in a.dx:
            if h / dx < 1.99:
                continue
            for bs in a.bed_stress:
                t0 = time.process_time()
                hist = granudep_layer(h * 1e-3, dx * 1e-3, bs)
                row = summarise("granudep", bs, h * 1e-3, dx * 1e-3, hist, ref, ts_ref, time.process_time() - t0)
                rows.append(row)
                print(f"h {h:g} mm dx {dx:g} mm {bs:7s}: ū(0.2) {row['u_t0.2']:.3f} (ref {row['ref_t0.2']:.3f}), "
                      f"stop {row['t_stop']:.2f} (ref {ts_ref:.2f}), max err {row['max_err']:.3f}", flush=True)
        if a.basilisk and Path(a.basilisk).exists():
            # Basilisk is read against the same 1D problem with granular.h's viscosity floor (a model
            # difference, not a discretisation one: it brakes sheets of 4-6 mm), and against the plain one
            emin = basilisk_eta_min()
            fname = f"1D with granular.h's floor eta >= {emin:.3f} Pa s"
            ref_f, ts_f = reference(h * 1e-3, emin)
            refs[(h, "floor")] = ref_f
            rows.append(summarise("reference", "1D FV 40 cells, Basilisk's floor", h * 1e-3, h * 1e-3 / 40, ref_f,
                                  ref_f, ts_f, 0.0, fname))
            bas = pd.read_csv(a.basilisk, comment="#")
            for (run, variant, hh, dxx), g in bas[np.isclose(bas.h_mm, h)].groupby(["run", "variant", "h_mm", "dx_mm"]):
                hist = pd.DataFrame({"t": np.round(g.t.to_numpy(), 4), "mean_speed": g.mean_speed.to_numpy()})
                rows.append(summarise("Basilisk", variant, h * 1e-3, dxx * 1e-3, hist, ref_f, ts_f, math.nan, fname))
                rows.append(summarise("Basilisk", variant, h * 1e-3, dxx * 1e-3, hist, ref, ts_ref, math.nan))
    if a.from_csv:
        df = pd.read_csv(a.from_csv)
        if (df.code == "Basilisk").any():
            for h in a.heights:
                refs[(h, "floor")] = reference(h * 1e-3, basilisk_eta_min())[0]
    else:
        df = pd.DataFrame(rows)
        Path(a.output).parent.mkdir(parents=True, exist_ok=True)
        tmp = f"{a.output}.tmp"
        df.to_csv(tmp, index=False, float_format="%.5g")
        os.replace(tmp, a.output)
    pd.set_option("display.width", 220)
    cols = ["code", "variant", "h_mm", "dx_mm", "layers", "u_t0.2", "ref_t0.2", "u_t0.3", "ref_t0.3", "t_stop",
            "t_stop_ref", "max_err"]
    print(df[cols].to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    if a.figure:
        Path(a.figure).parent.mkdir(parents=True, exist_ok=True)
        figure(df[df.code != "reference"], refs, a.figure)
        print(f"figure: {a.figure}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
