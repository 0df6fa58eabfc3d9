"""How far does a change of linear solver move the runout? (Target: results identical within the
CG tolerance, runouts moved by <= 0.5 %)

    NUMBA_NUM_THREADS=1 python benchmarks/solver_runout_check.py --dx 0.004 --seeds 0,1,2,3 \\
        --variant ssor numerics.deflation_min_unknowns=1000000000 \\
        --variant deflated numerics.deflation_min_unknowns=0

Runs T22-A70 (``--case``) to rest at ``--dx`` for each variant (a name and config overrides) and each
seed (0: the unperturbed lattice; k > 0: the granular particles' initial positions moved by
0.01 dx, normal, seed k, as the time-step study (docs/model.md) did: round-off alone moves a single
run by 0.3-0.7 %, so a solver change is judged on the mean over seeds against the seed spread).
Prints one row per run (volume front v99, 2 d front, rest times, steps, largest energy excess,
solver fallbacks, PPE iterations per step, CPU seconds) and, per variant, the mean and its change
against the first variant; ``--csv`` writes the rows.
"""
from __future__ import annotations

import argparse
import csv
import time

import numpy as np

from granudep.cliutil import parse_sets


def one_run(case: str, dx: float, seed: int, overrides: dict) -> dict:
    from granudep.isph.config import load_config
    from granudep.isph.output import build_dataset
    from granudep.isph.stepper import IsphSolver
    from granudep.isph.run import run
    from granudep.progress import Progress
    cfg = load_config(case, dx=dx, progress_every_s=1e9, **overrides)
    s = IsphSolver(cfg)
    if seed:
        rng = np.random.default_rng(seed)
        nf = s.nf
        s.x[:nf] += 0.01 * dx * rng.standard_normal(nf)
        s.y[:nf] = np.maximum(s.y[:nf] + 0.01 * dx * rng.standard_normal(nf), 0.5 * dx)
    c0 = time.process_time()
    solver, snaps, status, ttr = run(cfg, progress=Progress(1e9), solver=s)
    cpu = time.process_time() - c0
    ds = build_dataset(cfg, solver, snaps, status, ttr)
    st = solver.stats
    return {"dx": dx, "seed": seed, "v99": float(ds.final_front_v99), "front_2d": float(ds.final_front_2d),
            "ts99_tc": ds.attrs["time_to_rest_mass99_norm"], "ts_tc": ds.attrs["time_to_rest_norm"],
            "steps": st.steps, "max_energy_excess": float(solver.energy.max_excess), "fallbacks": st.fallbacks,
            "ppe_its": st.ppe_iters / max(st.steps, 1), "cpu_s": cpu, "status": status}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", default="T22-A70")
    ap.add_argument("--dx", type=float, default=0.004)
    ap.add_argument("--seeds", default="0,1,2,3")
    ap.add_argument("--variant", nargs="+", action="append", required=True, metavar=("NAME", "KEY=VALUE"),
                    help="a name and its config overrides (repeat the option per variant)")
    ap.add_argument("--csv", default=None)
    args = ap.parse_args()
    from granudep.isph.heap import keep_freed_memory
    keep_freed_memory()
    seeds = [int(k) for k in args.seeds.split(",")]
    rows = []
    for seed in seeds:                        # variants interleaved per seed (the machine drifts)
        for name, *sets in args.variant:
            over = parse_sets(sets)       # the CLI's --set rule (YAML 1.2 numbers: 1e-10 is a float)
            row = {"variant": name, **one_run(args.case, args.dx, seed, over)}
            rows.append(row)
            print(" ".join(f"{k} {v:.4f}" if isinstance(v, float) else f"{k} {v}" for k, v in row.items()), flush=True)
    names = [v[0] for v in args.variant]
    keys = ("v99", "front_2d", "ts99_tc", "ts_tc", "steps", "ppe_its", "cpu_s")
    mean = {n: {k: float(np.mean([r[k] for r in rows if r["variant"] == n])) for k in keys} for n in names}
    spread = {n: {k: float(np.ptp([r[k] for r in rows if r["variant"] == n])) for k in keys} for n in names}
    print(f"\n{args.case} at dx = {args.dx * 1e3:g} mm, seeds {seeds}: mean (spread over seeds) "
          f"and change of the mean against {names[0]}")
    for n in names:
        print(f"  {n}: " + ", ".join(
            f"{k} {mean[n][k]:.4f} ({spread[n][k]:.4f}) {100 * (mean[n][k] / mean[names[0]][k] - 1):+.2f} %"
            for k in keys)
              + f"; max energy excess {max(r['max_energy_excess'] for r in rows if r['variant'] == n):.2e} E_ref, "
                f"fallbacks {sum(r['fallbacks'] for r in rows if r['variant'] == n)}")
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)


if __name__ == "__main__":
    main()
