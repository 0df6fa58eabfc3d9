"""The SPH operators of isph/operators.py against plain-NumPy references (naive_isph.py) on small
clouds, and the claims their docstrings make: the renormalised gradient and divergence are exact for
linear fields, also on a support cut by a free surface."""
import numpy as np
import pytest

from granudep.isph import approximate, operators
from granudep.isph.bundles import Pairs, WallSurface
from granudep.isph.neighbours import build_neighbours

import naive_isph as naive

DX = 0.01
H = 1.3 * DX
VOL = DX * DX


def _cloud(n_side=11, jitter=0.2, seed=0, walls=False):
    """Granular particles on a jittered lattice with free edges; optionally three wall rows under them."""
    rng = np.random.default_rng(seed)
    gx, gy = np.meshgrid((np.arange(n_side) + 0.5) * DX, (np.arange(n_side) + 0.5) * DX)
    x = gx.ravel() + rng.uniform(-jitter, jitter, gx.size) * DX
    y = gy.ravel() + rng.uniform(-jitter, jitter, gy.size) * DX
    nf = x.size
    if walls:
        wx, wy = np.meshgrid((np.arange(-3, n_side + 3) + 0.5) * DX, -(np.arange(3) + 0.5) * DX)
        x, y = np.concatenate((x, wx.ravel())), np.concatenate((y, wy.ravel()))
    start, nbr, rx, ry, rr = build_neighbours(x, y, nf, 2.0 * H, 0.0)
    wk, gw = operators.pair_kernel(rr, H)
    return dict(x=x, y=y, nf=nf, start=start, nbr=nbr, rx=rx, ry=ry, rr=rr, wk=wk, gw=gw,
                pairs=Pairs(start, nbr, rx, ry, rr, wk, gw))


def _geometry(c):
    return operators.geometry_terms(c["pairs"], c["nf"], H, VOL)


@pytest.mark.parametrize("walls", [False, True])
def test_geometry_terms_match_the_pairwise_formulas(walls):
    c = _cloud(walls=walls)
    divr, conc, gcx, gcy, lmat, (mxx, myy) = _geometry(c)
    n_divr, n_conc, n_gcx, n_gcy, n_lmat, m = naive.geometry(c["x"], c["y"], c["nf"], H, VOL)
    for got, ref in ((divr, n_divr), (conc, n_conc), (gcx, n_gcx), (gcy, n_gcy), (lmat, n_lmat),
                     (mxx, m[:, 0, 0]), (myy, m[:, 1, 1])):
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())


def test_free_surface_detector_reads_two_inside_and_less_at_the_edge():
    """∇·r ≈ 2 (the dimension; 1.948 by the lattice quadrature at h = 1.3 dx) where the support is full,
    below the 1.6 threshold at an edge."""
    c = _cloud(n_side=13, jitter=0.0)
    divr = _geometry(c)[0]
    x, y = c["x"][:c["nf"]], c["y"][:c["nf"]]
    inner = (np.abs(x - x.mean()) < 3 * DX) & (np.abs(y - y.mean()) < 3 * DX)
    edge = y > y.max() - 0.1 * DX
    assert np.all(np.abs(divr[inner] - 2.0) < 0.06)
    assert np.all(divr[edge] < 1.6)


def test_renormalisation_inverts_the_moment_matrix_where_it_is_applied():
    c = _cloud()
    _, _, _, _, lmat, _ = _geometry(c)
    m = naive.geometry(c["x"], c["y"], c["nf"], H, VOL)[5]
    lm = lmat.reshape(-1, 2, 2)
    applied = ~np.all(np.isclose(lm, np.eye(2)), axis=(1, 2))
    assert applied.mean() > 0.6  # all but the cut corners and some edge particles
    prod = np.einsum("iab,ibc->iac", lm[applied], m[applied])
    np.testing.assert_allclose(prod, np.broadcast_to(np.eye(2), prod.shape), atol=1e-10)


def test_velocity_gradient_and_divergence_are_exact_for_a_linear_field_up_to_the_free_edges():
    c = _cloud(jitter=0.25, seed=3)
    nf = c["nf"]
    x, y = c["x"], c["y"]
    lmat = _geometry(c)[4]
    a = np.array([[0.7, -1.3], [2.1, 0.4]])
    u = 0.3 + a[0, 0] * x + a[0, 1] * y
    v = -0.2 + a[1, 0] * x + a[1, 1] * y
    empty = np.zeros(0)
    grad = operators.velocity_gradient(c["pairs"], nf, VOL, (x, y), (u, v), lmat,
                                       WallSurface(empty, empty, empty), 0, 0.0, DX)
    renorm = ~np.all(np.isclose(lmat, [1.0, 0.0, 0.0, 1.0]), axis=1)
    assert renorm.sum() > 0.6 * nf
    np.testing.assert_allclose(grad[renorm], np.broadcast_to(a.ravel(), (renorm.sum(), 4)), rtol=1e-9, atol=1e-9)
    div = operators.divergence(c["pairs"], nf, VOL, u, v, lmat)
    np.testing.assert_allclose(div[renorm], np.trace(a), rtol=1e-9)
    # and each agrees with the plain-NumPy gradient on any field
    f = np.random.default_rng(5).normal(size=x.size)
    ref = naive.granular_gradient(x, y, nf, H, VOL, f, lmat)
    grad_f = operators.velocity_gradient(c["pairs"], nf, VOL, (x, y), (f, f), lmat,
                                         WallSurface(empty, empty, empty), 0, 0.0, DX)
    np.testing.assert_allclose(grad_f[:, :2], ref, rtol=1e-10, atol=1e-10 * np.abs(ref).max())


def test_pressure_gradient_is_exact_for_a_linear_pressure_without_walls():
    c = _cloud(jitter=0.2, seed=7)
    nf = c["nf"]
    x, y = c["x"], c["y"]
    lmat = _geometry(c)[4]
    p = 50.0 + 3.0e3 * x - 9.81e3 * y
    empty = np.zeros(0)
    gpx, gpy = approximate.pressure_gradient(c["pairs"], nf, VOL, p, (np.zeros(nf),
                                           np.zeros(nf)), lmat, WallSurface(empty, empty, empty), 1e-4, 1000.0, np.zeros(nf, np.bool_))
    renorm = ~np.all(np.isclose(lmat, [1.0, 0.0, 0.0, 1.0]), axis=1)
    np.testing.assert_allclose(gpx[renorm], 3.0e3, rtol=1e-9)
    np.testing.assert_allclose(gpy[renorm], -9.81e3, rtol=1e-9)


def test_smoothed_gradient_and_shepard_average_match_the_kernel_means():
    c = _cloud(walls=True)
    nf = c["nf"]
    rng = np.random.default_rng(9)
    fx, fy = rng.normal(size=nf), rng.normal(size=nf)
    sx, sy = operators.smoothed_gradient(c["pairs"], nf, H, fx, fy)
    np.testing.assert_allclose(sx, naive.shepard(c["x"], c["y"], nf, H, fx), rtol=1e-12)
    np.testing.assert_allclose(sy, naive.shepard(c["x"], c["y"], nf, H, fy), rtol=1e-12)
    f = rng.normal(size=nf)
    np.testing.assert_allclose(operators.shepard_average(c["pairs"], nf, H, f),
                               naive.shepard(c["x"], c["y"], nf, H, f), rtol=1e-12)


def test_pair_kernel_matches_the_wendland_formulas():
    r = np.linspace(0.0, 2.2 * H, 301)
    w, gw = operators.pair_kernel(r, H)
    nw, ngw = naive.wendland(r, H)
    np.testing.assert_allclose(w, nw, rtol=1e-13, atol=1e-13 * nw.max())
    np.testing.assert_allclose(gw, ngw, rtol=1e-12, atol=1e-12 * np.abs(ngw).max())
    assert w[-1] == 0.0 and gw[-1] == 0.0 and gw[0] == 0.0
