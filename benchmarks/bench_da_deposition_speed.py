"""Does deposition speed a DA flow up? Runout, maximum speed and flow time of 1D-A70 and
the example path (config/da/example_path.yaml) without deposition and with it under these
variants: the former behaviour (a particle's own deposit in its bed term, deposition on any slope), each
of the two changes alone (``deposition.own_deposit: exclude``, ``deposition.steep_bed:
no_deposit``), both (the default), and no deposit-as-bed term at all (eq 11 as printed).
Deposition runs use each config's own x∞ mode (self-consistent by default):

    NUMBA_NUM_THREADS=1 python benchmarks/bench_da_deposition_speed.py [--cases 1D-A70 example_path]
        [--n-particles N] [--csv OUT.csv]
"""
from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
CASES = {"1D-A70": "1D-A70", "example_path": str(ROOT / "config" / "da" / "example_path.yaml")}
VARIANTS = [("no deposition", False, {}),
            ("earlier defaults", True, {"own_deposit": "include", "steep_bed": "deposit"}),
            ("own deposit excluded only", True, {"own_deposit": "exclude", "steep_bed": "deposit"}),
            ("steep-bed rule only", True, {"own_deposit": "include", "steep_bed": "no_deposit"}),
            ("both (default)", True, {"own_deposit": "exclude", "steep_bed": "no_deposit"}),
            ("no deposit-as-bed term", True, {"deposit_as_bed": False, "steep_bed": "deposit"})]


def max_speed(ds) -> float:
    """Largest |u| of any particle at any output (the path runs also have the per-step envelope)."""
    if "max_speed" in ds:
        return float(ds.max_speed.max())
    return float(np.nanmax(np.abs(ds.u.values)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=list(CASES), choices=list(CASES))
    ap.add_argument("--n-particles", type=int, default=None)
    ap.add_argument("--csv", type=Path)
    args = ap.parse_args()
    from granudep.da.api import run_da
    from granudep.da.config import resolve
    rows = []
    for case in args.cases:
        print(f"\n{case}\n{'variant':<32} {'runout m':>9} {'max |u|':>8} {'flow t s':>9} {'dep. %':>7} "
              f"{'x_inf':>8} {'wall s':>7}", flush=True)
        for name, dep, keys in VARIANTS:
            over = {"n_particles": args.n_particles} if args.n_particles else {}
            base = resolve(CASES[case], **over)
            depsec = {"enabled": dep, **keys}
            t0 = time.perf_counter()
            ds = run_da(base, deposition=depsec, progress=False)
            wall = time.perf_counter() - t0
            vf = np.asarray(ds.flowing_volume)
            vd = np.asarray(ds.deposited_volume)
            r = {"case": case, "variant": name, "runout": float(ds.final_runout), "max_speed": max_speed(ds),
                 "flow_time": float(ds.flow_time), "deposited_pct": 100.0 * vd[-1] / (vf[0] + vd[0]),
                 "x_inf": float(ds.attrs.get("x_inf", float("nan"))), "wall_s": wall,
                 "n": int(ds.attrs.get("n_particles", base.numerics.n_particles))}
            rows.append(r)
            print(f"{name:<32} {r['runout']:>9.4f} {r['max_speed']:>8.3f} {r['flow_time']:>9.3f} "
                  f"{r['deposited_pct']:>7.1f} {r['x_inf']:>8.3f} {wall:>7.1f}", flush=True)
    if args.csv:
        args.csv.parent.mkdir(parents=True, exist_ok=True)
        with args.csv.open("w", newline="") as f:
            wr = csv.DictWriter(f, fieldnames=list(rows[0]))
            wr.writeheader()
            wr.writerows(rows)


if __name__ == "__main__":
    main()
