"""Benchmark of the 2D ISPH solver (not a test): ms per step and particle-steps/s for a
~4000-particle collapse (T22-A150 at dx = 4 mm: 3750 granular particles), with the PPE and the
implicit viscous step solved by SuperLU ("direct"), Jacobi-CG ("cg", numba, scipy's iterates bit
for bit, u/v in lock-step) and DIC-preconditioned CG ("cg_dic"), all warm-started; and the wall
time of T22-A70 at dx = 4 mm to rest (``--full``, solver ``--full-solver``).

Run: NUMBA_NUM_THREADS=1 .venv/bin/python benchmarks/bench_isph.py [--steps 100] [--solvers cg,cg_dic,direct]
     [--full [--full-solver cg_dic]]
Targets (one core): <= 8 ms/step at ~4000 particles; T22-A70 to rest <= 60 s.

Measured 2026-11-22 on the shared 2-core AMD EPYC under load (load average 1.5-4; minimum of
interleaved repeats, so the numbers are upper bounds), ms/step [neighbours, kernels, viscous, PPE]:
  before (scipy Jacobi-CG, two-pass neighbours): 19.2 [1.70, 1.41, 7.07, 8.98]; 157 PPE + 113 viscous CG its
  cg:     16.7 [1.17, 1.40, 4.85, 9.07]   (same iterations; PPE is matvec-bound like scipy's)
  cg_dic: 10.8 [0.70, 1.36, 3.66, 5.03]   (62 PPE + 56 viscous iterations)
  direct: 50.7 (before) - 82 (under heavier load)
Solver alone on one captured step (PPE 3603 unknowns, 74k nonzeros; viscous 3750, 77k): PPE scipy
8.40, numba cg 8.38, cg_dic 4.30 ms; viscous u+v scipy 5.84, cg (lock-step) 3.87, cg_dic 2.60 ms.
Neighbour list 1.43 -> 0.76 ms. T22-A70 dx = 4 mm to rest (fewer particles: scipy's per-call and
per-iteration Python overhead weighs more): before 23.9 s (repeats 27.5, 31.1; 2499 steps), cg 14.2 s
(repeats 14.3, 14.9; same 2499 steps, same front and rest time), cg_dic 12.0 s (2448 steps; a
different trajectory, see docs/model.md "Linear solvers").

A later performance pass, measured the same way (interleaved with the previous code, minimum of
3, --steps 400, load average 0.8-0.9): cg_dic 11.80 [1.07, 1.70, 3.52, 5.38] -> 6.78 ms/step
[1.00, 0.97, 2.28, 2.41]; CG iterations/step PPE 62 -> 31, viscous (u+v) 46 -> 26. From: modified
incomplete Cholesky (ic_modification 0.97: PPE 62 -> 30 iterations), triangles with unsigned,
row-sorted indices (Eisenstat product 57 -> 34 us), viscous warm start from the previous increment,
W and dW/dr evaluated once per pair and step (kernels ~1.5 -> ~1.0 ms), two numpy reductions moved to
numba (0.28 ms), cell-ordered candidates in the neighbour search, and a renumbering of the particles
in natural order every 10 steps (matters once the flow has mixed them: T22-A70). T22-A70 dx = 4 mm
to rest: 7.8 s (1644 steps, 4.70 ms/step) -> 5.9 s (1698 steps, 3.47 ms/step); rest time and front
13.62 t_c, 1.440 m -> 13.62 t_c, 1.504 m (area ratio 0.901 -> 0.902): within the round-off spread above.
"""
from __future__ import annotations

import argparse
import os
import time

from granudep.isph.api import run_isph, warmup
from granudep.isph.config import load_config
from granudep.isph.stepper import IsphSolver


def per_step(case: str, dx: float, steps: int, solver: str) -> dict:
    cfg = load_config(case, dx=dx, pressure_solver=solver, viscous_solver=solver)
    s = IsphSolver(cfg)
    for _ in range(5):  # start-up (column at rest, first collapse)
        dt = s.time_step()
        s.dt = dt
        s.step(dt)
    s.stats.__init__()
    t0 = time.perf_counter()
    for _ in range(steps):
        dt = s.time_step()
        s.dt = dt
        s.step(dt)
    wall = time.perf_counter() - t0
    st = s.stats
    n = st.steps
    return {"case": case, "solver": solver, "particles": s.nf, "ms_per_step": 1e3 * wall / n,
            "particle_steps_per_s": s.nf * n / wall, "neighbours_ms": 1e3 * st.t_neigh / n,
            "kernels_ms": 1e3 * st.t_kern / n, "viscous_ms": 1e3 * st.t_visc / n, "ppe_ms": 1e3 * st.t_ppe / n,
            "cg_iters_ppe": st.ppe_iters / n, "cg_iters_visc": st.visc_iters / n, "fallbacks": st.fallbacks}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--full", action="store_true", help="also run T22-A70 at dx = 4 mm to rest")
    ap.add_argument("--solvers", default="cg,cg_dic,direct", help="comma-separated solvers to time per step")
    ap.add_argument("--full-solver", default="cg_dic", help="solver (PPE and viscous) of the --full run")
    args = ap.parse_args()
    print(f"NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', '(unset)')}")
    t0 = time.perf_counter()
    warmup()
    print(f"warm-up (numba compile or cache load): {time.perf_counter() - t0:.1f} s")
    for solver in args.solvers.split(","):
        r = per_step("T22-A150", 0.004, args.steps if solver == "cg" else max(args.steps // 4, 10), solver)
        print(f"{r['case']} dx=4mm {r['particles']} particles, {solver:6s}: {r['ms_per_step']:7.2f} ms/step, "
              f"{r['particle_steps_per_s']:9.3g} particle-steps/s  [neighbours {r['neighbours_ms']:.2f}, "
              f"kernels {r['kernels_ms']:.2f}, viscous {r['viscous_ms']:.2f}, PPE {r['ppe_ms']:.2f} ms; "
              f"CG iterations/step: PPE {r['cg_iters_ppe']:.0f}, viscous (u+v) {r['cg_iters_visc']:.0f}; "
              f"direct fallbacks {r['fallbacks']}]")
    if args.full:
        t0 = time.perf_counter()
        ds = run_isph("T22-A70", dx=0.004, progress_every_s=30.0,
                      **{"numerics.pressure_solver": args.full_solver, "numerics.viscous_solver": args.full_solver})
        wall = time.perf_counter() - t0
        print(f"T22-A70 dx=4mm ({args.full_solver}): {ds.attrs['status']} at t={float(ds.time[-1]):.3f} s, time_to_rest="
              f"{float(ds.time_to_rest):.3f} s ({ds.attrs['time_to_rest_norm']:.2f} t_c), front "
              f"{float(ds.final_front_position):.3f} m, {ds.attrs['n_steps']} steps, wall {wall:.1f} s "
              f"({ds.attrs['ms_per_step']:.2f} ms/step)")


if __name__ == "__main__":
    main()
