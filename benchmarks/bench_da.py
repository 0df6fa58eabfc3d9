"""Benchmark of the DA SPH solver: 1D-A70, 1000 particles, run to rest (no deposition, and one
deposition run with a fixed x_inf). Prints wall time after JIT and particle-steps per second.

Target: <= 1 s after compilation on one core. Run with NUMBA_NUM_THREADS=1; the
machine is shared, so report the load next to the numbers:

    NUMBA_NUM_THREADS=1 .venv/bin/python benchmarks/bench_da.py [--repeat 3]
"""
from __future__ import annotations

import argparse
import os
import time

from granudep.da.api import _k, warmup
from granudep.da.config import resolve
from granudep.da.solver import Physics, simulate


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--n-particles", type=int, default=1000)
    args = ap.parse_args()
    t0 = time.perf_counter()
    warmup()
    print(f"warm-up (JIT or cache load): {time.perf_counter() - t0:.2f} s")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    for deposition in (False, True):
        cfg = resolve("1D-A70", deposition=deposition, n_particles=args.n_particles)
        ka, kp = _k(cfg)
        phys = Physics(ka, kp, deposition, -0.0313, 0.0402, 2.5)
        best = float("inf")
        for _ in range(args.repeat):
            t = time.perf_counter()
            rec = simulate(cfg, phys)
            best = min(best, time.perf_counter() - t)
        ps = args.n_particles * rec.n_steps / best
        print(f"1D-A70 {'with' if deposition else 'without'} deposition, N = {args.n_particles}: "
              f"{rec.n_steps} steps to rest (t = {rec.time[-1]:.3f} s, {len(rec.time)} outputs), "
              f"best wall {best:.3f} s of {args.repeat}, {ps / 1e6:.2f} M particle-steps/s "
              f"(load average {load:.2f}, NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', 'unset')})")


if __name__ == "__main__":
    main()
