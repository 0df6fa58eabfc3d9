"""PySPH's 2D dam break beside granudep's, on this machine, in one run (not a test).

PySPH is never a granudep dependency: it lives in a scratch virtual environment outside the
repository (default /work/scratch/pysph-venv, created and filled here when missing: ``pip install
pysph`` builds from source, ~6 min, plus scipy/cython/mako), with HOME pointed at a scratch folder
(PySPH writes its compiled-kernel cache under ~/.pysph). For each PySPH scheme (SISPH, the projection-type
one, and WCSPH for scale) ``pysph.examples.dam_break_2d`` runs twice in a child
process of that venv (tf_a and tf_b, one OpenMP thread, no output), after one untimed short run per
scheme that builds its kernels (minutes the first time): ms/step = the difference of the wall
times over the difference of the step counts, which drops the set-up and the kernel loading.
Beside it, in this process, granudep's water dam break (``isph.verification.dam_break_config``, at
the dx that gives PySPH's fluid particle count) and the T22-A150 collapse at 4 mm (3750 particles),
ms/step over ``--steps`` steps after a warm-up, for each ``--solvers`` entry. The rounds are
interleaved (PySPH, granudep, PySPH, ...) and the median of ``--repeats`` is printed with the
load average; the ratio is PySPH ms/step / granudep ms/step (> 1: granudep faster).

PySPH 1.0b2's IISPH dam break is not timed by default: with its adaptive step its solver reports
2 steps (1.5 s wall) for any tf from 0.001 to 0.3 s, and with --no-adaptive-timestep (dt = 0.0006 s)
it diverges within 0.02 s ("Domain size has increased by a large amount"): no ms/step to compare.

Run: NUMBA_NUM_THREADS=1 python benchmarks/pysph_side_by_side.py [--schemes sisph,wcsph]
     [--solvers cg_two_level,cg_dic] [--repeats 3] [--venv /work/scratch/pysph-venv]
Target (printed, not asserted): granudep >= 2.5x faster than PySPH's SISPH.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

DRIVER = r'''
import json, sys, time, os
from pysph.examples.dam_break_2d import DamBreak2D
scheme, dx, tf = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
out = os.path.join(os.environ["HOME"], "out_" + scheme)
app = DamBreak2D(output_dir=out)
t0 = time.perf_counter()
app.run(["--scheme", scheme, "--dx", str(dx), "--tf", str(tf), "--disable-output", "-q"])
wall = time.perf_counter() - t0
fluid = [pa for pa in app.particles if pa.name == "fluid"][0]
print(json.dumps({"scheme": scheme, "steps": int(app.solver.count), "wall": wall,
                  "fluid": int(fluid.get_number_of_particles()), "t": float(app.solver.t)}))
'''


def ensure_venv(venv: Path, home: Path) -> Path:
    py = venv / "bin" / "python"
    home.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "HOME": str(home)}
    if py.exists() and subprocess.run([str(py), "-c", "import pysph"], env=env, capture_output=True).returncode == 0:
        return py
    print(f"creating {venv} and building PySPH (pip install pysph, ~6 min) ...", flush=True)
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    pip = [str(py), "-m", "pip", "install", "-q"]
    subprocess.run(["nice", "-n", "10", *pip, "numpy", "scipy", "cython", "mako", "pytools", "beaker", "setuptools",
                    "wheel"], env=env, check=True)
    subprocess.run(["nice", "-n", "10", *pip, "pysph"], env=env, check=True)
    return py


def pysph_ms_per_step(py: Path, home: Path, scheme: str, dx: float, tf_a: float, tf_b: float) -> dict:
    env = {**os.environ, "HOME": str(home), "OMP_NUM_THREADS": "1"}
    rs = []
    for tf in (tf_a, tf_b):
        r = subprocess.run([str(py), "-c", DRIVER, scheme, str(dx), str(tf)], env=env, capture_output=True,
                           text=True)
        if r.returncode != 0:
            raise RuntimeError(f"PySPH {scheme} failed:\n{r.stderr[-2000:]}")
        rs.append(json.loads(r.stdout.strip().splitlines()[-1]))
    a, b = rs
    return {"fluid": b["fluid"], "steps": b["steps"] - a["steps"],
            "ms": 1e3 * (b["wall"] - a["wall"]) / max(b["steps"] - a["steps"], 1)}


def granudep_ms_per_step(case: str, n_target: int, solver: str, steps: int) -> dict:
    import math
    from granudep.isph.config import load_config
    from granudep.isph.stepper import IsphSolver
    from granudep.isph.verification import dam_break_config
    over = {"numerics.pressure_solver": solver.split("/")[0]}
    if "/" in solver:
        over["numerics.ppe_operator"] = solver.split("/")[1]
    if case == "dam-break":
        d = dam_break_config(0.004)
        dx = math.sqrt(d["geometry"]["L0"] * d["geometry"]["H0"] / n_target)
        cfg = load_config(dam_break_config(round(dx, 5)), **over)
    else:
        cfg = load_config(case, dx=0.004, progress_every_s=1e9, **over)
    s = IsphSolver(cfg)
    for _ in range(10):                      # warm-up: first steps of the collapse, caches
        dt = s.time_step()
        s.dt = dt
        s.step(dt)
    s.stats.__init__()
    t0 = time.perf_counter()
    c0 = time.process_time()
    for _ in range(steps):
        dt = s.time_step()
        s.dt = dt
        s.step(dt)
    n = s.stats.steps
    return {"fluid": s.nf, "ms": 1e3 * (time.perf_counter() - t0) / n, "cpu_ms": 1e3 * (time.process_time() - c0) / n,
            "ppe_its": s.stats.ppe_iters / n}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--venv", default="/work/scratch/pysph-venv")
    ap.add_argument("--home", default="/work/scratch/pysph-home")
    ap.add_argument("--schemes", default="sisph,wcsph", help="PySPH schemes (iisph: see the module doc)")
    ap.add_argument("--solvers", default="cg_two_level,cg_dic", help="granudep numerics.pressure_solver values "
                                                               "(solver/matrix_free: numerics.ppe_operator)")
    ap.add_argument("--dx", type=float, default=0.0231, help="PySPH particle spacing (its 1 x 2 m column: "
                                                             "2/dx^2 fluid particles, 0.0231: ~3750)")
    ap.add_argument("--tf", default="0.05,0.15", help="PySPH end times of the two runs (s)")
    ap.add_argument("--steps", type=int, default=60, help="granudep steps timed")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    py = ensure_venv(Path(args.venv), Path(args.home))
    from granudep.isph.api import warmup
    warmup()
    tf_a, tf_b = (float(v) for v in args.tf.split(","))
    schemes = args.schemes.split(",")
    solvers = args.solvers.split(",")
    rows: dict = {}
    env = {**os.environ, "HOME": args.home, "OMP_NUM_THREADS": "1"}
    for scheme in schemes:      # build (or load) each scheme's compiled kernels before any timing
        subprocess.run([str(py), "-c", DRIVER, scheme, str(args.dx), str(tf_a / 5)], env=env, capture_output=True)
    for rep in range(args.repeats):
        for scheme in schemes:
            r = pysph_ms_per_step(py, Path(args.home), scheme, args.dx, tf_a, tf_b)
            r["load"] = os.getloadavg()[0]
            rows.setdefault(("pysph", scheme), []).append(r)
            for solver in solvers:
                for case in ("dam-break", "T22-A150"):
                    g = granudep_ms_per_step(case, r["fluid"], solver, args.steps)
                    g["load"] = os.getloadavg()[0]
                    rows.setdefault((case, solver), []).append(g)
    if os.environ.get("NUMBA_NUM_THREADS") != "1":
        print("warning: NUMBA_NUM_THREADS is not 1, so granudep does not run on one thread like PySPH (OMP_NUM_THREADS=1); "
              "on the 2-core machine two numba threads are slower (docs/performance.md)", flush=True)
    print(f"NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', '(unset)')}, OMP_NUM_THREADS=1 for PySPH; "
          f"median of {args.repeats} interleaved rounds (all values in brackets)")
    med = {k: statistics.median(r["ms"] for r in v) for k, v in rows.items()}
    for (kind, name), rr in rows.items():
        extra = f", PPE iterations/step {rr[0]['ppe_its']:.1f}" if "ppe_its" in rr[0] else ""
        all_ms = ", ".join(f"{r['ms']:.1f}" for r in rr)
        loads = ", ".join(f"{r['load']:.1f}" for r in rr)
        print(f"  {kind:9s} {name:18s} {rr[0]['fluid']:6d} particles: {med[(kind, name)]:8.2f} ms/step "
              f"[{all_ms}]{extra}; load {loads}")
    for scheme in schemes:
        for solver in solvers:
            for case in ("dam-break", "T22-A150"):
                ratio = med[("pysph", scheme)] / med[(case, solver)]
                flag = "met" if ratio >= 2.5 else "not met"
                print(f"  PySPH {scheme} / granudep {case} ({solver}): {ratio:.2f}x  (target >= 2.5x: {flag})")


if __name__ == "__main__":
    main()
