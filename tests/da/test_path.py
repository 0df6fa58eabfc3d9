"""DA model on a path profile: geometry, input checks, physics checks, outputs, CLI."""
import math
import subprocess
import sys

import numpy as np
import pytest
import yaml

from granudep.config import ConfigError
from granudep.da import path_verification as pv
from granudep.da.api import run_da
from granudep.da.config import resolve
from granudep.da.path import SmoothedPolyline, build_bed, read_profile
from granudep.io import check_contract, open_dataset, write_netcdf

USER_AB = {"ab_source": "user", "A": -0.0313, "B": 0.0402}


def _passed(rows):
    bad = [r for r in rows if not r["passed"]]
    assert not bad, bad


# --- geometry -------------------------------------------------------------------------------

def test_smoothing_has_no_wiggles_and_keeps_straight_runs_straight(tmp_path):
    csv = pv.slope_to_flat(tmp_path)
    bed = build_bed(read_profile(str(csv)), 15.0)
    th = np.degrees(bed.theta)
    assert np.all(np.diff(bed.theta) <= 1e-15)          # slope eases monotonically across the knee
    assert th.max() <= 35.0 + 1e-9 and th.min() >= -1e-12  # never outside the segment slopes
    assert np.all(bed.kappa >= 0.0)                      # concave everywhere: no counter-curvature
    assert abs(th[0] - 35.0) < 1e-6 and abs(th[-1]) < 1e-9  # straight far from the knee
    # the bed is consistent: ∫ sin θ ds = drop, ∫ cos θ ds = horizontal length
    from scipy.integrate import simpson
    assert simpson(np.sin(bed.theta), x=bed.s) == pytest.approx(bed.z[0] - bed.z[-1], rel=1e-7)
    assert simpson(np.cos(bed.theta), x=bed.s) == pytest.approx(bed.x[-1], rel=1e-7)


def test_smoothed_polyline_derivatives_are_consistent():
    f = SmoothedPolyline([0.0, 1.0, 3.0, 4.0], [2.0, 1.0, 1.5, 0.0], 0.3)
    x = np.linspace(-1.0, 5.0, 6001)
    h = x[1] - x[0]
    np.testing.assert_allclose(np.gradient(f(x, 0), h)[2:-2], f(x, 1)[2:-2], atol=1e-5)
    np.testing.assert_allclose(np.gradient(f(x, 1), h)[2:-2], f(x, 2)[2:-2], atol=1e-4)
    # far from the knots the smoothed line is the polyline
    assert f(np.array([-1.0]), 0)[0] == pytest.approx(3.0, abs=1e-12)


def test_s_z_input_and_header_spellings(tmp_path):
    t = math.tan(math.radians(30.0))
    x = np.array([0.0, 10.0, 20.0, 40.0])
    z = np.array([20 * t, 10 * t, 0.0, 0.0])
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(z)))])
    a = read_profile(str(pv.write_profile(tmp_path / "xz.csv", x, z, header=["x (m)", "z_m"])))
    b = read_profile(str(pv.write_profile(tmp_path / "sz.csv", s, z, header=["s [m]", "z/m"])))
    np.testing.assert_allclose(a.x, b.x, atol=1e-12)
    np.testing.assert_allclose(a.z, b.z)


@pytest.mark.parametrize("problem", list(pv.BAD_PATHS))
def test_bad_paths_refused_with_one_line(problem):
    msg = pv.bad_path_messages()[problem]
    assert msg is not None and msg.startswith("geometry.path.file: bad.csv")
    assert pv.BAD_PATHS[problem][1] in msg and "\n" not in msg


def test_bad_path_cli_exit_2_one_line(tmp_path):
    (tmp_path / "p.csv").write_text("x,z\n0,1\n1,0\n2,0\n")
    cfg = tmp_path / "c.yaml"
    cfg.write_text(yaml.safe_dump({"case": "p", "geometry": {"path": {"file": str(tmp_path / "p.csv")}},
                                   "deposition": USER_AB}))
    out = subprocess.run([sys.executable, "-m", "granudep", "da", str(cfg)], capture_output=True, text=True)
    assert out.returncode == 2
    lines = [ln for ln in out.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "geometry.path.file: p.csv: header column 'x' has no unit" in lines[0]


def test_set_up_errors_name_the_key(tmp_path):
    csv = pv.slope_to_flat(tmp_path)
    base = {"case": "p", "deposition": USER_AB, "numerics": {"earth_pressure": "savage_hutter"}}
    with pytest.raises(ConfigError, match="geometry.path.release_start: the release"):
        run_da({**base, "geometry": {"path": {"file": str(csv), "release_start": 400.0}}})
    with pytest.raises(ConfigError, match="numerics.earth_pressure: 'paper'"):
        run_da({**base, "numerics": {}, "geometry": {"path": {"file": str(csv)}}})
    with pytest.raises(ConfigError, match="geometry.path.ab_slope: 'local' needs"):
        run_da({**base, "geometry": {"path": {"file": str(csv), "ab_slope": "local"}}})
    with pytest.raises(ConfigError, match="geometry.path.release_polygon: stations s must increase"):
        resolve({**base, "geometry": {"path": {"file": str(csv), "release_polygon": [[5, 1], [3, 1]]}}})


# --- verification (the same functions as `granudep verify da`) ---------------------------------

def test_straight_path_reproduces_constant_theta():
    _passed(pv.check_straight_path())


def test_coulomb_block_on_curved_path_vs_energy_line():
    rows = pv.check_coulomb_path()
    _passed(rows)
    with_c = [r for r in rows if r["quantity"].startswith("with centripetal: stop")][0]
    without = [r for r in rows if r["quantity"].startswith("without centripetal: stop")][0]
    assert with_c["value"] < without["value"] - 5.0   # the centripetal friction shortens the runout


def test_mass_conservation_and_uniform_width():
    _passed(pv.check_path_mass_and_width())


def test_bad_path_row():
    _passed(pv.check_bad_paths())


def test_convex_break_clips_the_normal_stress_and_counts(tmp_path):
    """A fast block over a sharp crest (10° to 45°, σ = 1 m): g cosθ + κ u² < 0 there."""
    from granudep.config import build
    from granudep.da.config import DAConfig
    from granudep.da.path_run import path_setup
    from granudep.da.path_solver import bed_table, simulate_path
    from granudep.da.step import D_LIFT
    from granudep.da.solver import Physics
    x = np.array([0.0, 20.0, 30.0, 60.0])
    z = np.array([20 * math.tan(math.radians(10)), 0.0, -10.0, -40.0])
    csv = pv.write_profile(tmp_path / "crest.csv", x, z)
    cfg = build(DAConfig, {"case": "crest", "geometry": {"L0": 5.0, "H0": 0.5, "back_wall": False,
                                                         "path": {"file": str(csv), "smoothing_length": 1.0}},
                           "material": {"phi_basal_deg": 20.0, "phi_internal_deg": 30.0},
                           "numerics": {"n_particles": 20, "earth_pressure": "one", "xsph_delta": 0.0,
                                        "smoothing": "fixed", "L_s": 1.0, "t_end": 1.5},
                           "deposition": {"enabled": False}, "output": {"dt_output": 0.5, "dx_grid": 0.25}})
    setup = path_setup(cfg)
    n = 4
    rec = simulate_path(cfg, setup, Physics(0.0, 0.0, False), bed_table(setup, 0.0, 0.0, 0.0, 0.0),
                        init=(np.linspace(10.0, 12.0, n), np.full(n, 0.01), np.full(n, 15.0)))
    assert rec.diag[D_LIFT] > 0
    assert 15.0 < rec.diag[2] < 30.0         # where: at the crest (x ≈ 20 m)


# --- outputs ---------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def lab_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("lab")
    cfg = pv._lab_config(pv.curved_lab_path(folder))
    return run_da(cfg, deposition=True), run_da(cfg, deposition=False)


def test_path_dataset_contract_and_envelopes(lab_run, tmp_path):
    ds, nd = lab_run
    check_contract(ds)
    for name in ("s", "x", "z"):
        assert name in ds.coords
    assert ds.flow_depth.attrs["coordinates"] == "x z"
    reached = np.isfinite(ds.arrival_time.values)
    assert reached.sum() > 100
    s = ds.s.values
    front = float(ds.front_position[-1])
    beyond = reached & (s > ds.attrs["release_end"]) & (s < front - 0.02)
    assert np.all(np.diff(ds.arrival_time.values[beyond]) >= 0.0)   # the flow arrives later further down
    assert float(ds.max_speed.max()) > 0.5
    assert np.all(ds.max_flow_depth.values[beyond] > 0.0)
    H, L = float(ds.drop_height), float(ds.reach_length)
    assert float(ds.travel_angle) == pytest.approx(math.degrees(math.atan(H / L)))
    assert float(ds.final_deposit_depth.sum() * ds.attrs["dx_grid"]) == pytest.approx(
        float(ds.flowing_volume[0]), rel=1e-6)
    assert float(ds.volume_error) < 1e-13
    out = tmp_path / "p.nc"
    write_netcdf(ds, out)
    back = open_dataset(out)
    np.testing.assert_array_equal(back.final_deposit_depth.values, ds.final_deposit_depth.values)
    assert nd.attrs["deposition"] == 0 and float(nd.deposited_volume.max()) == 0.0


def test_release_polygon_volume(tmp_path):
    from granudep.da.path_run import path_setup
    csv = pv.curved_lab_path(tmp_path, width=2.0)
    cfg = resolve({**pv._lab_config(csv), "geometry": {"back_wall": False, "path": {
        "file": str(csv), "smoothing_length": 0.1, "release_polygon": [[0.1, 0.0], [0.2, 0.1], [0.4, 0.1]]}}})
    st = path_setup(cfg)
    assert st.origin == 0.0 and st.s_start == 0.1 and st.s_end == 0.4
    assert float(np.sum(st.V0)) == pytest.approx(2.0 * (0.5 * 0.1 * 0.1 + 0.2 * 0.1), rel=1e-3)
    assert st.H0 == pytest.approx((0.005 + 0.02) / 0.3, rel=1e-3)


def test_cli_on_a_path(tmp_path):
    csv = pv.curved_lab_path(tmp_path)
    cfg = pv._lab_config(csv)
    cfg["numerics"]["n_particles"] = 100
    y = tmp_path / "lab.yaml"
    y.write_text(yaml.safe_dump(cfg))
    out = subprocess.run([sys.executable, "-m", "granudep", "da", str(y), "--no-deposition", "-o",
                          str(tmp_path / "o.nc")], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "travel angle atan(H/L)" in out.stdout
    assert open_dataset(tmp_path / "o.nc").attrs["path_file"] == str(csv)


def test_path_front_takes_the_farthest_main_run():
    from granudep.front import main_run_front
    edges = np.arange(101) * 1.0
    depth = np.zeros(100)
    depth[5:15] = 3.0      # left in the release zone (the deepest)
    depth[40:60] = 1.0     # the main deposit, separated by a gap
    depth[80] = 0.2        # a detached bit (< 1 %)
    assert main_run_front(edges, depth, 0.1, np.ones(100)) == 60.0
    depth[40:60] = 0.001   # below threshold: the release deposit is the front
    assert main_run_front(edges, depth, 0.1, np.ones(100)) == 15.0


def test_ab_by_release_zone_or_local_slope(tmp_path):
    from granudep.da.path_run import path_coefficients, path_setup
    table = tmp_path / "coefficients.csv"
    table.write_text("theta_deg,a,A,B\n10,0.2,-0.05,0.08\n10,1.0,-0.03,0.05\n22,0.2,-0.04,0.06\n22,1.0,-0.02,0.03\n")
    csv = pv.curved_lab_path(tmp_path)
    base = pv._lab_config(csv)
    dep = {**base["deposition"], "ab_source": "computed", "coefficients": str(table)}
    cfg = resolve({**base, "deposition": dep})
    with pytest.raises(ConfigError, match="geometry.path.ab_slope: 'release' reads A, B at the release zone"):
        path_coefficients(cfg, path_setup(cfg))          # a 30 deg release is outside the 10-22 deg table
    local = {**base["geometry"], "path": {**base["geometry"]["path"], "ab_slope": "local"}}
    cfg = resolve({**base, "geometry": local, "deposition": dep})
    A, B, src = path_coefficients(cfg, path_setup(cfg))
    a = 0.14 / 0.2
    steep = np.degrees(path_setup(cfg).bed.theta) >= 22.0
    flat = np.degrees(path_setup(cfg).bed.theta) <= 10.0
    np.testing.assert_allclose(A[steep], -0.04 + (a - 0.2) / 0.8 * 0.02)   # clamped to 22 deg
    np.testing.assert_allclose(A[flat], -0.05 + (a - 0.2) / 0.8 * 0.02)    # clamped to 10 deg
    assert "clamped" in src


def test_path_figure_cli(lab_run, tmp_path):
    from granudep.cli import main
    files = []
    for k, ds in enumerate(lab_run):
        files.append(str(tmp_path / f"r{k}.nc"))
        write_netcdf(ds, files[-1])
    out = tmp_path / "path.png"
    assert main(["path-figure", "-o", str(out), *files]) == 0
    assert out.stat().st_size > 10_000 and out.read_bytes()[:4] == b"\x89PNG"
    assert main(["path-figure", "-o", str(out), files[0], files[1], files[0]]) == 2


def test_path_figure_takes_runs_on_different_station_grids(lab_run, tmp_path):
    """With deposition the grid follows the particles (solver.grid_spacing), so the two runs of a
    figure may sit on different station grids: each is drawn on its own."""
    from granudep.cli import main
    dep, _ = lab_run
    cfg = pv._lab_config(pv.curved_lab_path(tmp_path))
    coarse = run_da({**cfg, "output": {**cfg["output"], "dx_grid": 2.0 * cfg["output"]["dx_grid"]}}, deposition=False)
    assert coarse.s.size != dep.s.size
    files = [str(tmp_path / "dep.nc"), str(tmp_path / "nodep.nc")]
    write_netcdf(dep, files[0])
    write_netcdf(coarse, files[1])
    out = tmp_path / "path.png"
    assert main(["path-figure", "-o", str(out), *files]) == 0
    assert out.read_bytes()[:4] == b"\x89PNG"
