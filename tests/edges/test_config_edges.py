"""Config edges: paper-case identity, section overrides, YAML 1.2 numbers, impossible inputs."""
from __future__ import annotations

import subprocess
import sys

import pytest

import granudep
from granudep.config import ConfigError, load_yaml, yaml12_numbers
from granudep.da.config import resolve
from granudep.isph.config import load_config


# --- a paper case name survives no change of geometry or material --------------------------------
@pytest.mark.parametrize("overrides, key", [
    ({"theta_deg": 16.0}, "geometry.theta_deg"),
    ({"H0": 0.05}, "geometry.H0"),
    ({"phi_internal_deg": 24.0}, "material.phi_internal_deg"),
    ({"phi_basal_deg": 20.0}, "wall.phi_basal_deg"),
])
def test_isph_paper_case_with_changed_geometry_or_material_is_refused(overrides, key):
    with pytest.raises(ConfigError, match=rf"^{key}: .* changes the paper case 'T22-A70'"):
        load_config("T22-A70", **overrides)


def test_isph_paper_case_yaml_with_changed_geometry_is_refused(tmp_path):
    f = tmp_path / "c.yaml"
    f.write_text("case: T22-A70\ngeometry: {theta_deg: 16}\n")
    with pytest.raises(ConfigError, match="geometry.theta_deg: 16.0 changes the paper case"):
        load_config(f)
    f.write_text("case: my-T22\ngeometry: {theta_deg: 16, L0: 0.2, H0: 0.14}\n")
    assert load_config(f).geometry.theta_deg == 16.0  # same geometry under its own name runs


def test_isph_paper_case_numerics_may_change():
    cfg = load_config("T22-A70", dx=0.01, t_end=1.0)
    assert cfg.case == "T22-A70" and cfg.numerics.dx == 0.01


@pytest.mark.parametrize("overrides, key", [
    ({"H0": 0.05}, "geometry.H0"),
    ({"theta_deg": 16.0}, "geometry.theta_deg"),
    ({"phi_internal_deg": 27.5}, "material.phi_internal_deg"),
])
def test_da_paper_case_with_changed_geometry_is_refused(overrides, key):
    with pytest.raises(ConfigError, match=rf"^{key}: .* changes the paper case '1D-A70'"):
        resolve("1D-A70", **overrides)


def test_da_ab_source_paper_refused_for_a_changed_geometry(tmp_path):
    f = tmp_path / "c.yaml"
    f.write_text("case: my-col\ngeometry: {L0: 0.2, H0: 0.05, theta_deg: 22}\ndeposition: {ab_source: paper}\n")
    with pytest.raises(ConfigError, match="deposition.ab_source: 'paper' needs a Table 5 case"):
        resolve(f)


# --- granudep.monitor stays callable ---------------------------------------------------------------
def test_monitor_entry_point_survives_subpackage_imports():
    code = ("import granudep, importlib; importlib.import_module('granudep.monitor.api');"
            "importlib.import_module('granudep.monitor.cli'); import granudep.monitor.sections;"
            "assert callable(granudep.monitor), granudep.monitor")
    subprocess.run([sys.executable, "-c", code], check=True)



# --- section overrides in run_da and run_isph ------------------------------------------------------
def test_resolve_takes_the_deposition_section():
    cfg = resolve("1D-A70", deposition={"ab_source": "user", "A": -0.1, "B": 0.1})
    assert cfg.deposition.enabled and cfg.deposition.ab_source == "user" and cfg.deposition.A == -0.1
    assert not resolve("1D-A70", deposition={"enabled": False}).deposition.enabled
    with pytest.raises(ConfigError, match="deposition.bogus: unknown key"):
        resolve("1D-A70", deposition={"bogus": 1})
    with pytest.raises(ConfigError, match="^deposition: must be true/false or a mapping"):
        resolve("1D-A70", deposition="yes")


def test_run_da_uses_the_deposition_section(monkeypatch):
    import granudep.da.api as api
    seen = {}

    def fake_coefficients(cfg):
        seen["cfg"] = cfg
        raise ConfigError("stop here")

    monkeypatch.setattr(api, "coefficients", fake_coefficients)
    monkeypatch.setattr(api, "_simulate", lambda *a, **k: (_ for _ in ()).throw(AssertionError("no run")))
    with pytest.raises(ConfigError, match="stop here"):
        granudep.run_da("1D-A70", deposition={"ab_source": "user", "A": -0.2, "B": 0.3})
    assert seen["cfg"].deposition.A == -0.2 and seen["cfg"].deposition.ab_source == "user"


def test_isph_section_overrides():
    cfg = load_config("T22-A70", numerics={"dx": 0.01, "cfl": 0.1}, output={"dt_output": 0.05})
    assert cfg.numerics.dx == 0.01 and cfg.numerics.cfl == 0.1 and cfg.output.dt_output == 0.05
    with pytest.raises(ConfigError, match="numerics.dxx: unknown key"):
        load_config("T22-A70", numerics={"dxx": 0.01})
    with pytest.raises(ConfigError, match="^numerics: must be a mapping"):
        load_config("T22-A70", numerics=0.01)


# --- impossible inputs --------------------------------------------------------------------------
def test_isph_slope_steeper_than_friction_is_refused():
    with pytest.raises(ConfigError, match=r"^geometry.theta_deg: must be < material.phi_internal_deg = 25.5"):
        load_config({"case": "steep", "geometry": {"theta_deg": 30.0}})
    for law in ("coulomb", "stress_limited"):  # the bed laws that use phi_B
        with pytest.raises(ConfigError, match=r"^geometry.theta_deg: must be < wall.phi_basal_deg = 20.0"):
            load_config({"case": "steep", "geometry": {"theta_deg": 22.0},
                         "wall": {"phi_basal_deg": 20.0, "slip": law}})
    # the Navier default and the no-slip bed do not use phi_B: the material's friction angle is the limit
    assert load_config({"case": "steep", "geometry": {"theta_deg": 22.0},
                        "wall": {"phi_basal_deg": 20.0}}).wall.slip == "navier"
    assert load_config({"case": "steep", "geometry": {"theta_deg": 22.0},
                        "wall": {"phi_basal_deg": 20.0, "slip": "no_slip"}}).wall.slip == "no_slip"


def test_da_slope_steeper_than_basal_friction_is_refused():
    data = {"case": "steep", "geometry": {"theta_deg": 24.0},
            "material": {"phi_basal_deg": 20.0, "phi_internal_deg": 30.0},
            "numerics": {"earth_pressure": "savage_hutter"}}
    with pytest.raises(ConfigError, match=r"^geometry.theta_deg: must be < material.phi_basal_deg = 20.0"):
        resolve(data, deposition=False)


def test_da_x_inf_without_user_mode_is_refused():
    with pytest.raises(ConfigError, match="^deposition.x_inf: used only with deposition.x_inf_mode 'user'"):
        resolve("1D-A70", x_inf=1.0)
    assert resolve("1D-A70", x_inf=1.0, x_inf_mode="user").deposition.x_inf == 1.0


def test_empty_yaml_is_refused(tmp_path):
    f = tmp_path / "empty.yaml"
    f.write_text("# nothing\n")
    with pytest.raises(ConfigError, match="the config file is empty"):
        load_config(f)
    with pytest.raises(ConfigError, match="the config file is empty"):
        resolve(f)


def test_non_utf8_yaml_is_one_line(tmp_path):
    f = tmp_path / "latin1.yaml"
    f.write_bytes("case: caf\xe9\n".encode("latin-1"))
    with pytest.raises(ConfigError, match="not a UTF-8 text file") as exc:
        load_yaml(f)
    assert "\n" not in str(exc.value)


# --- YAML 1.2 numbers ------------------------------------------------------------------------------
def test_yaml_reads_numbers_as_yaml_1_2(tmp_path):
    f = tmp_path / "n.yaml"
    f.write_text("a: 5.0e4\nb: 1e-3\nc: -2E+2\nd: 1\ne: '5.0e4'\nf: 0.5\ng: 1.5e3x\n")
    d = load_yaml(f)
    assert d["a"] == 5.0e4 and isinstance(d["a"], float)
    assert d["b"] == 1e-3 and d["c"] == -200.0
    assert d["d"] == 1 and isinstance(d["d"], int)
    assert d["e"] == "5.0e4" and d["f"] == 0.5 and d["g"] == "1.5e3x"


def test_isph_yaml_with_eta_max_5e4(tmp_path):
    f = tmp_path / "c.yaml"
    f.write_text("case: mine\nrheology: {eta_max: 5.0e4, eta_min: 1e-3}\n")
    cfg = load_config(f)
    assert cfg.rheology.eta_max == 5.0e4 and cfg.rheology.eta_min == 1e-3


def test_yaml12_numbers_converts_what_yaml11_left_as_strings():
    assert yaml12_numbers({"a": ["5.0e4", "x", "1e-3", "12"], "b": {"c": "2e5"}}) == \
        {"a": [5.0e4, "x", 1e-3, "12"], "b": {"c": 2e5}}


def test_monitor_called_twice_in_one_session():
    import pathlib
    sys.path.insert(0, str(pathlib.Path(__file__).parents[1] / "monitor"))
    from monitor_synth import ramp_run
    run = ramp_run(case="T22-A70", dx=0.004)
    a = granudep.monitor(run)
    b = granudep.monitor(run, width_factor=3.0)
    assert a.sizes["section"] == b.sizes["section"] == 11 and b.attrs["width_factor"] == 3.0


# --- outputs checked before work; unreadable inputs one line ---------------------------------------
def _read_only_folder(tmp_path):
    """A folder nobody can write to (root ignores permissions: then /proc, which no one can)."""
    import os
    if os.geteuid() != 0:
        d = tmp_path / "ro"
        d.mkdir()
        d.chmod(0o500)
        return d
    return __import__("pathlib").Path("/proc/granudep-no-such-folder")


@pytest.mark.parametrize("argv", [
    ["isph", "T22-A70", "--dx", "0.02", "--t-end", "0.02"],
    ["da", "1D-A70", "--no-deposition", "--n-particles", "40"],
])
def test_run_commands_check_the_output_before_any_work(tmp_path, capsys, monkeypatch, argv):
    from granudep.cli import main
    import granudep.isph.api as iapi
    import granudep.da.api as dapi
    monkeypatch.setattr(iapi, "run", lambda *a, **k: (_ for _ in ()).throw(AssertionError("ran")))
    monkeypatch.setattr(dapi, "_simulate", lambda *a, **k: (_ for _ in ()).throw(AssertionError("ran")))
    ro = _read_only_folder(tmp_path)
    assert main(argv + ["-o", str(ro / "out.nc")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("granudep: error: output: cannot write to "), err
    assert main(argv + ["-o", str(tmp_path / "out.txt")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "out.txt must end in .nc" in err[0], err


def test_run_isph_api_checks_the_output_before_the_run(tmp_path, monkeypatch):
    import granudep.isph.api as iapi
    monkeypatch.setattr(iapi, "run", lambda *a, **k: (_ for _ in ()).throw(AssertionError("ran")))
    with pytest.raises(ConfigError, match="cannot write to"):
        granudep.run_isph("T22-A70", output=_read_only_folder(tmp_path) / "x.nc", dx=0.02)


@pytest.mark.parametrize("content", [b"", b"hello, this is text\n", None])
@pytest.mark.parametrize("command", ["monitor", "monitor-wm", "regress", "isph-vtk"])
def test_unreadable_netcdf_inputs_are_one_line(tmp_path, capsys, content, command):
    from granudep.cli import main
    from granudep.io import write_netcdf
    bad = tmp_path / "bad.nc"
    if content is None:  # a truncated NetCDF/HDF5 file
        import numpy as np
        import xarray as xr
        from granudep.io import provenance, var
        ds = provenance(xr.Dataset({"a": var(np.arange(10000.0), ("t",), "m", "a")}), case="c", config_yaml="{}")
        write_netcdf(ds, tmp_path / "full.nc")
        bad.write_bytes((tmp_path / "full.nc").read_bytes()[:3000])
    else:
        bad.write_bytes(content)
    extra = {"regress": ["-o", str(tmp_path / "reg")], "isph-vtk": ["-o", str(tmp_path / "vtk")]}.get(command, [])
    assert main([command, str(bad)] + extra) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(bad) in err[0] and ("NetCDF" in err[0] or "empty" in err[0]), err


def test_monitor_x_inf_beyond_the_bed_is_refused(tmp_path):
    import pathlib
    sys.path.insert(0, str(pathlib.Path(__file__).parents[1] / "monitor"))
    from monitor_synth import ramp_run
    run = ramp_run(case="T22-A70", dx=0.004)
    end = float(run.attrs.get("domain_length", float(run.x.max())))
    with pytest.raises(ConfigError, match=r"^x_inf: must be <= .* the end of the run's bed"):
        granudep.monitor(run, x_inf=end + 1.0)


def test_da_cli_x_inf_alone_means_user_mode(monkeypatch):
    from granudep.cli import main
    import granudep.da.api as dapi
    seen = {}

    def fake(cfg, **kw):
        seen["cfg"] = cfg
        raise ConfigError("stop")

    monkeypatch.setattr(dapi, "run_da", fake)
    assert main(["da", "1D-A70", "--x-inf", "1.2", "-o", "/tmp/granudep-test-xinf.nc"]) == 2
    assert seen["cfg"].deposition.x_inf_mode == "user" and seen["cfg"].deposition.x_inf == 1.2


def test_set_on_every_run_command(monkeypatch):
    from granudep.cli import main
    import granudep.isph.api as iapi
    seen = {}
    monkeypatch.setattr(iapi, "run_config", lambda cfg, **k: seen.setdefault("cfg", cfg) and None)
    assert main(["isph", "T22-A70", "--set", "numerics.cfl=0.1", "--set", "stop_at_rest=false",
                 "--set", "eta_max=5.0e4", "-o", "/tmp/granudep-test-set.nc"]) == 0
    c = seen["cfg"]
    assert c.numerics.cfl == 0.1 and c.output.stop_at_rest is False and c.rheology.eta_max == 5.0e4
    assert main(["isph", "T22-A70", "--set", "nonsense"]) == 2
    assert main(["isph", "T22-A70", "--threads", "0"]) == 2


def test_benchmark_summary_is_world_readable(tmp_path):
    import os
    import pathlib
    import subprocess
    root = pathlib.Path(__file__).resolve().parents[2]
    bench = tmp_path / "benchmarks" / "isph"
    bench.mkdir(parents=True)
    (bench / "T22-A70.tsv").write_text("s\th:m:s\tmax_rss\n1.5\t0:00:01\t100.0\n")
    out = tmp_path / "benchmarks" / "summary.csv"
    old = os.umask(0o022)
    try:
        subprocess.run([sys.executable, str(root / "benchmarks" / "workflow_summary.py"), str(tmp_path / "benchmarks"),
                        "-o", str(out)], check=True, capture_output=True)
    finally:
        os.umask(old)
    assert out.stat().st_mode & 0o777 == 0o644
    assert "T22-A70" in out.read_text()


def test_version_names_the_commit(capsys):
    from granudep.cli import main
    from granudep._version import commit
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    out = capsys.readouterr().out.strip()
    assert out.startswith(f"granudep {granudep.__version__} (commit ") and "\n" not in out
    c = commit()
    if c is not None:  # a git checkout: the version carries the commit
        assert c.split("+")[0] in out and f"+g{c[:10]}" in granudep.__version__


def test_python_api_progress_lines_in_logs(caplog):
    from granudep.progress import BarProgress, make_progress
    p = make_progress(None, 0.0)  # not a terminal under pytest: plain lines
    assert not isinstance(p, BarProgress)
    with caplog.at_level("INFO", logger="granudep"):
        p(lambda: "step 1")
    assert "step 1" in caplog.text
    bar = make_progress("bar", 0.0, total=2.0)
    bar.update(1.0)
    assert isinstance(bar, BarProgress) and bar.bar.n == 1.0
    bar.close()
    with pytest.raises(ConfigError, match="progress: must be one of"):
        make_progress("loud", 1.0)


def test_vtk_binary_with_velocity_and_deposited_flag(tmp_path):
    import base64
    import re
    import numpy as np
    from granudep.cli import main
    nc = tmp_path / "r.nc"
    granudep.run_isph("T22-A70", output=nc, dx=0.02, t_end=0.02, progress=False)
    assert main(["isph-vtk", str(nc), "-o", str(tmp_path / "bin")]) == 0
    assert main(["isph-vtk", str(nc), "-o", str(tmp_path / "asc"), "--encoding", "ascii"]) == 0
    text = sorted((tmp_path / "bin").glob("*.vtp"))[-1].read_text()
    asc = sorted((tmp_path / "asc").glob("*.vtp"))[-1].read_text()
    assert len(text) < len(asc)
    run = granudep.load(nc).isel(time=-1)

    def array(name, dtype):
        m = re.search(rf'Name="{name}"[^>]*format="binary">([^<]+)<', text)
        raw = m.group(1)
        head = base64.b64decode(raw[:12])  # 8-byte UInt64 header -> 12 base64 characters
        n = int(np.frombuffer(head, np.uint64)[0])
        return np.frombuffer(base64.b64decode(raw[12:]), dtype)[: n // np.dtype(dtype).itemsize]

    vel = array("velocity", np.float32).reshape(-1, 3)
    np.testing.assert_array_equal(vel[:, 0], run.u.values.astype(np.float32))
    np.testing.assert_array_equal(vel[:, 1], run.v.values.astype(np.float32))
    dep = array("deposited", np.int8)
    np.testing.assert_array_equal(dep, (np.hypot(run.u.values, run.v.values) < 0.1).astype(np.int8))
    assert 'Name="free_surface"' in text and 'Vectors="velocity"' in text


@pytest.mark.parametrize("stage", ["isph", "da", "monitor", "regress"])
def test_config_template_is_a_valid_config_of_the_stage(tmp_path, capsys, stage):
    from granudep.cli import main
    assert main(["config", "template", stage]) == 0
    text = capsys.readouterr().out
    f = tmp_path / f"{stage}.yaml"
    f.write_text(text)
    data = load_yaml(f)
    assert data and "#" in text
    assert main(["config", "show", str(f), "--stage", stage]) == 0
    assert capsys.readouterr().out.count("\n") > 5


def test_config_write_gives_the_yaml_the_workflow_rules_wrote_before(tmp_path, capsys):
    """`granudep config write` (rules user_case_config, sensitivity_config): dotted keys in order,
    YAML values (a quoted '123' stays a string), the same bytes as the rules' yaml.safe_dump."""
    import yaml
    from granudep.cli import main
    out = tmp_path / "c.yaml"
    assert main(["config", "write", "-o", str(out), "--set", "case='123'", "--set", "geometry.theta_deg=20",
                 "--set", "geometry.L0=0.2", "--set", "wall.phi_basal_deg=23.5"]) == 0
    assert out.read_text() == yaml.safe_dump({"case": "123", "geometry": {"theta_deg": 20, "L0": 0.2},
                                              "wall": {"phi_basal_deg": 23.5}}, sort_keys=False)
    assert load_config(out).wall.phi_basal_deg == 23.5
    assert main(["config", "write", "-o", str(tmp_path / "c.txt"), "--set", "a=1"]) == 2
    assert main(["config", "write", "-o", str(out)]) == 2
    assert "give at least one --set" in capsys.readouterr().err


def test_config_show_resolves_with_units_and_ranges(capsys):
    from granudep.cli import main
    assert main(["config", "show", "T22-A70", "--set", "numerics.dx=0.01"]) == 0
    out = capsys.readouterr().out
    assert "  dx: 0.01    # [m]; > 0.0 and <= 0.1; initial particle spacing" in out
    assert "  theta_deg: 22.0    # [deg]; >= 0.0 and < 60.0; slope angle" in out
    assert main(["config", "show", "1D-A70"]) == 0
    assert "  n_particles: 1000    # >= 20 and <= 200000" in capsys.readouterr().out
    assert main(["config", "show", "1D-A70", "--set", "H0=0.05"]) == 2
    assert "changes the paper case" in capsys.readouterr().err
