"""API, NetCDF output, CLI and input validation of the DA stage."""
import subprocess
import sys

import numpy as np
import pytest
import yaml

from granudep.config import ConfigError
from granudep.da.api import run_da
from granudep.da.config import resolve
from granudep.io import open_dataset, write_netcdf


@pytest.mark.parametrize("mapping, key", [
    ({"geometry": {"H0": -0.1}}, "geometry.H0: must be > 0"),
    ({"geometry": {"H0": "tall"}}, "geometry.H0: must be a number"),
    ({"geometry": {"theta_deg": 95.0}}, "geometry.theta_deg: must be >= 0.0 and < 90.0"),
    ({"geometry": {"theta_deg": 30.0}}, "geometry.theta_deg: must be <= material.phi_internal_deg"),
    ({"geometry": {"heigth": 0.1}}, "geometry.heigth: unknown key"),
    ({"numerics": {"cfl": 1.5}}, "numerics.cfl: must be > 0.0 and <= 1.0"),
    ({"deposition": {"x_inf_mode": "user"}}, "deposition.x_inf: required"),
    ({"deposition": {"x_inf_mode": "user", "x_inf": 0.1}}, "deposition.x_inf: must be > geometry.L0"),
    ({"deposition": {"ab_source": "user"}}, "deposition.A:"),
    ({"case": "bad name!"}, "case:"),
])
def test_bad_input_is_one_line_naming_the_key(mapping, key):
    data = {"case": "1D-A70", **mapping}
    with pytest.raises(ConfigError) as err:
        resolve(data)
    assert key in str(err.value)
    assert "\n" not in str(err.value)


def test_paper_coefficients_need_a_table5_case():
    with pytest.raises(ConfigError, match="deposition.ab_source"):
        resolve({"case": "mine"})
    cfg = resolve({"case": "mine", "deposition": {"ab_source": "user", "A": -0.03, "B": 0.04}})
    assert cfg.geometry.L0 == 0.2


def test_cli_bad_input_exits_2_with_one_line(tmp_path):
    cfg = tmp_path / "bad.yaml"
    cfg.write_text(yaml.safe_dump({"case": "bad", "geometry": {"H0": 0.0}}))
    out = subprocess.run([sys.executable, "-m", "granudep", "da", str(cfg)], capture_output=True, text=True)
    assert out.returncode == 2
    lines = [ln for ln in out.stderr.splitlines() if ln.strip()]
    assert lines == ["granudep: error: geometry.H0: must be > 0.0 (got 0.0)"]


def test_same_input_twice_gives_identical_output(small_case):
    kw = dict(x_inf_mode="user", x_inf=1.5)
    a = run_da(small_case, **kw)
    b = run_da(small_case, **kw)
    for name in ("x", "u", "h", "volume", "flow_depth", "deposit_depth", "front_position"):
        np.testing.assert_array_equal(a[name].values, b[name].values)


def test_dataset_contract_and_roundtrip(small_case, tmp_path):
    ds = run_da(small_case, deposition=False)
    for name in ("front_position", "runout", "flowing_volume", "deposited_volume", "flow_depth", "deposit_depth",
                 "x", "u", "h", "volume", "final_runout", "final_runout_norm", "flow_time", "flow_time_norm"):
        assert name in ds, name
    assert set(ds.flow_depth.dims) == {"time", "x_grid"} and set(ds.x.dims) == {"time", "particle"}
    for att in ("theta_deg", "L0", "H0", "a", "deposition", "front_depth_threshold", "x_inf"):
        assert isinstance(ds.attrs[att], (int, float)), att
    assert ds.attrs["deposition"] == 0 and ds.attrs["front_depth_threshold"] == pytest.approx(1.4e-3)
    assert ds.attrs["at_rest"] == 1
    assert float(ds.final_runout) == pytest.approx(float(ds.front_position[-1]) - 0.2)
    assert float(ds.runout[-1]) == pytest.approx(float(ds.final_runout))
    assert 0 < float(ds.flow_time) <= float(ds.time[-1])
    path = write_netcdf(ds, tmp_path / "run.nc")
    back = open_dataset(path)
    np.testing.assert_array_equal(back.x.values, ds.x.values)
    assert back.attrs["case"] == "1D-A70" and "numerics:" in back.attrs["config"]


def test_cli_runs_a_yaml_case_and_prints_the_summary(tmp_path):
    cfg = tmp_path / "mine.yaml"
    cfg.write_text(yaml.safe_dump({"case": "mine", "geometry": {"L0": 0.1, "H0": 0.05},
                                   "numerics": {"n_particles": 100},
                                   "output": {"dt_output": 0.05, "dx_grid": 2e-3}}))
    out_nc = tmp_path / "mine.nc"
    out = subprocess.run([sys.executable, "-m", "granudep", "da", str(cfg), "--no-deposition", "-o", str(out_nc)],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "final runout dL/L0 =" in out.stdout and "flow time" in out.stdout and "front =" in out.stdout
    ds = open_dataset(out_nc)
    assert ds.attrs["case"] == "mine" and ds.attrs["deposition"] == 0


def test_example_configs_resolve():
    from pathlib import Path
    for path in sorted(Path(__file__).parents[2].joinpath("config", "da").glob("*.yaml")):
        cfg = resolve(path)
        assert cfg.case


def test_verification_table_has_the_contract_columns(monkeypatch):
    from granudep.da import verification as v
    monkeypatch.setattr(v, "check_dam_break", lambda quick, *a: [])
    for name in ("check_kerswell", "check_savage_hutter", "check_coulomb_block", "check_deposition",
                 "check_energy_deposition"):
        monkeypatch.setattr(v, name, lambda quick: [])
    table = v.run_all(quick=True)
    assert list(table.columns) == ["check", "quantity", "value", "reference", "error", "tolerance", "passed", "note"]
    assert len(table) == 2 and table.passed.all()
