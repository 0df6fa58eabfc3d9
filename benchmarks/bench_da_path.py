"""Benchmark of the DA model on a path profile: 10 000 particles on a 1 km path
(a 30° slope over 600 m easing into a 400 m flat runout zone, σ = 20 m), a 50 m × 5 m release,
run to rest. Prints the wall time after JIT, the steps and particle-steps per second.

Target: <= 10 s after compilation on one core. Run with NUMBA_NUM_THREADS=1; the
machine is shared, so the load average and the process CPU time are printed next to the numbers:

    NUMBA_NUM_THREADS=1 python benchmarks/bench_da_path.py [--n-particles 10000] [--deposition]
        [--time-step relative|absolute] [--repeat 1]
"""
from __future__ import annotations

import argparse
import math
import os
import tempfile
import time
from pathlib import Path


def config(csv: Path, n: int, time_step: str, deposition: bool) -> dict:
    return {"case": "bench_path",
            "geometry": {"L0": 50.0, "H0": 5.0, "back_wall": True,
                         "path": {"file": str(csv), "smoothing_length": 20.0, "release_start": 10.0,
                                  "time_step": time_step}},
            "material": {"phi_internal_deg": 32.0, "phi_basal_deg": 28.0},
            "numerics": {"n_particles": n, "earth_pressure": "savage_hutter", "t_end": 300.0, "u_rest": 1e-3},
            "deposition": {"ab_source": "user", "A": -0.0313, "B": 0.0402, "x_inf_mode": "user", "x_inf": 800.0,
                           "enabled": deposition},
            "output": {"dt_output": 2.0, "dx_grid": 0.5, "front_depth_threshold": 0.05, "flow_time_tolerance": 0.5}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n-particles", type=int, default=10000)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--deposition", action="store_true", help="with deposition (x_inf fixed at s = 800 m)")
    ap.add_argument("--time-step", choices=["relative", "absolute"], default="relative")
    ap.add_argument("--t-end", type=float, default=300.0, metavar="S",
                    help="stop after S s of flow (a per-step cost measurement; default 300: to rest)")
    args = ap.parse_args()
    from granudep.da.api import run_da
    from granudep.da.path_verification import write_profile
    t = math.tan(math.radians(30.0))
    with tempfile.TemporaryDirectory() as tmp:
        csv = write_profile(Path(tmp) / "km.csv", [0.0, 300.0, 600.0, 800.0, 1000.0],
                            [600.0 * t, 300.0 * t, 0.0, 0.0, 0.0])
        t0 = time.perf_counter()
        small = config(csv, 200, args.time_step, args.deposition)
        small["numerics"]["t_end"] = 2.0
        run_da(small, deposition=args.deposition)
        print(f"warm-up (JIT or cache load, 200 particles for 2 s): {time.perf_counter() - t0:.2f} s")
        cfg = config(csv, args.n_particles, args.time_step, args.deposition)
        cfg["numerics"]["t_end"] = args.t_end
        best, cpu, ds = float("inf"), float("inf"), None
        for _ in range(args.repeat):
            t1, c1 = time.perf_counter(), time.process_time()
            ds = run_da(cfg, deposition=args.deposition)
            best = min(best, time.perf_counter() - t1)
            cpu = min(cpu, time.process_time() - c1)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    steps = int(ds.attrs["n_steps"])
    print(f"1 km path, N = {args.n_particles}, {'with' if args.deposition else 'without'} deposition, time_step "
          f"{args.time_step}: {steps} steps to t = {float(ds.time[-1]):.2f} s ({ds.attrs['status']}); best wall "
          f"{best:.2f} s of {args.repeat} (target <= 10 s; CPU {cpu:.2f} s: the wall time on a shared machine includes "
          f"waiting), {1e3 * best / max(steps, 1):.2f} ms/step ({1e3 * cpu / max(steps, 1):.2f} ms CPU), "
          f"{args.n_particles * steps / best / 1e6:.2f} M particle-steps/s; "
          f"front at x = {ds.attrs['final_front_x']:.1f} m, travel angle {float(ds.travel_angle):.2f} deg; "
          f"load average {load:.2f}, NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', 'unset')}")


if __name__ == "__main__":
    main()
