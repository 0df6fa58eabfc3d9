"""Particle shifting next to the free surface (physics.surface_band, physics.shifting)."""
import numpy as np

from granudep.isph import operators, shifting
from granudep.isph import verification as v
from granudep.isph.config import load_config
from granudep.isph.bundles import Pairs, pairs_of
from granudep.isph.stepper import IsphSolver


def _layer(dx):
    """The verification suite's periodic layer."""
    return IsphSolver(load_config(v.layer_config(30.0, 0.02, dx)))


def _layer_terms(s):
    nf = s.nf
    pairs = pairs_of(s.x, s.y, nf, s.radius, s.period, s.h)
    divr, conc, gcx, gcy, lmat, _ = operators.geometry_terms(pairs, nf, s.h, s.vol)
    fs = divr < s.cfg.numerics.free_surface_threshold
    return pairs, gcx, gcy, fs


def test_surface_band_covers_the_layers_with_a_truncated_support():
    """On a lattice (h = 1.3 dx, support 2.6 dx) only the top layer is free-surface; layers 2 and 3
    (1 and 2 dx below it) get α = 1, deeper layers 0: the band is the truncated support."""
    dx = 0.002
    s = _layer(dx)
    pairs, _, _, fs = _layer_terms(s)
    layer = np.round((0.02 - dx / 2 - s.y[:s.nf]) / dx).astype(int)   # 0 = top
    assert fs[layer == 0].all() and not fs[layer > 0].any()
    alpha = shifting.surface_band(pairs, s.nf, fs, s.h, 2.0 * dx)
    assert np.allclose(alpha[layer <= 2], 1.0) and np.allclose(alpha[layer >= 3], 0.0)


def test_surface_band_is_continuous_at_the_edge_of_the_support():
    """A free-surface neighbour entering the support from its edge contributes W → 0: α does not jump."""
    h, dx = 1.3, 1.0
    for r in (2 * h - 1e-3, 2 * h - 1e-6):
        start = np.array([0, 1, 1])
        nbr = np.array([1])
        wk, gw = operators.pair_kernel(np.array([r]), h)
        pairs = Pairs(start, nbr, np.array([-r]), np.zeros(1), np.array([r]), wk, gw)
        alpha = shifting.surface_band(pairs, 2, np.array([False, True]), h, 2.0 * dx)
        assert 0.0 < alpha[0] < 1e-5


def test_shift_below_the_surface_loses_its_normal_part():
    """Moving layer: with 'surface' (the normal part removed on free-surface particles only) the
    truncated support of the second layer (∇C ≠ 0 one dx under the surface) pushes it up into the
    surface layer at every step; with the band it is shifted along the surface only."""
    dx = 0.002
    s = _layer(dx)
    pairs, gcx, gcy, fs = _layer_terms(s)
    s.u[:] = 1.0
    ncx, ncy = operators.smoothed_gradient(pairs, s.nf, s.h, gcx, gcy)
    layer = np.round((0.02 - dx / 2 - s.y[:s.nf]) / dx).astype(int)
    dt = 1e-4
    alpha = shifting.surface_band(pairs, s.nf, fs, s.h, 2.0 * dx)
    _, sy_band = shifting.shifting(s.nf, (gcx, gcy), (s.u, s.v), alpha, s.h, dt, 2.0, dx, (ncx, ncy))
    _, sy_surf = shifting.shifting(s.nf, (gcx, gcy), (s.u, s.v), fs.astype(float), s.h, dt, 2.0, dx, (ncx, ncy))
    below = layer == 1
    assert np.all(sy_surf[below] > 1e-3 * dx)          # pushed up into the surface layer
    assert np.abs(sy_band[below]).max() < 1e-9 * dx
