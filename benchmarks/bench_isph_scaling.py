"""Scaling benchmark of the 2D ISPH solver (not a test): ms/step, particle-steps/s and the
breakdown (neighbours, kernels, viscous, PPE) with the CG/AMG iterations at 3750, 15 000 and 60 000
particles (T22-A150 at dx = 4, 2, 1 mm), from a developed flow
(a checkpoint after ``--t-flow`` s of collapse at 4 mm, refined to 2 and 1 mm and relaxed for 50
steps, see :func:`refine`; built once and cached under results/bench_cache/);
the fitted exponent of cost/step vs N; the peak RSS; optionally T22-A70 to rest (``--to-rest``).

Each variant also prints the parts of its step (PPE assembly, PPE CG, viscous assembly,
viscous CG, the rest) and the speed targets (printed, never asserted): <= 10 ms/step at 3750
particles on one thread, and T22-A70 at 1 mm to rest <= 20 min estimated from ms/step at 28 000
particles (power law between the measured N) x 6109 steps (the no-slip bed's run to rest). A variant is a
numerics.pressure_solver value, optionally /numerics.ppe_operator (cg_dic/matrix_free), or
cg_dic/deflated and cg_dic/undeflated: the SSOR-CG with and without the aggregation coarse space at
any N (numerics.deflation_min_unknowns 0 / never; the default deflates from 12 000 unknowns on).

Run (one command per figure set):
  NUMBA_NUM_THREADS=1 python benchmarks/bench_isph_scaling.py [--dx 4,2,1] [--steps 50] [--solvers cg_two_level,cg_dic]
  python benchmarks/bench_isph_scaling.py --threads 1,2 --solvers cg_two_level,cg_dic   (the figures of docs/performance.md)
      [--set numerics.projection=approximate]   (scheme options of the timed steps; default: adjoint pair)
  NUMBA_NUM_THREADS=2 python benchmarks/bench_isph_scaling.py ...
  python benchmarks/bench_isph_scaling.py --threads 1,2      (one subprocess per thread count, interleaved;
      two threads: numerics.threads_mode auto = the PPE geometry beside the predictor;
      --set numerics.threads_mode=prange for the kernels' parallel builds instead)
  NUMBA_NUM_THREADS=2 python benchmarks/bench_isph_scaling.py --to-rest 2,1   (T22-A70 to rest, wall time)
      [--set numerics.deflation_min_unknowns=1000000000000]   (scheme options also apply to --to-rest)
Timings on a shared machine are noisy: ``--repeats`` runs the same steps again from the
checkpoint (interleaved over the solvers) and the median is printed, with the process CPU time.

Measured 2026-12-01 on the shared 2-core machine at load average 4.5-6.5 (four agents;
``--threads 1,2,1,2 --repeats 1 --steps 20``, the two runs of each thread count shown), ms/step
[neighbours, kernels, viscous, PPE], cg_dic, 30.9-36 PPE and 18-29 viscous iterations per step:
  1 thread:  N = 3750: 47.8 / 24.1 [6.6, 11.1, 12.3, 17.5]; 15000: 161 / 135; 60000: 483 / 596
             [67.7, 60.6, 158.5, 195.0]; cost/step ~ N^0.83 / N^1.16 (wall), N^1.00 / N^1.08 (CPU)
  2 threads: N = 3750: 24.4 / 45.1; 15000: 114 / 153; 60000: 634 / 815; N^1.18 / N^1.04 (wall),
             N^0.98 / N^1.06 (CPU)
  peak RSS (all three states in one process, 60 000 particles the largest) 360-370 MB.
Again at load average 2.7-4.7 (``--threads 1,2,1,2,1,2``), medians of the three runs of each:
  1 thread:  3750: 23.8 ms/step (1.57e5 particle-steps/s) [3.1, 4.4, 7.4, 7.4 in the fastest run];
             15000: 91.7; 60000: 481 (fastest 350 [43.4, 42.3, 121.8, 141.8], 1.71e5 particle-steps/s);
             cost/step ~ N^0.99 / N^1.08 / N^0.99 (wall), N^0.98-1.00 (CPU)
  2 threads: 3750: 24.2; 15000: 100.4; 60000: 368; N^0.92-0.99 (wall)
The 2-thread runs used as much CPU time as wall time (e.g. 365 CPU ms in a 367 ms step): the second
core was taken by other jobs. Control: a trivially parallel numba prange loop gave 0.53-0.76 s on
one and 0.60-0.65 s on two threads at the same load. So the spread between repeats (2x at 4 mm)
is the machine's load, not the code, and no 2-thread speed-up could be resolved under it. The same code
could not be measured idle that day (the 6.1 ms/step of ``bench_isph.py`` in the README was measured
earlier on an idle core). Before the fixed-order
dot products of linsolve (OpenBLAS threading each ddot above 10 000 entries), the 2 mm step read
1434/1330 ms (now 128/132 ms in the same A/B, 10 steps). T22-A70 to rest at 2 mm (7000 particles,
one thread, load average 6-13): 807 s, 4191 steps, 192.5 ms/step, at rest 17.97 t_c, front 2.136 m,
peak RSS 426 MB, 0 fallbacks.
"""
from __future__ import annotations

import argparse
import math
import os
import pickle
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

CACHE = Path(__file__).resolve().parents[1] / "results" / "bench_cache"
CASE = "T22-A150"


def _cfg(case: str, dx: float, solver: str | None = None):
    from granudep.isph.config import load_config
    over = {"dx": dx, "progress_every_s": 1e9}
    if solver:
        over["numerics.pressure_solver"] = solver
    return load_config(case, **over)


def refine(coarse, cfg):
    """A solver at cfg's dx (= coarse dx / 2) holding the coarse solver's flow: each coarse particle
    split into four at (±dx/2, ±dx/2) around it, with its velocity, pressure and viscosity; the wall
    particles those of the fine lattice. The 2 and 1 mm benchmark states are built so (a 1 mm run
    to t = 0.3 s costs ~2000 steps of 60 000 particles, hours on the shared machine), from the 4 mm
    state after t_flow of flow, and relaxed for ``RELAX`` steps: a developed velocity field on a
    locally regular lattice."""
    from granudep.isph.stepper import IsphSolver
    s = IsphSolver(cfg)
    nc = coarse.nf
    if 4 * nc != s.nf:
        raise ValueError(f"refine: {nc} coarse particles (some left through the outflow?) for {s.nf} fine ones")
    h = 0.5 * s.dx
    offs = [(-0.5 * h, -0.5 * h), (0.5 * h, -0.5 * h), (-0.5 * h, 0.5 * h), (0.5 * h, 0.5 * h)]
    xs = np.concatenate([coarse.x[:nc] + 2 * ox for ox, _ in offs])
    ys = np.concatenate([coarse.y[:nc] + 2 * oy for _, oy in offs])
    ys = np.maximum(ys, 0.5 * s.dx)
    s.x[:s.nf] = xs
    s.y[:s.nf] = ys
    for name in ("u", "v", "p", "eta", "gdot"):
        setattr(s, name, np.tile(getattr(coarse, name)[:nc], 4))
    s.t = coarse.t
    s.permuted = True  # the ids no longer follow the initial lattice
    return s


RELAX = 50


def checkpoint(case: str, dx: float, t_flow: float):
    """IsphSolver of ``case`` at dx after t_flow seconds of flow (default numerics), cached. At dx
    below 4 mm: the checkpoint at 2 dx refined (:func:`refine`) and relaxed for RELAX steps."""
    from granudep.isph.stepper import IsphSolver
    CACHE.mkdir(parents=True, exist_ok=True)
    path = CACHE / f"{case}_dx{dx * 1e3:g}mm_t{t_flow:g}.pkl"
    if path.exists():
        with open(path, "rb") as f:
            return pickle.load(f)
    t0 = time.perf_counter()
    if dx < 0.0039:
        s = refine(checkpoint(case, 2 * dx, t_flow), _cfg(case, dx))
        for _ in range(RELAX):
            dt = s.time_step()
            s.dt = dt
            s.step(dt)
    else:
        s = IsphSolver(_cfg(case, dx))
        while s.t < t_flow:
            dt = s.time_step()
            s.dt = dt
            s.step(dt)
    print(f"  checkpoint {path.name}: {s.step_no} steps, {time.perf_counter() - t0:.0f} s", flush=True)
    tmp = path.with_suffix(".tmp")
    with open(tmp, "wb") as f:
        pickle.dump(s, f)
    tmp.replace(path)
    return s


#: scheme options of the timed steps (``--set KEY=VALUE``), e.g. numerics.projection=approximate
SETS: dict = {}
#: ``--solvers`` suffixes that set numerics.deflation_min_unknowns (isph/deflation.py)
DEFLATION = {"deflated": 0, "undeflated": 10 ** 12}


def _restart(s, solver: str):
    """The checkpointed solver (default numerics) with another PPE solver and the ``--set`` scheme
    options (same state: a developed flow of the default scheme)."""
    from granudep.isph.config import load_config
    solver, _, operator = solver.partition("/")   # e.g. cg_dic/matrix_free: numerics.ppe_operator
    if operator in DEFLATION:                      # cg_dic/deflated, cg_dic/undeflated: the SSOR-CG with or
        over = {"numerics.deflation_min_unknowns": DEFLATION[operator]}   # without the coarse space at any N
    else:
        over = {"numerics.ppe_operator": operator} if operator else {}
    s.cfg = load_config(s.cfg, **{"numerics.pressure_solver": solver, **over, **SETS})
    s.stats.__init__()
    return s


#: seconds spent in the parts of the step, filled by the wrappers of :func:`_install_part_timers`
PARTS: dict = {}


def _install_part_timers() -> None:
    """Time the PPE assembly (CSR product or matrix-free operator), the PPE solve, the viscous
    assembly and the viscous solve inside every step (wrappers around the module functions)."""
    from granudep.isph import projection, viscous
    from granudep.isph.linear_systems import LinearSystems
    if getattr(LinearSystems, "_bench_parts", False):
        return

    def wrap(owner, name, key):
        f = getattr(owner, name)

        def g(*a, **k):
            t0 = time.perf_counter()
            try:
                return f(*a, **k)
            finally:
                PARTS[key] = PARTS.get(key, 0.0) + time.perf_counter() - t0
        setattr(owner, name, g)
    wrap(projection, "assemble_adjoint_ppe", "ppe_assembly")
    wrap(projection, "matrix_free_operator", "ppe_assembly")
    wrap(projection, "adjoint_triangles", "ppe_assembly")
    wrap(projection, "ppe_rhs", "ppe_assembly")
    wrap(LinearSystems, "solve_ppe", "ppe_solve")
    wrap(LinearSystems, "solve_ppe_free", "ppe_solve")
    wrap(viscous, "assemble_viscous", "visc_assembly")
    wrap(LinearSystems, "solve_cg_pair", "visc_solve")
    LinearSystems._bench_parts = True


def time_steps(case: str, dx: float, t_flow: float, solver: str, steps: int) -> dict:
    _install_part_timers()
    s = _restart(checkpoint(case, dx, t_flow), solver)
    for _ in range(2):  # hierarchy build / first-call overheads
        dt = s.time_step()
        s.dt = dt
        s.step(dt)
    s.stats.__init__()
    PARTS.clear()
    t0 = time.perf_counter()
    c0 = time.process_time()
    for _ in range(steps):
        dt = s.time_step()
        s.dt = dt
        s.step(dt)
    wall = time.perf_counter() - t0
    cpu = time.process_time() - c0
    st = s.stats
    n = st.steps
    return {"dx_mm": dx * 1e3, "solver": solver, "particles": s.nf, "ms": 1e3 * wall / n, "cpu_ms": 1e3 * cpu / n,
            "neigh": 1e3 * st.t_neigh / n, "kern": 1e3 * st.t_kern / n, "visc": 1e3 * st.t_visc / n,
            "ppe": 1e3 * st.t_ppe / n, "it_ppe": st.ppe_iters / n, "it_visc": st.visc_iters / n,
            "fallbacks": st.fallbacks, **{k: 1e3 * v / n for k, v in PARTS.items()},
            "load": os.getloadavg()[0]}


def fit_exponent(ns, ms) -> float:
    return float(np.polyfit(np.log(ns), np.log(ms), 1)[0])


def per_step(args) -> None:
    dxs = [float(d) * 1e-3 for d in args.dx.split(",")]
    solvers = args.solvers.split(",")
    rows = {}
    for dx in dxs:
        checkpoint(CASE, dx, args.t_flow)
    for rep in range(args.repeats):
        for dx in dxs:
            for solver in solvers:
                r = time_steps(CASE, dx, args.t_flow, solver, args.steps)
                rows.setdefault((dx, solver), []).append(r)
    print(f"NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', '(unset)')}, {CASE} after {args.t_flow} s of "
          f"flow, {args.steps} steps, median of {args.repeats} (ms/step [neighbours, kernels, viscous, PPE])")
    for solver in solvers:
        ns, ts = [], []
        for dx in dxs:
            rr = rows[(dx, solver)]
            med = {k: statistics.median(r[k] for r in rr) for k in ("ms", "cpu_ms", "neigh", "kern", "visc", "ppe",
                                                                  "it_ppe", "it_visc")}
            n = rr[0]["particles"]
            ns.append(n)
            ts.append(med["ms"])
            print(f"  dx={dx * 1e3:g}mm N={n:6d} {solver:8s}: {med['ms']:8.2f} ms/step (CPU {med['cpu_ms']:.2f}), "
                  f"{n / med['ms'] * 1e3:9.3g} particle-steps/s [{med['neigh']:.2f}, {med['kern']:.2f}, "
                  f"{med['visc']:.2f}, {med['ppe']:.2f}]; iterations/step PPE {med['it_ppe']:.1f}, viscous (u+v) "
                  f"{med['it_visc']:.1f}; fallbacks {rr[0]['fallbacks']}; all ms: "
                  + ", ".join(f"{r['ms']:.2f}" for r in rr), flush=True)
            parts = {k: statistics.median(r.get(k, 0.0) for r in rr)
                     for k in ("ppe_assembly", "ppe_solve", "visc_assembly", "visc_solve")}
            rest = med["ms"] - sum(parts.values())
            print(f"      parts (ms/step, median): PPE assembly {parts['ppe_assembly']:.2f}, PPE CG "
                  f"{parts['ppe_solve']:.2f}, viscous assembly {parts['visc_assembly']:.2f}, viscous CG "
                  f"{parts['visc_solve']:.2f}, rest {rest:.2f}; load average "
                  + ", ".join(f"{r['load']:.1f}" for r in rr), flush=True)
        if len(ns) > 1:
            cs = [statistics.median(r["cpu_ms"] for r in rows[(dx, solver)]) for dx in dxs]
            print(f"  {solver}: cost/step ~ N^{fit_exponent(ns, ts):.3f} (wall), N^{fit_exponent(ns, cs):.3f} (CPU) "
                  f"over N = {ns[0]}..{ns[-1]}")
        print_targets(solver, ns, ts, [statistics.median(r["cpu_ms"] for r in rows[(dx, solver)]) for dx in dxs])
    print(f"peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")


#: T22-A70 at dx = 1 mm: particles and steps to rest with the default (no-slip) bed, measured with
#: `--to-rest 1` (SSOR-CG PPE without deflation: at rest at 12.57 t_c after 6109 steps, 1757 s on one
#: thread; the deflated PPE: 6126 steps, 1224.7 s). The 2026-12-02 Coulomb-bed run needed 13 877 steps (README
#: "A 1 mm rung").
N_1MM, STEPS_1MM = 28_000, 6_109


def print_targets(solver: str, ns, ts, cpus=None) -> None:
    """The speed targets (printed, never asserted): <= 10 ms/step at 3750 particles on one thread;
    T22-A70 at 1 mm to rest <= 20 min, estimated as ms/step at 28 000 particles (the power law
    through the two nearest measured N) times 6109 steps (``STEPS_1MM``). Each from the wall time and, on a
    loaded machine the better guess of an idle core, from the process CPU time (``cpus``)."""
    threads = os.environ.get("NUMBA_NUM_THREADS", "(unset)")
    for label, vals in (("wall", ts), ("CPU", cpus)):
        if vals is None:
            continue
        for n, t in zip(ns, vals):
            if n == 3750:
                print(f"  target {solver} ({label}): <= 10 ms/step at 3750 particles (NUMBA_NUM_THREADS={threads}): "
                      f"{t:.2f} ms/step, {'met' if t <= 10.0 else 'not met'}")
        if len(ns) > 1 and min(ns) <= N_1MM <= max(ns):
            pairs = sorted(zip(ns, vals))
            (n0, t0), (n1, t1) = next((a, b) for a, b in zip(pairs, pairs[1:]) if a[0] <= N_1MM <= b[0])
            k = math.log(t1 / t0) / math.log(n1 / n0)
            est = t0 * (N_1MM / n0) ** k
            minutes = est * STEPS_1MM / 6e4
            # a proxy (T22-A150's developed flow, not T22-A70's phases): with the deflated PPE it estimated
            # 19.8 min and a run measured 20.4 (--to-rest 1), without deflation 20.7 and 29.3; only a run decides
            print(f"  target {solver} ({label}): T22-A70 at 1 mm to rest <= 20 min: estimated {est:.0f} ms/step at "
                  f"{N_1MM} particles x {STEPS_1MM} steps = {minutes:.1f} min "
                  f"({'below' if minutes <= 20.0 else 'above'} 20 min; an estimate: measure with --to-rest 1)")


def to_rest(args) -> None:
    from granudep.isph.api import run_isph
    for d in args.to_rest.split(","):
        dx = float(d) * 1e-3
        t0 = time.perf_counter()
        ds = run_isph("T22-A70", dx=dx, progress_every_s=60.0,
                      **{"numerics.pressure_solver": args.solvers.split(",")[0].partition("/")[0], **SETS})
        wall = time.perf_counter() - t0
        print(f"T22-A70 dx={d}mm ({ds.attrs['n_particles']} particles, NUMBA_NUM_THREADS="
              f"{os.environ.get('NUMBA_NUM_THREADS', '(unset)')}): {ds.attrs['status']} at t={float(ds.time[-1]):.3f} s, "
              f"time_to_rest {ds.attrs['time_to_rest_norm']:.2f} t_c, front {float(ds.final_front_position):.3f} m, "
              f"{ds.attrs['n_steps']} steps, wall {wall:.1f} s ({ds.attrs['ms_per_step']:.2f} ms/step), "
              f"fallbacks {ds.attrs.get('linear_solver_fallbacks', 'n/a')}, peak RSS "
              f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", default="4,2,1", help="resolutions in mm")
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--t-flow", type=float, default=0.3, help="seconds of flow before the timed steps")
    ap.add_argument("--solvers", default="cg_dic", help="comma-separated numerics.pressure_solver values")
    ap.add_argument("--threads", default=None, help="e.g. 1,2: rerun this command once per NUMBA_NUM_THREADS")
    ap.add_argument("--to-rest", default=None, help="e.g. 2,1: T22-A70 to rest at these dx (mm)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="scheme option of the timed steps (repeatable), e.g. numerics.projection=approximate")
    args = ap.parse_args()
    from granudep.cliutil import parse_sets
    SETS.update(parse_sets(args.set))
    if args.threads:
        argv, skip = [], False
        for a in sys.argv[1:]:
            if skip or a == "--threads" or a.startswith("--threads="):
                skip = a == "--threads"
                continue
            argv.append(a)
        for t in args.threads.split(","):
            subprocess.run([sys.executable, __file__, *argv], env={**os.environ, "NUMBA_NUM_THREADS": t}, check=True)
        return
    from granudep.isph.api import warmup
    warmup()
    if args.to_rest:
        to_rest(args)
    else:
        per_step(args)


if __name__ == "__main__":
    main()
