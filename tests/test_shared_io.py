"""Atomic NetCDF writes and the CF/provenance data contract."""
from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from granudep.io import ContractError, open_dataset, provenance, var, write_netcdf, write_text


def _dataset():
    ds = xr.Dataset({"front_position": var(np.linspace(0.2, 0.5, 4), ("time",), "m", "front position")},
                    coords={"time": var(np.arange(4.0), ("time",), "s", "time")})
    return provenance(ds, case="T22-A70", config_yaml="a: 1\n", command="test")


def test_roundtrip_has_contract_attributes(tmp_path):
    path = write_netcdf(_dataset(), tmp_path / "out" / "run.nc")
    back = open_dataset(path)
    assert back.attrs["Conventions"] == "CF-1.10" and back.attrs["case"] == "T22-A70"
    assert back.attrs["config"] == "a: 1\n" and "granudep" in back.attrs["history"]
    assert back["front_position"].attrs["units"] == "m"
    assert back["time"].encoding.get("_FillValue") is None  # no NaN fill on coordinates
    np.testing.assert_array_equal(back["front_position"].values, np.linspace(0.2, 0.5, 4))
    assert [p.name for p in path.parent.iterdir()] == ["run.nc"]  # no temporaries left


def test_missing_units_is_refused_and_nothing_written(tmp_path):
    ds = _dataset()
    ds["bad"] = xr.DataArray(np.zeros(4), dims="time", attrs={"long_name": "no units"})
    with pytest.raises(ContractError, match="'bad' lacks the 'units'"):
        write_netcdf(ds, tmp_path / "run.nc")
    assert list(tmp_path.iterdir()) == []


def test_failed_write_leaves_no_file(tmp_path, monkeypatch):
    ds = _dataset()

    def boom(self, *args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", boom)
    with pytest.raises(OSError):
        write_netcdf(ds, tmp_path / "run.nc")
    assert list(tmp_path.iterdir()) == []


def test_write_text_replaces_atomically(tmp_path):
    p = tmp_path / "t.csv"
    write_text("a\n", p)
    write_text("b\n", p)
    assert p.read_text() == "b\n" and len(list(tmp_path.iterdir())) == 1


def test_written_files_get_umask_permissions(tmp_path):
    import os
    umask = os.umask(0o022)
    try:
        p = write_text("x\n", tmp_path / "perm.txt")
    finally:
        os.umask(umask)
    assert (p.stat().st_mode & 0o777) == 0o644
