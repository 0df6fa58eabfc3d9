"""Both cores: the per-particle loops run in parallel (numba prange), each iteration
writing only its own particle/row, so the results do not depend on the thread count — bit for bit.
Each run is a subprocess with its own NUMBA_NUM_THREADS (numba reads it at import)."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

_SCRIPT = r"""
import json, sys
import numba
import numpy as np
from granudep.isph.config import load_config
from granudep.isph.stepper import IsphSolver
s = IsphSolver(load_config("T22-A70", dx=0.01, **{"numerics.reorder_interval": 5,
                                                   "numerics.threads_mode": sys.argv[2]}))
for _ in range(40):
    dt = s.time_step()
    s.dt = dt
    s.step(dt)
np.savez(sys.argv[1], x=s.x, y=s.y, u=s.u, v=s.v, p=s.p, eta=s.eta, fs=s.fs, ids=s.ids)
from granudep.isph import operators
builds = {b: len(getattr(operators.geometry_terms, b).signatures) for b in ("serial", "parallel")}
from granudep.isph import stepper
print(json.dumps({"threads": numba.get_num_threads(), "ppe": s.stats.ppe_iters, "visc": s.stats.visc_iters,
                  "builds": builds, "ppe_thread": stepper._PPE_THREAD is not None}))
"""


def _run(threads, out, mode="overlap"):
    env = {**os.environ, "NUMBA_NUM_THREADS": str(threads)}
    r = subprocess.run([sys.executable, "-c", _SCRIPT, str(out), mode], env=env, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    return json.loads(r.stdout.strip().splitlines()[-1])


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="needs two cores to start two numba threads")
def test_one_and_two_threads_give_the_same_run_bit_for_bit(tmp_path):
    a = _run(1, tmp_path / "t1.npz")
    b = _run(2, tmp_path / "t2.npz", "prange")
    c = _run(2, tmp_path / "t3.npz", "auto")        # the default: overlap on two threads
    assert a["threads"] == 1 and b["threads"] == 2 and c["threads"] == 2  # NUMBA_NUM_THREADS honoured
    assert (a["ppe"], a["visc"]) == (b["ppe"], b["visc"]) == (c["ppe"], c["visc"]) and a["ppe"] > 0
    # one thread runs the serial build (no hand-off to a worker thread per prange region), two in
    # threads_mode prange the parallel one: the comparison below is between the two builds
    assert a["builds"] == {"serial": 1, "parallel": 0}, a["builds"]
    assert b["builds"] == {"serial": 0, "parallel": 1}, b["builds"]
    # threads_mode overlap (auto on two threads): the serial builds, and the PPE geometry built on a second
    # thread beside the predictor (solver._start_ppe_geometry); one thread and prange build it inline
    assert c["builds"] == {"serial": 1, "parallel": 0}, c["builds"]
    assert not a["ppe_thread"] and not b["ppe_thread"] and c["ppe_thread"]
    r1 = np.load(tmp_path / "t1.npz")
    for other in ("t2.npz", "t3.npz"):
        r2 = np.load(tmp_path / other)
        for k in r1.files:
            assert np.array_equal(r1[k], r2[k]), (other, k)
    assert np.abs(r1["u"]).max() > 0.05  # the column is collapsing: the comparison is not of a state at rest


def test_the_two_builds_of_a_prange_kernel_keep_separate_caches_and_agree():
    """The serial build is a renamed copy (its own cache index); both give the same numbers."""
    from granudep.isph import operators
    from granudep.isph.parallel import SERIAL_SUFFIX

    k = operators.pair_kernel
    assert k.serial.py_func.__qualname__ == k.py_func.__qualname__ + SERIAL_SUFFIX
    assert k.parallel.py_func.__qualname__ == k.py_func.__qualname__
    assert k.serial.py_func.__code__ is k.py_func.__code__
    assert k.build(1) is k.serial and k.build(2) is k.parallel
    rr = np.random.default_rng(3).uniform(0.0, 0.02, 500)
    a = k.serial(rr, 0.006)
    b = k.parallel(rr, 0.006)
    ref = k.py_func(rr, 0.006)
    for x, y, z in zip(a, b, ref):
        assert np.array_equal(x, y)
        np.testing.assert_allclose(x, z, rtol=1e-12, atol=0.0)
    assert np.abs(a[0]).max() > 0
