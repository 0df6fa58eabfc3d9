"""The adjoint PPE divergence (isph/projection.py) against a dense NumPy transpose of the gradient."""
import numpy as np

from granudep.isph import physics as ph
from granudep.isph.neighbours import build_neighbours
from granudep.isph.projection import adjoint_divergence


def _cloud(n_side=9, dx=0.01, seed=0):
    rng = np.random.default_rng(seed)
    gx, gy = np.meshgrid(np.arange(n_side) * dx, np.arange(n_side) * dx)
    x = gx.ravel() + rng.uniform(-0.2, 0.2, gx.size) * dx
    y = gy.ravel() + rng.uniform(-0.2, 0.2, gy.size) * dx + 0.05   # far from any wall: no wall particles
    return x, y, dx


def test_adjoint_divergence_is_minus_the_transpose_of_the_gradient():
    x, y, dx = _cloud()
    nf = x.size
    h = 1.3 * dx
    vol = dx * dx
    start, nbr, rx, ry, rr = build_neighbours(x, y, nf, 2.0 * h, 0.0)
    wk, gw = ph.pair_kernel(rr, h)
    _, _, _, _, lmat, _ = ph.geometry_terms(start, nbr, rx, ry, rr, wk, gw, nf, h, vol)
    zeros = np.zeros(nf)
    empty = np.zeros(0)
    detached = np.zeros(nf, np.bool_)
    # dense gradient matrices from unit pressure fields
    gxm = np.zeros((nf, nf))
    gym = np.zeros((nf, nf))
    for k in range(nf):
        e = np.zeros(nf)
        e[k] = 1.0
        a, b = ph.pressure_gradient(start, nbr, rx, ry, rr, gw, nf, h, vol, e, zeros, zeros, lmat, empty, empty,
                                    1e-3, 1000.0, detached)
        gxm[:, k], gym[:, k] = a, b
    rng = np.random.default_rng(1)
    u, v = rng.normal(size=nf), rng.normal(size=nf)
    d = adjoint_divergence(start, nbr, rx, ry, gw, nf, vol, u, v, lmat)
    assert np.allclose(d, -(gxm.T @ u + gym.T @ v), rtol=1e-10, atol=1e-10 * np.abs(d).max())


def _setup(jitter, n_side=13, seed=2):
    rng = np.random.default_rng(seed)
    dx = 0.01
    gx, gy = np.meshgrid(np.arange(n_side) * dx, np.arange(n_side) * dx)
    x = gx.ravel() + rng.uniform(-jitter, jitter, gx.size) * dx
    y = gy.ravel() + rng.uniform(-jitter, jitter, gy.size) * dx + 0.05
    nf = x.size
    h = 1.3 * dx
    start, nbr, rx, ry, rr = build_neighbours(x, y, nf, 2.0 * h, 0.0)
    wk, gw = ph.pair_kernel(rr, h)
    _, _, _, _, lmat, _ = ph.geometry_terms(start, nbr, rx, ry, rr, wk, gw, nf, h, dx * dx)
    cx, cy = x - x.mean(), y - y.mean()
    inner = (np.abs(cx) < 2.5 * dx) & (np.abs(cy) < 2.5 * dx)
    return x, y, dx, start, nbr, rx, ry, rr, gw, lmat, inner


def test_adjoint_divergence_is_exact_for_linear_fields_on_a_lattice():
    x, y, dx, start, nbr, rx, ry, rr, gw, lmat, inner = _setup(0.0)
    u = 0.3 + 2.0 * x - 1.0 * y
    v = -0.1 + 0.5 * x + 3.0 * y                          # div = 5
    d = adjoint_divergence(start, nbr, rx, ry, gw, x.size, dx * dx, u, v, lmat)
    assert np.allclose(d[inner], 5.0, rtol=1e-9)


def test_adjoint_divergence_sees_a_uniform_translation_on_a_disordered_cloud():
    """Why it is not the default: on a disordered cloud Σ_j V ∇W_kj ≠ 0, and the adjoint of the
    renormalised gradient reads a uniform translation as divergence (the renormalised divergence
    reads exactly 0)."""
    x, y, dx, start, nbr, rx, ry, rr, gw, lmat, inner = _setup(0.2)
    nf = x.size
    u = np.full(nf, 1.0)
    v = np.zeros(nf)
    d_adj = adjoint_divergence(start, nbr, rx, ry, gw, nf, dx * dx, u, v, lmat)
    d_ren = ph.divergence(start, nbr, rx, ry, rr, gw, nf, 1.3 * dx, dx * dx, u, v, lmat)
    assert np.max(np.abs(d_ren[inner])) < 1e-9
    assert np.sqrt(np.mean(d_adj[inner] ** 2)) > 1.0        # 1/s for 1 m/s: O(disorder / h)
