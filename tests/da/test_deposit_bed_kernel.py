"""The deposit as bed seen through the SPH kernel (sph.deposit_gradient with
step.deposit_smoothing_length): the deposit is known per grid cell, so its kernel is never narrower
than a cell."""
import numpy as np

from granudep.da.sph import deposit_gradient
from granudep.da.step import deposit_smoothing_length

DXG = 1e-3
NG = 200


def flat_deposit(depth=0.01):
    return np.full(NG, depth * DXG)        # volume per cell of a flat deposit of that depth


def gradient(x, dep, L, qc=3.0):
    out = np.empty_like(x)
    deposit_gradient(x, np.ones_like(x), dep, DXG, L, qc, False, out)
    return out


def test_deposit_kernel_is_the_smoothing_length_or_the_cell():
    assert deposit_smoothing_length(2.5e-3, DXG) == 2.5e-3
    assert deposit_smoothing_length(1.2e-4, DXG) == DXG


def test_a_flat_deposit_pushes_no_particle_with_the_cell_wide_kernel():
    # particles everywhere between the cell centres, far from both ends of the grid
    x = np.linspace(0.05, 0.15, 1001)
    dep = flat_deposit()
    ok = gradient(x, dep, deposit_smoothing_length(1.2e-4, DXG))
    # a flat deposit of 1 cm: |dh_D/dx| well below 1 % of (depth / cell)
    assert np.max(np.abs(ok)) < 0.01 * 0.01 / DXG


def test_a_kernel_narrower_than_the_cell_sees_a_comb_of_spikes():
    # the failure the floor removes: L = 0.12 mm on the 1 mm grid (1D-A70 at N = 16 000)
    x = np.linspace(0.05, 0.15, 1001)
    narrow = gradient(x, flat_deposit(), 1.2e-4)
    assert np.max(np.abs(narrow)) > 10.0 * 0.01 / DXG
