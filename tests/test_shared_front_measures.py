"""Robust front measures: the same rules for 2D and DA depth profiles."""
import numpy as np

from granudep.front import front_measures, tail_extent, volume_front


def test_volume_front_of_a_uniform_layer_is_the_quantile():
    edges = np.linspace(0.0, 10.0, 11)
    depth = np.ones(10)
    assert np.isclose(volume_front(edges, depth, 0.01), 9.9)
    assert np.isclose(volume_front(edges, depth, 0.25), 7.5)


def test_volume_front_ignores_how_thin_a_tail_is():
    """A sheet carrying 0.5 % of the volume moves the 1 % volume front less than one cell,
    while the zero-threshold tail extent jumps to its end."""
    edges = np.linspace(0.0, 20.0, 201)
    depth = np.where(edges[:-1] < 5.0, 0.02, 0.0)
    base = volume_front(edges, depth)
    thin = depth.copy()
    thin[(edges[:-1] >= 5.0) & (edges[:-1] < 15.0)] = 0.02 * 0.005 * 5.0 / 10.0  # 0.5 % of the volume
    assert abs(volume_front(edges, thin) - base) < 0.1
    assert np.isclose(tail_extent(edges, thin), 15.0)
    m = front_measures(edges, thin, d=0.0007)
    assert np.isclose(m["front_2d"], 5.0) and np.isclose(m["front_5mm"], 5.0)
    assert np.isclose(m["front_tail"], 15.0)


def test_front_measures_empty_profile_is_nan():
    edges = np.linspace(0.0, 1.0, 5)
    m = front_measures(edges, np.zeros(4), d=0.001)
    assert all(np.isnan(v) for v in m.values())
