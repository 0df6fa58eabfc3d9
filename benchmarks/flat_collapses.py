"""The θ = 0 column collapses (glass beads and quartz sand, L0 = 0.1 m, a = 0.5 and 1) on
a resolution ladder, with the robust front measures, their change between the two finest
resolutions and, from the three finest, the observed order and the Richardson value.

    NUMBA_NUM_THREADS=1 python benchmarks/flat_collapses.py [--dx 2 1 0.7] [--cases glass_beads:0.5 ...]
        [-j 2] [-o results/convergence/flat_collapses.csv] [--figure flats.png]
    python benchmarks/flat_collapses.py --from-csv runs.csv [runs2.csv ...] --figure flats.png

Each case is :func:`granudep.isph.verification.flat_collapse_config` (Coulomb bed with the
material's own friction angle, default scheme, run to rest). Measures (``ΔL/L0 = (x − L0)/L0``):
the 1 % volume front (``v99``), the attached front at a 2 d and at a 5 mm thickness, the highest
particle at rest H/L0, the time to rest t_s/t_c and the largest energy excess over E_0 (share of
E_ref). Cost on one core: glass a = 0.5 at 2 / 1 / 0.7 / 0.5 mm 28 s / 34 s / 1.9 min /
~8 min; the a = 1 columns twice the particles.
"""
from __future__ import annotations

import argparse
import os
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pandas as pd

MEASURES = ("front_v99", "front_2d", "front_5mm", "H_over_L0", "t_rest_norm")
DEFAULT_CASES = ("glass_beads:0.5", "glass_beads:1", "quartz_sand:0.5", "quartz_sand:1")


def run_one(material: str, aspect: float, dx: float) -> dict:
    import numpy as np

    from granudep.isph.api import run_isph
    from granudep.isph.verification import flat_collapse_config
    t0 = time.perf_counter()
    cfg = flat_collapse_config(material, aspect, dx, **{"energy_limit": 10.0})
    ds = run_isph(cfg, progress=False)
    l0 = float(ds.attrs["L0"])
    row = {"material": material, "aspect": aspect, "dx_mm": dx * 1e3, "status": ds.attrs["status"],
           "particles": int(ds.sizes["particle"]), "t_rest_norm": float(ds.attrs["time_to_rest_norm"]),
           "max_energy_excess": float(ds.attrs["energy_max_excess"]), "wall_s": time.perf_counter() - t0}
    for k in ("front_2d", "front_5mm", "front_v99"):
        row[k] = (float(ds[f"final_{k}"]) - l0) / l0
    row["H_over_L0"] = float(np.nanmax(ds["y"].isel(time=-1).values)) / l0
    print(f"  {material} a={aspect:g} dx={dx * 1e3:g} mm: v99 {row['front_v99']:.4f}, 2d {row['front_2d']:.3f}, "
          f"5 mm {row['front_5mm']:.3f}, H/L0 {row['H_over_L0']:.4f}, t_s {row['t_rest_norm']:.2f} t_c, "
          f"{row['particles']} particles, {row['wall_s']:.0f} s ({row['status']})", flush=True)
    return row


def summarise(df: pd.DataFrame) -> pd.DataFrame:
    """Per case and measure: the value at each dx, the change between the two finest, the observed
    order and the Richardson value from the three finest (:func:`granudep.richardson.observed_order`)."""
    from granudep.richardson import observed_order
    out = []
    for (mat, a), g in df.groupby(["material", "aspect"], sort=False):
        g = g.sort_values("dx_mm")
        for m in MEASURES:
            f, h = g[m].to_numpy(), g["dx_mm"].to_numpy()
            row = {"material": mat, "aspect": a, "measure": m,
                   **{f"dx{d:g}mm": v for d, v in zip(h, f)}}
            if len(f) >= 2:
                row["finest_pair_change"] = (f[0] - f[1]) / abs(f[1]) if f[1] != 0 else float("nan")
            o = observed_order(h, f)
            row.update(order=o["order"], richardson=o["extrapolated"], converging=o["converging"], why=o["reason"])
            out.append(row)
    return pd.DataFrame(out)


def figure(df: pd.DataFrame, path: str) -> None:
    """Each front measure and H/L0 against dx, one line per case (markers only where run)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    labels = {"front_v99": "1 % volume front", "front_2d": "attached front, 2 d", "front_5mm": "attached front, 5 mm",
              "H_over_L0": "highest particle H/L0"}
    from matplotlib.ticker import FixedLocator, NullLocator, ScalarFormatter

    from granudep.cases import material as table2_material
    fig, axes = plt.subplots(1, 4, figsize=(15, 3.6), constrained_layout=True)
    ticks = sorted(df["dx_mm"].unique())
    for ax, m in zip(axes, labels):
        for (mat, a), g in df.groupby(["material", "aspect"], sort=False):
            g = g.sort_values("dx_mm")
            y = g[m].to_numpy(dtype=float).copy()
            # a thickness threshold under two particle layers measures a sheet of one particle: not drawn
            thick = {"front_2d": 2e3 * table2_material(mat)["d"], "front_5mm": 5.0}.get(m)
            if thick is not None:
                y[thick < 2.0 * g["dx_mm"].to_numpy()] = np.nan
            ax.plot(g["dx_mm"], y, "o-", label=f"{mat.replace('_', ' ')}, a = {a:g}")
        ax.set_xscale("log")
        ax.xaxis.set_major_locator(FixedLocator(ticks))
        ax.xaxis.set_minor_locator(NullLocator())
        ax.xaxis.set_major_formatter(ScalarFormatter())
        ax.set_xlabel("Δx (mm)")
        ax.set_title(labels[m], fontsize=10)
        ax.set_ylabel("H/L0" if m == "H_over_L0" else "ΔL/L0")
        ax.invert_xaxis()
    axes[0].legend(fontsize=8)
    fig.suptitle("θ = 0 column collapses (L0 = 0.1 m) at rest against resolution; attached fronts drawn only "
                 "where their thickness is at least two particle layers (2 d: glass 1.4 mm, quartz 3 mm)",
                 fontsize=10)
    fig.savefig(path, dpi=120)
    print(f"figure: {path}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", type=float, nargs="+", default=[2.0, 1.0, 0.7], help="spacings in mm")
    ap.add_argument("--cases", nargs="+", default=list(DEFAULT_CASES), help="MATERIAL:ASPECT")
    ap.add_argument("-j", "--jobs", type=int, default=1)
    ap.add_argument("-o", "--output", default=None, help="CSV of every run (the summary goes beside it)")
    ap.add_argument("--from-csv", nargs="+", default=None, help="summarise (and plot) earlier runs instead")
    ap.add_argument("--figure", default=None, help="PNG of the measures against dx")
    a = ap.parse_args(argv)
    if a.from_csv:
        df = pd.concat([pd.read_csv(f) for f in a.from_csv], ignore_index=True)
        df = df.drop_duplicates(["material", "aspect", "dx_mm"], keep="last")
    else:
        os.environ.setdefault("NUMBA_NUM_THREADS", "1")
        jobs = [(c.split(":")[0], float(c.split(":")[1]), d * 1e-3) for c in a.cases for d in a.dx]
        with ProcessPoolExecutor(max_workers=max(1, a.jobs)) as ex:
            rows = list(ex.map(run_one, *zip(*jobs)))
        df = pd.DataFrame(rows)
    summ = summarise(df)
    with pd.option_context("display.width", 200, "display.max_columns", 30, "display.float_format", "{:.4g}".format):
        print(summ.drop(columns=["why"]).to_string(index=False))
    for r in summ.itertuples():
        if r.why:
            print(f"  {r.material} a={r.aspect:g} {r.measure}: {r.why}")
    if a.output:
        df.to_csv(a.output, index=False)
        summ.to_csv(a.output.replace(".csv", "_summary.csv"), index=False)
    if a.figure:
        figure(df, a.figure)


if __name__ == "__main__":
    main()
