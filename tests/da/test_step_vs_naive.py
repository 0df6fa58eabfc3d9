"""The numba step (``granudep.da.step.advance``, shared by the constant-θ and the path model) against
its plain-NumPy twin (``tests/da/naive_da.py``): one step on small problems.

Not bit for bit: the twin sums dense rows with NumPy's pairwise summation and the pair passes are
compiled with FMA contraction, so the two differ by re-association round-off; the comparison is to
1e-14 of each field's scale (measured: at most 5e-15, the deposit). Bit-for-bit identity of whole
runs before/after the refactoring was checked once against the previous code (commit message)."""
import math

import numpy as np
import pytest

import naive_da as nv
from granudep.da.config import resolve
from granudep.da.path import N_TABLE, T_A, T_B, T_COS, T_DWIDTH, T_KACT, T_KAPPA, T_KPASS, T_SIN, T_WIDTH
from granudep.da.solver import Physics, constant_bed_table, step_params
from granudep.da.sph import F_H, F_K, F_ND, F_U, F_V, F_V0, N_FIELDS
from granudep.da.step import MAX_STEPS, StepParams, advance, own_trail

N = 48


def _state(rng, n=N, L0=0.2, dead=()):
    """Sorted, irregular positions in [0, L0], smooth nonuniform velocities and volumes."""
    dx = L0 / n
    x = (np.arange(n) + 0.5) * dx + rng.uniform(-0.2, 0.2, n) * dx
    u = 0.4 + 0.6 * np.sin(3.0 * x / L0) + rng.uniform(-0.05, 0.05, n)
    V = 0.14 * dx * (1.0 + 0.3 * np.cos(2.0 * x / L0)) * (1.0 - x / (1.5 * L0))
    V0 = V * 1.05
    V[list(dead)] = 0.0
    u[list(dead)] = 0.0                                   # as after a full deposition
    nd = np.full(n, 1.0 / dx) * (1.0 + 0.1 * rng.uniform(-1, 1, n))
    return x, u, V, V0, nd


def _kernel_step(x, u, V, V0, nd, dep, depb, binv, p, tab, ng_env=0, k_state=None):
    F = np.zeros((N_FIELDS, x.size))
    F[F_U], F[F_V], F[F_V0], F[F_ND] = u, V, V0, nd
    F[F_K] = 1.0 if k_state is None else k_state
    xk, order = x.copy(), np.arange(x.size, dtype=np.int64)
    dep, depb = dep.copy(), depb.copy()
    env = np.zeros((3, ng_env))
    env[2] = np.inf
    out = advance((xk, F, order), (dep, depb if p.has_width else dep, binv, own_trail(x.size)), (env, np.zeros(3)),
                  0.0, 10.0, p._replace(max_steps=1), tab, 0)
    assert out[2] == MAX_STEPS and out[1] == 1          # exactly one step taken
    assert np.all(order == np.arange(x.size))           # the test states stay sorted
    return xk, F, dep, depb, out[5], out[4]


def _compare(mine, ref, what):
    scale = max(float(np.max(np.abs(ref))), 1e-300)
    err = float(np.max(np.abs(np.asarray(mine) - np.asarray(ref)))) / scale
    assert err < 1e-14, f"{what}: relative difference {err:.3e}"
    return err


def _constant_case(deposition):
    cfg = resolve("1D-A70", deposition=deposition, n_particles=N)
    phys = Physics(0.9, 2.0, deposition, -0.0313, 2.0, 0.18)
    p = step_params(cfg, phys)
    return cfg, p, constant_bed_table(cfg.theta, phys)


def _k_state(rng, n=N):
    """A strained k per particle: some at the limits (0.9, 2.0 of the test tables), some inside."""
    return np.clip(rng.uniform(0.7, 2.2, n), 0.5, 3.0)


@pytest.mark.parametrize("deposition,switch", [(False, "particle"), (True, "particle"), (False, "symmetric"),
                                               (True, "symmetric"), (False, "strain"), (True, "strain")])
def test_constant_slope_step_matches_naive(deposition, switch):
    rng = np.random.default_rng(7)
    cfg, p, tab = _constant_case(deposition)
    # the plain eq 25 mean here; the volume-weighted mean (the default) has its own comparison below
    p = p._replace(k_symmetric=switch != "particle", k_strain=20.0 if switch == "strain" else 0.0,
                   smoothing_volume=False)
    x, u, V, V0, nd = _state(rng, dead=(5,))
    ks = _k_state(np.random.default_rng(3)) if switch == "strain" else None
    ng = 240
    dep = np.zeros(ng)
    dep[20:60] = 1e-5 * (1 + np.sin(np.arange(40)))   # an existing deposit: the bed term acts
    binv = np.ones(ng)
    xk, F, depk, _, dt, L = _kernel_step(x, u, V, V0, nd, dep, dep, binv, p, tab, k_state=ks)
    xn, un, Vn, depn, _, h, dt_n, L_n, fr, *kn = nv.step(x, u, V, V0, nd, dep, dep, binv, p, tab, k_state=ks)
    assert L == pytest.approx(L_n, rel=1e-14) and dt == pytest.approx(dt_n, rel=1e-13)
    if switch == "strain":
        _compare(F[F_K], kn[0], "strained k")
        assert 0 < np.count_nonzero((F[F_K] > 0.9) & (F[F_K] < 2.0)) < N     # some inside the limits, some on them
    _compare(F[F_H], h, "depth")
    _compare(F[F_U], un, "velocity")
    _compare(xk - x, xn - x, "displacement")
    _compare(F[F_V], Vn, "volume")
    _compare(depk, depn, "deposit")
    if deposition:
        assert np.count_nonzero(fr) > 5                   # the deposition branch is exercised
        assert np.sum(F[F_V]) + np.sum(depk) == pytest.approx(np.sum(V) + np.sum(dep), rel=1e-14)
    assert F[F_U, 5] == 0.0 and xk[5] == x[5]             # an emptied particle stays put


@pytest.mark.parametrize("max_tan,switch", [(math.inf, "particle"), (math.tan(math.radians(25.5)), "particle"),
                                             (math.tan(math.radians(25.5)), "symmetric"), (math.inf, "strain")])
def test_path_step_matches_naive_with_width_curvature_and_relative_dt(max_tan, switch):
    """A bed table with varying slope, curvature and width (the path model's stage functions);
    deposition on every slope, or none where the bed (30° -> 12°) is steeper than φ_B = 25.5°."""
    rng = np.random.default_rng(11)
    cfg, p0, _ = _constant_case(True)
    ns, ds = 60, 0.005
    s = np.arange(ns) * ds
    th = np.radians(30.0 - 60.0 * s)
    tab = np.zeros((N_TABLE, ns))
    tab[T_SIN], tab[T_COS] = np.sin(th), np.cos(th)
    tab[T_KAPPA] = 60.0 * np.pi / 180.0
    tab[T_WIDTH] = 1.0 + 2.0 * s
    tab[T_DWIDTH] = 2.0
    tab[T_KACT], tab[T_KPASS] = 0.9, 2.0
    tab[T_A], tab[T_B] = -0.02 - 0.05 * s, 2.0
    p = p0._replace(origin=0.01, ds=ds, centripetal=True, has_width=True, dt_relative=True, geometry_step=0.004,
                    x_min=0.0, deposit_max_tan=max_tan, k_symmetric=switch != "particle",
                    k_strain=20.0 if switch == "strain" else 0.0)
    x, u, V, V0, nd = _state(rng)
    ks = _k_state(np.random.default_rng(3)) if switch == "strain" else None
    ng = 240
    dep = np.zeros(ng)
    dep[10:50] = 2e-5
    c = (np.arange(ng) + 0.5) * p.dx_grid + p.origin
    binv = 1.0 / (1.0 + 2.0 * c)
    depb = dep * binv
    xk, F, depk, depbk, dt, L = _kernel_step(x, u, V, V0, nd, dep, depb, binv, p, tab, ng_env=ng, k_state=ks)
    xn, un, Vn, depn, depbn, h, dt_n, L_n, fr, *kn = nv.step(x, u, V, V0, nd, dep, depb, binv, p, tab, k_state=ks)
    if switch == "strain":
        _compare(F[F_K], kn[0], "strained k")
    assert dt == pytest.approx(dt_n, rel=1e-13)
    for mine, ref, what in ((F[F_H], h, "depth"), (F[F_U], un, "velocity"), (xk - x, xn - x, "displacement"),
                            (F[F_V], Vn, "volume"), (depk, depn, "deposit"), (depbk, depbn, "deposit/width")):
        _compare(mine, ref, what)
    tan_b = math.tan(math.radians(25.5))
    steep = np.abs(np.interp(x + p.origin, s, tab[T_SIN])) > tan_b * np.interp(x + p.origin, s, tab[T_COS])
    assert np.count_nonzero(steep) > 5
    if max_tan == math.inf:
        assert np.count_nonzero(fr) > 5 and np.count_nonzero(fr[steep]) > 5   # the branch is exercised
    else:
        assert not np.any(fr[steep])                        # no deposit where it could not rest

def test_step_params_is_a_typed_record():
    """The kernels take one NamedTuple, typed field by field (no float-coded flags)."""
    cfg, p, _ = _constant_case(True)
    assert isinstance(p, StepParams)
    assert isinstance(p.back_wall, bool) and isinstance(p.max_steps, int) and isinstance(p.eq12, bool)
    assert p.tan_phi_basal == pytest.approx(math.tan(math.radians(cfg.material.phi_basal_deg)))
    assert all(isinstance(v, (bool, int, float)) for v in p)


@pytest.mark.slow
def test_step_vs_naive_without_jit():
    """The same comparisons with NUMBA_DISABLE_JIT=1: the stages also work as plain Python."""
    import os
    import subprocess
    import sys
    here = os.path.dirname(__file__)
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    out = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-m", "not slow",
                          os.path.join(here, "test_step_vs_naive.py")], env=env, capture_output=True, text=True,
                         timeout=600)
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-2000:]


def test_volume_weighted_smoothing_length_matches_naive_and_ignores_emptied_particles():
    """numerics.smoothing_weight: volume: eq 25's mean weighted by V/V0, against the NumPy twin; and a
    cluster of nearly emptied particles (n_i 50 times the rest) moves the count mean, not the weighted one."""
    rng = np.random.default_rng(11)
    cfg, p, tab = _constant_case(True)
    p = p._replace(smoothing_volume=True, k_symmetric=False, k_strain=0.0)
    x, u, V, V0, nd = _state(rng, dead=(5,))
    V0 = V0 * (1.0 + rng.uniform(0.0, 3.0, N))           # unequal fractions V/V0
    ng = 240
    dep = np.zeros(ng)
    dep[20:60] = 1e-5 * (1 + np.sin(np.arange(40)))   # an existing deposit: the bed term acts
    binv = np.ones(ng)
    xk, F, depk, _, dt, L = _kernel_step(x, u, V, V0, nd, dep, dep, binv, p, tab)
    xn, un, Vn, depn, _, h, dt_n, L_n, fr, *kn = nv.step(x, u, V, V0, nd, dep, dep, binv, p, tab)
    assert L == pytest.approx(L_n, rel=1e-14)
    assert np.count_nonzero(fr > 0) > 0                  # eq 34 deposits in this step
    _compare(F[F_U], un, "velocity")
    _compare(F[F_V], Vn, "volume")
    _compare(depk, depn, "deposit")
    from granudep.da.step import smoothing_length
    G = np.zeros((N_FIELDS, N))
    G[F_V0] = 1.0
    G[F_V] = 1.0
    G[F_ND] = 100.0
    G[F_V, :10] = 1e-4                                    # ten particles nearly emptied by eq 34 ...
    G[F_ND, :10] = 5000.0                                 # ... piled into one cluster
    count = smoothing_length(G, p._replace(smoothing_volume=False))
    weighted = smoothing_length(G, p)
    full = N - 10
    clean = p.smoothing_B / 100.0                         # the full particles alone
    assert weighted == pytest.approx(p.smoothing_B * (full + 10e-4) / (full * 100.0 + 10e-4 * 5000.0), rel=1e-14)
    assert abs(weighted / clean - 1.0) < 2e-3
    assert count == pytest.approx(p.smoothing_B * N / (full * 100.0 + 10 * 5000.0), rel=1e-14)
    assert count < 0.2 * clean
