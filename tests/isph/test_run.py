"""End-to-end runs: output contract, CLI, blow-up handling."""
import math

import numpy as np
import pytest
import xarray as xr

from granudep.cli import main
from granudep.isph.api import run_isph
from granudep.isph.solver import IsphBlowUp

CONTRACT_VARS = ["x", "y", "u", "v", "pressure", "viscosity", "free_surface", "front_position",
                 "kinetic_energy", "final_front_position", "time_to_rest"]
CONTRACT_ATTRS = ["theta_deg", "L0", "H0", "dx", "smoothing_length", "particle_volume", "rho", "rho_s", "d",
                  "mu_s", "mu_2", "I0", "front_depth_threshold"]


def test_short_collapse_writes_the_contract(tmp_path):
    out = tmp_path / "T22-A70.nc"
    rc = main(["isph", "T22-A70", "--dx", "0.01", "--t-end", "0.1", "-o", str(out)])
    assert rc == 0
    ds = xr.open_dataset(out)
    for name in CONTRACT_VARS:
        assert name in ds, name
        assert "units" in ds[name].attrs and "long_name" in ds[name].attrs
    for a in CONTRACT_ATTRS:
        assert isinstance(ds.attrs[a], (float, np.floating)), a
    assert ds.attrs["smoothing_length"] == pytest.approx(1.3 * 0.01)
    assert ds.sizes["time"] == 11  # 0.01 s snapshots incl. t = 0
    assert np.allclose(np.diff(ds.time), 0.01)
    # the column starts to collapse: the front advances beyond the gate, mass is conserved
    assert ds.front_position[0] == pytest.approx(0.2, abs=1e-9)
    assert ds.front_position[-1] > 0.2
    assert ds.kinetic_energy[-1] > 0
    assert ds.x.dtype == np.float32 and ds.free_surface.dtype == np.int8


def test_blow_up_raises_with_time_step_position_and_keeps_partial_output(tmp_path):
    out = tmp_path / "escape.nc"
    with pytest.raises(IsphBlowUp, match=r"left the domain at t=.* step \d+: \(x, y\)"):
        run_isph("T22-A70", output=out, dx=0.01, domain_length=0.21, t_end=1.0)
    ds = xr.open_dataset(out)
    assert ds.attrs["status"].startswith("failed: particle")
    assert ds.sizes["time"] >= 1
    assert math.isnan(float(ds.time_to_rest))


def test_cli_bad_input_exits_2(capsys):
    assert main(["isph", "T22-A70", "--dx", "-1"]) == 2
    assert "numerics.dx" in capsys.readouterr().err


def test_vtk_export(tmp_path):
    nc = tmp_path / "r.nc"
    run_isph("T22-A70", output=nc, dx=0.02, t_end=0.02)
    assert main(["isph-vtk", str(nc), "-o", str(tmp_path / "vtk")]) == 0
    files = sorted((tmp_path / "vtk").glob("*.vtp"))
    assert len(files) == 3
    text = files[0].read_text()
    assert "<PolyData>" in text and 'Name="pressure"' in text
    assert (tmp_path / "vtk" / "T22-A70.pvd").read_text().count("<DataSet") == 3
