"""The recorded deposit depth is a kernel estimate: no gaps between sparse tip particles, volume kept."""
import numpy as np

from granudep.da.driver import smooth_deposit


def test_sparse_deposit_has_no_gaps_and_conserves_volume():
    dxg, L = 1e-3, 4e-3
    dep = np.zeros(400)
    dep[[0, 2, 100, 104, 109, 115, 300]] = [2e-6, 1e-6, 1e-6, 1e-6, 1e-6, 1e-6, 3e-6]  # m² per cell
    h_d = smooth_deposit(dep, L, qc=3.0, dxg=dxg)
    assert abs(h_d.sum() * dxg - dep.sum()) <= 1e-15 * dep.sum() + 1e-22  # wall reflection keeps volume
    assert (h_d[100:116] > 0.2 * h_d[100:116].max()).all()  # tip particles 4-6 cells apart: no gaps
    assert h_d[200] == 0.0  # but no spreading beyond the kernel support (3 L_s)
