"""The DA output carries the robust front measures of granudep.front, read like the 2D runs."""
import numpy as np

from granudep.da.api import run_da
from granudep.front import front_measures


def test_da_file_has_the_2d_front_measures():
    ds = run_da({"case": "tiny", "geometry": {"L0": 0.05, "H0": 0.02, "theta_deg": 10.0},
                 "numerics": {"n_particles": 40, "t_end": 0.1}, "output": {"dt_output": 0.025}},
                deposition=False)
    for k in ("front_2d", "front_5mm", "front_v99", "front_tail"):
        assert k in ds and f"final_{k}" in ds
    # the default front of the DA run is the 2 d attached front of the shared rule
    np.testing.assert_allclose(ds["front_2d"].values, ds["front_position"].values)
    # recomputed from the stored profile on the grid, at the last output
    dxg = float(ds.attrs["dx_grid"])
    depth = ds["flow_depth"].values[-1] + ds["deposit_depth"].values[-1]
    m = front_measures(np.arange(depth.size + 1) * dxg, depth, float(ds.attrs["d"]))
    for k, v in m.items():
        assert float(ds[f"final_{k}"].values) == v
    assert float(ds["final_front_v99"].values) <= float(ds["final_front_tail"].values)
    L0 = float(ds.attrs["L0"])
    assert float(ds["final_runout_norm_v99"].values) == (float(ds["final_front_v99"].values) - L0) / L0
