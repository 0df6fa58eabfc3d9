"""Does Basilisk's T22-A70 layer touch the bed? A picture of the field dumps of ``column.c``.

For one Basilisk run (default ``T22_3.33``) and its dump times (0.4, 0.8, 1.2 s): the grain volume
fraction f of the lowest 12 cell rows along the slope (the bed is y = 0, the y axis is stretched),
and the volume fraction of the bed cell row beside the grain thickness Σ f Δ of each column. Where
the bed row is empty under a thick column, the flowing layer rides on a film of granular.h's passive
fluid (η_f = 0.49 Pa s, no friction) instead of shearing against the no-slip bed.

    python benchmarks/independent/bed_contact_figure.py [--runs DIR] [--run T22_3.33] [-o PNG]

Needs the run folder of ``run_basilisk.sh`` (default /work/scratch/basilisk/runs); the measures per
x band are ``docs/data/independent_basilisk_bed_contact.csv`` (``measures.py``).
"""
from __future__ import annotations

import argparse
import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

REPO = Path(__file__).resolve().parents[2]


def load_dump(path: Path, dx: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cell indices (i, j) and f of a ``NAME.field_t{t}`` dump (x y f u v p per cell with f > 0.01)."""
    F = np.loadtxt(path, ndmin=2)
    i = np.round(F[:, 0] / dx - 0.5).astype(int)
    j = np.round(F[:, 1] / dx - 0.5).astype(int)
    return i, j, F[:, 2]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", default="/work/scratch/basilisk/runs", type=Path)
    ap.add_argument("--run", default="T22_3.33")
    ap.add_argument("--rows", type=int, default=12, help="cell rows drawn above the bed")
    ap.add_argument("-o", "--output", default=REPO / "docs/figures/independent_bed_contact.png", type=Path)
    a = ap.parse_args()
    log = (a.runs / f"{a.run}.log").read_text()
    dx = float(re.search(r"# dx = ([0-9.eE+-]+) m", log).group(1))
    dumps = sorted(a.runs.glob(f"{a.run}.field_t*"), key=lambda p: float(p.name.split("_t")[-1]))
    if not dumps:
        raise SystemExit(f"no field dumps {a.run}.field_t* in {a.runs}")
    fig, axes = plt.subplots(len(dumps), 2, figsize=(13, 2.6 * len(dumps)), squeeze=False,
                             gridspec_kw={"width_ratios": [1.6, 1]})
    for row, p in zip(axes, dumps):
        t = float(p.name.split("_t")[-1])
        i, j, f = load_dump(p, dx)
        ncol = int(i.max()) + 1
        img = np.zeros((a.rows, ncol))
        keep = j < a.rows
        img[j[keep], i[keep]] = f[keep]
        ax = row[0]
        im = ax.imshow(img, origin="lower", aspect="auto", cmap="viridis", vmin=0, vmax=1,
                       extent=(0, ncol * dx, 0, a.rows * dx * 1e3))
        ax.set_ylabel("y above bed (mm)")
        ax.set_title(f"Basilisk {a.run.replace('_', ' ')} mm, t = {t:.1f} s: grain fraction f of the "
                     f"lowest {a.rows} cell rows", fontsize=9)
        fig.colorbar(im, ax=ax, pad=0.01, label="f")
        vol = np.zeros(ncol)
        np.add.at(vol, i, f * dx)
        fbed = np.zeros(ncol)
        fbed[i[j == 0]] = f[j == 0]
        xc = (np.arange(ncol) + 0.5) * dx
        occ = vol > 0.002
        ax2 = row[1]
        ax2.plot(xc, vol * 1e3, color="0.3", lw=1, label="thickness Σ f Δ (mm)")
        ax2.set_ylabel("thickness (mm)")
        ax3 = ax2.twinx()
        ax3.plot(xc[occ], fbed[occ], ".", ms=2.5, color="C3", label="bed cell f (columns > 2 mm)")
        ax3.set_ylim(-0.05, 1.05)
        ax3.set_ylabel("f of the bed cell", color="C3")
        off = occ & (fbed < 0.5)
        ax2.set_title(f"bed cell f < 0.5 under {off.sum() / max(occ.sum(), 1):.0%} of the columns "
                      f"holding grains ({vol[off].sum() / max(vol[occ].sum(), 1e-30):.0%} of the volume)",
                      fontsize=9)
        for ax_ in (ax, ax2):
            ax_.set_xlim(0, min(1.92, ncol * dx + 0.05))
    for ax_ in axes[-1]:
        ax_.set_xlabel("x down-slope (m)")
    fig.suptitle("T22-A70 with a no-slip bed in Basilisk + granular.h: the advancing layer leaves the bed "
                 "cell row (VOF contact line with no slip)", fontsize=10)
    fig.tight_layout()
    a.output.parent.mkdir(parents=True, exist_ok=True)
    tmp = a.output.with_suffix(".tmp.png")
    fig.savefig(tmp, dpi=110)
    tmp.replace(a.output)
    print(f"figure: {a.output}")


if __name__ == "__main__":
    main()
