"""μ(I) laws, the Barker–Gray well-posedness test and the partial regularisation."""
import math

import numpy as np
import pytest

from granudep.isph.viscous import mu_i_viscosity
from granudep.isph.rheology import (friction, ill_posed_bounds, mu_extended, regularisation_constant,
                                    regularised_viscosity, well_posedness)

MU_S = math.tan(math.radians(25.5))
MU_2, I0 = 0.73, 0.279


def test_extended_law_is_eq5_for_mu_inf_zero():
    i = np.logspace(-6, 1, 50)
    eq5 = MU_S + (MU_2 - MU_S) / (I0 / i + 1.0)
    assert np.allclose(mu_extended(i, MU_S, MU_2, 0.0, I0), eq5, rtol=1e-14)


def test_well_posed_band_of_the_glass_beads():
    """With the paper's glass beads (μ_s = tan 25.5°, μ_2 = 0.73, I_0 = 0.279) the law is well posed
    only for 0.0554 < I < 0.3965; C changes sign at both ends."""
    lo, hi = ill_posed_bounds(MU_S, MU_2, 0.0, I0)
    assert lo == pytest.approx(0.05539, rel=1e-3) and hi == pytest.approx(0.39649, rel=1e-3)
    assert well_posedness(0.5 * lo, MU_S, MU_2, 0.0, I0) > 0 > well_posedness(2 * lo, MU_S, MU_2, 0.0, I0)
    assert well_posedness(2 * hi, MU_S, MU_2, 0.0, I0) > 0


def test_regularised_friction_is_continuous_and_below_the_band_well_behaved():
    lo, _ = ill_posed_bounds(MU_S, MU_2, 0.05, I0)
    a = regularisation_constant(lo, MU_S, MU_2, 0.05, I0, 1.9)
    below = friction(lo * (1 - 1e-9), MU_S, MU_2, 0.05, I0, lo, 1.9, a)
    above = friction(lo * (1 + 1e-9), MU_S, MU_2, 0.05, I0, lo, 1.9, a)
    assert below == pytest.approx(above, rel=1e-6)
    i = np.logspace(-8, math.log10(lo) - 1e-6, 200)
    mu = np.array([friction(x, MU_S, MU_2, 0.05, I0, lo, 1.9, a) for x in i])
    assert np.all(np.diff(mu) > 0)          # monotone in I, μ → 0 as I → 0
    assert mu[0] < 0.3


def _grad(n, rng):
    g = rng.normal(scale=5.0, size=(n, 4))
    g[:3] = 0.0                             # a few particles at rest
    return g


def test_regularised_kernel_without_regularisation_matches_the_paper_kernel():
    """i_n1 = 0 and μ_∞ = 0: the same η as :func:`mu_i_viscosity` wherever that one is not at its cap."""
    rng = np.random.default_rng(3)
    n = 200
    grad = _grad(n, rng)
    p = rng.uniform(-10.0, 2000.0, n)
    e1, g1 = mu_i_viscosity(grad, p, 7e-4, 2500.0, MU_S, MU_2, I0, 1e-3, 5e3)
    e2, g2 = regularised_viscosity(grad, p, 7e-4, 2500.0, (MU_S, MU_2, 0.0, I0, 0.0, 1.9, 1.0), (1e-3, 5e3))
    assert np.array_equal(g1, g2)
    assert np.allclose(e1, e2, rtol=1e-12, atol=0.0)


def test_regularised_kernel_against_numpy():
    rng = np.random.default_rng(4)
    n = 300
    grad = _grad(n, rng) * 0.01
    p = rng.uniform(1.0, 2000.0, n)
    lo, _ = ill_posed_bounds(MU_S, MU_2, 0.0, I0)
    a = regularisation_constant(lo, MU_S, MU_2, 0.0, I0, 1.9)
    eta, gd = regularised_viscosity(grad, p, 7e-4, 2500.0, (MU_S, MU_2, 0.0, I0, lo, 1.9, a), (1e-3, 5e3))
    dxy = 0.5 * (grad[:, 1] + grad[:, 2])
    gref = np.sqrt(2.0 * (grad[:, 0] ** 2 + grad[:, 3] ** 2 + 2.0 * dxy ** 2))
    i = gref * 7e-4 / np.sqrt(p / 2500.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        mu = np.where(i < lo, np.sqrt(1.9 / np.log(a / i)), mu_extended(i, MU_S, MU_2, 0.0, I0))
        ref = np.clip(np.where(gref > 0, mu * p / gref, 5e3), 1e-3, 5e3)
    assert np.allclose(gd, gref, rtol=1e-14)
    assert np.allclose(eta, ref, rtol=1e-12)
