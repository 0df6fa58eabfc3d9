"""Pressure filters of the friction law (rheology.pressure_filter): kernels against plain NumPy."""
import numpy as np
import pytest

from granudep.isph import operators
from granudep.isph.bundles import pairs_of


def _cloud(n_side=14, jitter=0.2, seed=0, walls=True):
    rng = np.random.default_rng(seed)
    dx = 0.01
    g = (np.arange(n_side) + 0.5) * dx
    gx, gy = np.meshgrid(g, g)
    x = gx.ravel() + rng.uniform(-jitter, jitter, gx.size) * dx
    y = gy.ravel() + rng.uniform(-jitter, jitter, gy.size) * dx
    nf = x.size
    if walls:                                    # wall particles below y = 0: never in the averages
        wx, wy = np.meshgrid((np.arange(-3, n_side + 3) + 0.5) * dx, -(np.arange(3) + 0.5) * dx)
        x, y = np.concatenate((x, wx.ravel())), np.concatenate((y, wy.ravel()))
    h = 1.3 * dx
    pairs = pairs_of(x, y, nf, 2.0 * h, 0.0, h)
    return dict(x=x, y=y, nf=nf, h=h, start=pairs.start, nbr=pairs.nbr, rx=pairs.rx, ry=pairs.ry, wk=pairs.wk,
                pairs=pairs)


def _naive(c, f, order):
    """Per particle: weighted least squares (order 1) or weighted mean (order 0), NumPy."""
    w0 = 7.0 / (4.0 * np.pi * c["h"] ** 2)
    out = np.empty(c["nf"])
    for i in range(c["nf"]):
        q = np.arange(c["start"][i], c["start"][i + 1])
        j = c["nbr"][q]
        keep = j < c["nf"]
        q, j = q[keep], j[keep]
        w = np.concatenate(([w0], c["wk"][q]))
        fv = np.concatenate(([f[i]], f[j]))
        if order == 0:
            out[i] = np.sum(w * fv) / np.sum(w)
            continue
        dxv = np.concatenate(([0.0], c["x"][j] - c["x"][i]))
        dyv = np.concatenate(([0.0], c["y"][j] - c["y"][i]))
        a = np.stack((np.ones_like(dxv), dxv, dyv), axis=1) * np.sqrt(w)[:, None]
        out[i] = np.linalg.lstsq(a, fv * np.sqrt(w), rcond=None)[0][0]
    return out


@pytest.mark.parametrize("walls", [True, False])
def test_mls_average_equals_the_weighted_least_squares_fit(walls):
    c = _cloud(walls=walls)
    f = np.random.default_rng(4).normal(size=c["x"].size)
    got = operators.mls_linear_average(c["pairs"], c["nf"], c["h"], f)
    assert np.allclose(got, _naive(c, f, 1), rtol=1e-9, atol=1e-9)


def test_mls_average_is_exact_for_linear_fields_up_to_the_edges():
    c = _cloud()
    f = 3.0 + 200.0 * c["x"] - 500.0 * c["y"]            # a hydrostatic-like linear pressure
    got = operators.mls_linear_average(c["pairs"], c["nf"], c["h"], f)
    assert np.abs(got - f[:c["nf"]]).max() < 1e-10 * np.abs(f).max()
    shep = operators.shepard_average(c["pairs"], c["nf"], c["h"], f)
    assert np.abs(shep - f[:c["nf"]]).max() > 1e-3 * np.abs(f).max()   # the Shepard mean is not


def test_filters_damp_a_layer_to_layer_alternation():
    c = _cloud(n_side=20, jitter=0.0)
    alt = np.where(np.round(c["y"] / 0.01 - 0.5) % 2 == 0, 1.0, -1.0)
    for got in (operators.mls_linear_average(c["pairs"], c["nf"], c["h"], alt),
                operators.shepard_average(c["pairs"], c["nf"], c["h"], alt)):
        inner = (c["y"][:c["nf"]] > 0.03) & (c["y"][:c["nf"]] < 0.17) & (c["x"][:c["nf"]] > 0.03) & (c["x"][:c["nf"]] < 0.17)
        assert np.abs(got[inner]).max() < 0.3


def test_shepard_average_equals_the_weighted_mean():
    c = _cloud()
    f = np.random.default_rng(5).normal(size=c["x"].size)
    assert np.allclose(operators.shepard_average(c["pairs"], c["nf"], c["h"], f), _naive(c, f, 0),
                       rtol=1e-12, atol=1e-12)
