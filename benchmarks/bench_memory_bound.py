"""Is the fine ISPH step bound by memory bandwidth? (not a test; prints figures)

    NUMBA_NUM_THREADS=2 python benchmarks/bench_memory_bound.py [--dx 2,1] [--repeats 20]

For one and two numba threads (``numba.set_num_threads``, bounded by NUMBA_NUM_THREADS):
  * the STREAM triad a = b + s c on 3 x 8e6 doubles (192 MB: far out of cache): the machine's
    sustainable bandwidth, GB/s;
  * the CSR product A p of a captured adjoint-pair PPE matrix (T22-A150 bench state of
    ``bench_isph_scaling.py`` at each dx, one step's system) with the CG's own row-parallel kernel
    (``linsolve._pcg_loop``'s loop, here ``csr_matvec`` and a prange copy): ms, and the bandwidth
    it draws (8 bytes of value + 8 of column index per entry, plus the vectors);
  * one two-level CG solve of that system: ms and iterations.
The CG's cost floor is iterations x (bytes of A)/(triad bandwidth); the benchmark prints it next
to the measured solve. A product that draws close to the triad bandwidth on one thread cannot be
made much faster by a second thread on the same memory bus. Run it on an idle machine: another
process on the other core takes part of the bus.

Measured 2026-12-02 (idle 2-core AMD EPYC VM, ``--dx 2,1 --repeats 20``): triad 23.1 GB/s
on one thread, 30.5 on two (medians 19.5 / 21.1). 1 mm system (59 706 unknowns, 4.08 M entries, 68
per row, 67 MB): A p 4.97 ms on one thread (13.4 GB/s, 58 % of the triad), 2.97 ms best / 4.39 ms
median on two; the two-level CG 400 ms (1 thread) / 341 ms (2 threads), 51 iterations, 7.3 ms per
iteration against its bandwidth floor of 2.9 ms (one thread). 2 mm (15 209 unknowns, 17 MB, inside
the 32 MB L3): A p 1.28 / 0.83 ms, CG 110 / 102 ms. The second core buys 8-32 % of bandwidth and
15 % of the CG. (An A p over four rows at once, each row summed in its own order, was 2x slower:
the product is not bound by the add latency.)
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numba
import numpy as np
from numba import njit, prange

sys.path.insert(0, str(Path(__file__).resolve().parent))


@njit(cache=True, parallel=True)
def _triad_parallel(a, b, c, s):
    for i in prange(a.size):
        a[i] = b[i] + s * c[i]


@njit(cache=True)
def _triad_serial(a, b, c, s):
    for i in range(a.size):
        a[i] = b[i] + s * c[i]


@njit(cache=True, parallel=True)
def _matvec_parallel(indptr, indices, data, x, out):
    for i in prange(indptr.size - 1):
        s = 0.0
        for k in range(indptr[i], indptr[i + 1]):
            s += data[k] * x[indices[k]]
        out[i] = s


def _best(f, repeats):
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t0)
    return min(ts), statistics.median(ts)


def capture_ppe(dx: float):
    """The PPE system (CSR, rhs, guess) of one step from the cached bench state at dx."""
    import bench_isph_scaling as bench
    s = bench.checkpoint(bench.CASE, dx, 0.3)
    saved = {}
    orig = s._solve_ppe

    def grab(indptr, indices, data, rhs, guess):
        saved.update(indptr=indptr.copy(), indices=indices.copy(), data=data.copy(), rhs=rhs.copy(), guess=guess.copy())
        return orig(indptr, indices, data, rhs, guess)

    s._solve_ppe = grab
    dt = s.time_step()
    s.dt = dt
    s.step(dt)
    return saved


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dx", default="2,1", help="bench resolutions in mm (4, 2, 1)")
    ap.add_argument("--repeats", type=int, default=20)
    a = ap.parse_args(argv)
    from granudep.isph import cg_two_level, linsolve
    linsolve.pin_blas_to_one_thread()
    threads = [t for t in (1, 2) if t <= numba.config.NUMBA_NUM_THREADS]
    n = 8_000_000
    x, y, z = np.zeros(n), np.ones(n), np.full(n, 2.0)
    triad = {}
    for t in threads:
        numba.set_num_threads(t)
        f = (lambda: _triad_serial(x, y, z, 3.0)) if t == 1 else (lambda: _triad_parallel(x, y, z, 3.0))
        f()
        best, med = _best(f, a.repeats)
        triad[t] = 24 * n / best / 1e9
        print(f"triad, {t} thread(s): best {best * 1e3:.2f} ms = {triad[t]:.1f} GB/s (median {24 * n / med / 1e9:.1f})",
              flush=True)
    for dxmm in a.dx.split(","):
        sysm = capture_ppe(float(dxmm) * 1e-3)
        ip, ix, d, b, g = (sysm[k] for k in ("indptr", "indices", "data", "rhs", "guess"))
        nrow, nnz = b.size, ix.size
        bytes_a = nnz * 16 + nrow * 8 * 3
        out = np.empty(nrow)
        for t in threads:
            numba.set_num_threads(t)
            f = (lambda: linsolve.csr_matvec(ip, ix, d, g, out)) if t == 1 else (lambda: _matvec_parallel(ip, ix, d, g, out))
            f()
            best, med = _best(f, a.repeats)
            cg_two_level.pcg_two_level(ip, ix, d, b, g, 1e-8, 0.0, 1000)
            t0 = time.perf_counter()
            _, it, info = cg_two_level.pcg_two_level(ip, ix, d, b, g, 1e-8, 0.0, 1000)
            solve = time.perf_counter() - t0
            floor = it * bytes_a / (triad[t] * 1e9)
            print(f"dx={dxmm} mm, {nrow} unknowns, {nnz} entries ({nnz / nrow:.0f}/row, {bytes_a / 1e6:.0f} MB), "
                  f"{t} thread(s): A p best {best * 1e3:.2f} ms ({bytes_a / best / 1e9:.1f} GB/s, "
                  f"{bytes_a / best / 1e9 / triad[t]:.0%} of the triad), median {med * 1e3:.2f} ms; two-level CG "
                  f"{solve * 1e3:.0f} ms, {it} iterations (info {info}); bandwidth floor of the CG {floor * 1e3:.0f} ms",
                  flush=True)


if __name__ == "__main__":
    main()
