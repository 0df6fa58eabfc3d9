"""Cell-linked neighbour list against a brute-force search, open and periodic in x, with and
without a dense pile (a particle with far more neighbours than on the lattice)."""
import numpy as np
import pytest

from granudep.isph.neighbours import build_neighbours


def _brute(x, y, nf, radius, period):
    out = []
    for i in range(nf):  # test reference only
        dx = x[i] - x
        if period > 0:
            dx = (dx + 0.5 * period) % period - 0.5 * period
        dy = y[i] - y
        d2 = dx * dx + dy * dy
        sel = np.flatnonzero(d2 < radius * radius)
        sel = sel[sel != i]
        out.append({int(j): (dx[j], dy[j]) for j in sel})
    return out


@pytest.mark.parametrize("period, pile", [(0.0, 0), (1.0, 0), (0.0, 90), (1.0, 90)])
def test_neighbour_list_matches_brute_force(period, pile):
    rng = np.random.default_rng(5)
    dx = 0.02
    g = np.arange(0.0, 1.0, dx)
    xx, yy = np.meshgrid(g, np.arange(0.0, 0.2, dx))
    x = xx.ravel() + 0.3 * dx * rng.standard_normal(xx.size)
    y = yy.ravel() + 0.3 * dx * rng.standard_normal(xx.size)
    if period > 0:
        x %= period
    # a pile: 90 particles within one support (about 21 neighbours on the lattice)
    x = np.concatenate([x, 0.5 + 0.01 * dx * np.arange(pile)])
    y = np.concatenate([y, np.full(pile, 0.1)])
    nf = x.size - 30  # the last 30 are "wall" particles: neighbours, not rows
    radius = 2.6 * dx
    start, nbr, rx, ry, rr = build_neighbours(x, y, nf, radius, period)
    ref = _brute(x, y, nf, radius, period)
    counts = np.diff(start)
    assert counts.max() > 90 if pile else counts.max() < 40
    for i in range(nf):
        got = nbr[start[i]:start[i + 1]]
        assert sorted(got.tolist()) == sorted(ref[i]), i
        exp = np.array([ref[i][int(j)] for j in got]).reshape(-1, 2)
        assert np.allclose(rx[start[i]:start[i + 1]], exp[:, 0], rtol=0, atol=1e-15)
        assert np.allclose(ry[start[i]:start[i + 1]], exp[:, 1], rtol=0, atol=1e-15)
    assert np.allclose(rr, np.hypot(rx, ry), rtol=1e-15, atol=0)
