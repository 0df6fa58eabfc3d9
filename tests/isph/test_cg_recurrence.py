"""The CG recurrence is written once (``isph.linsolve``: ``converged``, ``search_direction``,
``cg_advance``) and every CG loop of granudep calls it: checked against plain NumPy, and on the
sources (no loop keeps a stopping test of its own)."""
import inspect
import re

import numpy as np

from granudep.isph import cg_dic, cg_two_level, deflation, linsolve
from granudep.isph.linsolve import cg_advance, converged, search_direction, stop_threshold


def test_search_direction_and_step_match_numpy():
    rng = np.random.default_rng(5)
    p, z, x, r, q = (rng.normal(size=50) for _ in range(5))
    p1 = p.copy()
    search_direction(p1, z, 0.7, 0.35, True)
    assert np.array_equal(p1, z)
    p2 = p.copy()
    search_direction(p2, z, 0.7, 0.35, False)
    assert np.array_equal(p2, p * (0.7 / 0.35) + z)
    x1, r1 = x.copy(), r.copy()
    cg_advance(x1, r1, p, q, 0.3)
    assert np.array_equal(x1, x + 0.3 * p) and np.array_equal(r1, r - 0.3 * q)


def test_stopping_test_is_strict_and_uses_the_larger_of_the_tolerances():
    t = stop_threshold(10.0, 1e-3, 1e-6)
    assert t == 1e-2
    assert stop_threshold(1e-6, 1e-3, 1e-6) == 1e-6
    assert converged(0.5 * t, t) and not converged(t, t)


def test_no_cg_loop_keeps_a_stopping_test_of_its_own():
    """Every comparison of a residual norm with the threshold goes through ``converged``."""
    own = re.compile(r"<\s*(thresh|th[uv])\b")
    for mod in (linsolve, cg_dic, cg_two_level, deflation):
        src = inspect.getsource(mod)
        body = src.replace(inspect.getsource(linsolve.converged.py_func), "") if mod is linsolve else src
        assert not own.findall(body), f"{mod.__name__} compares a residual with the threshold itself"


def test_one_loop_serves_the_csr_and_the_matrix_free_two_level_cg():
    """``cg_two_level`` (CSR) and the matrix-free two-level CG both run ``linsolve._pcg_loop``."""
    assert "_pcg_free_loop" not in dir(cg_two_level)
    src = inspect.getsource(cg_two_level)
    assert src.count("_pcg_loop(") == 2
