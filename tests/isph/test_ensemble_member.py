"""Ensemble members: numerics.seed 0 is the lattice, seed k > 0 a reproducible perturbation of it."""
import numpy as np
import pytest

from granudep.config import ConfigError
from granudep.isph.api import run_isph
from granudep.isph.config import load_config
from granudep.isph.setup import build_particles, lattice, perturbed


def test_seed_zero_is_the_lattice_and_a_seed_moves_every_particle_by_about_jitter_dx():
    dx = 0.004
    x, y = lattice(0.0, 0.1, 0.0, 0.07, dx)
    px, py = perturbed(x, y, dx, 0, 0.01)
    assert px is x and py is y
    qx, qy = perturbed(x, y, dx, 3, 0.01)
    d = np.concatenate([qx - x, qy - y]) / dx
    inner = (x > x.min()) & (x < x.max()) & (y > y.min()) & (y < y.max())
    # the std of N(0, 0.01) over ~900 interior samples: within 10 % of 0.01 (the sampling error is ~3 %)
    assert np.std(np.concatenate([(qx - x)[inner], (qy - y)[inner]]) / dx) == pytest.approx(0.01, rel=0.1)
    assert np.all(np.abs(d) < 0.06)  # 6 sigma
    assert qx.min() >= x.min() and qx.max() <= x.max() and qy.min() >= y.min() and qy.max() <= y.max()
    rx, ry = perturbed(x, y, dx, 3, 0.01)
    assert np.array_equal(rx, qx) and np.array_equal(ry, qy)
    sx, _ = perturbed(x, y, dx, 4, 0.01)
    assert not np.array_equal(sx, qx)


def test_build_particles_perturbs_the_grains_only():
    base = build_particles(load_config("T22-A70", dx=0.01))
    member = build_particles(load_config("T22-A70", dx=0.01, numerics={"dx": 0.01, "seed": 2}))
    nf = base.nf
    assert member.nf == nf
    assert not np.array_equal(member.x[:nf], base.x[:nf])
    assert np.array_equal(member.x[nf:], base.x[nf:]) and np.array_equal(member.y[nf:], base.y[nf:])


def test_a_member_reruns_bit_for_bit_and_differs_from_the_lattice():
    kw = dict(dx=0.01, t_end=0.1)
    a = run_isph("T22-A70", numerics={"dx": 0.01, "t_end": 0.1, "seed": 5}, progress=None)
    b = run_isph("T22-A70", numerics={"dx": 0.01, "t_end": 0.1, "seed": 5}, progress=None)
    c = run_isph("T22-A70", **kw, progress=None)
    assert np.array_equal(a["x"].values, b["x"].values) and np.array_equal(a["u"].values, b["u"].values)
    assert not np.array_equal(a["x"].values, c["x"].values)
    assert "seed: 5" in a.attrs["config"]


@pytest.mark.parametrize("key, value", [("seed", -1), ("jitter", 0.5)])
def test_bad_member_keys_are_refused_with_the_key_and_the_range(key, value):
    with pytest.raises(ConfigError, match=f"numerics.{key}"):
        load_config("T22-A70", numerics={key: value})
