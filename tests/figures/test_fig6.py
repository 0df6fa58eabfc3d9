"""Fig 6: the F/D interface at requested times, read from a tiny planted run; the case's YAML."""
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import synthetic_data as syn
from granudep import cases
from granudep.cli import main
from granudep.config import ConfigError
from granudep.figures import fig6
from granudep.io import var, write_netcdf
from test_figures_runout import check_png

ROOT = Path(__file__).resolve().parents[2]
DX = 0.01


def planted_run(slip="navier", L0=0.04, H0=0.28):
    """8 x 6 particles on a dx lattice, three snapshots (0, 0.1, 0.2 s): the two lowest rows deposited
    and the four above flowing at t = 0 and 0.1 s, everything at rest at 0.2 s."""
    X, Y = np.meshgrid((np.arange(8) + 0.5) * DX, (np.arange(6) + 0.5) * DX)
    x, y = X.ravel(), Y.ravel()
    time = np.array([0.0, 0.1, 0.2])
    speed = np.where(y > 2 * DX, 0.5, 0.0)
    u = np.stack([speed, speed, np.zeros_like(speed)])
    xs, ys = np.stack([x] * 3), np.stack([y] * 3)
    ds = xr.Dataset(
        {"x": var(xs, ("time", "particle"), "m", "x"), "y": var(ys, ("time", "particle"), "m", "y"),
         "u": var(u, ("time", "particle"), "m s-1", "u"), "v": var(0 * u, ("time", "particle"), "m s-1", "v"),
         "final_front_v99": var(0.075, (), "m", "1 % volume front at the end"),
         "final_front_position": var(0.08, (), "m", "front at the end"),
         "time_to_rest": var(0.15, (), "s", "time to rest")},
        coords={"time": var(time, ("time",), "s", "time")})
    return syn._attrs(ds, "fig6-test", theta_deg=0.0, L0=L0, H0=H0, dx=DX, wall_slip=slip, wall_slip_length=0.018,
                      status="at rest")


def test_interface_and_surface_at_planted_times():
    ds = planted_run()
    tab = fig6.interfaces_at_times(ds, [0.1, 0.2], unit="s")
    flowing, rest = tab[tab.t_request == 0.1], tab[tab.t_request == 0.2]
    # four columns of width 2 dx; deposited rows 0, 1 (top centre 1.5 dx) under the flowing ones
    np.testing.assert_allclose(flowing["x"], [0.01, 0.03, 0.05, 0.07])
    np.testing.assert_allclose(flowing["interface"], 2 * DX)
    np.testing.assert_allclose(flowing["surface"], 6 * DX)
    # at rest the interface is the free surface
    np.testing.assert_allclose(rest["interface"], 6 * DX)
    assert (flowing["time"] == 0.1).all() and not tab["beyond_end"].any()


def test_times_in_scaled_units_and_past_the_end():
    ds = planted_run()
    tc = cases.characteristic_time(0.28, 0.0)
    # t_L0 = sqrt(L0/g) = t_c sqrt(L0/H0); 0.1 s expressed in each unit picks the 0.1 s snapshot
    assert fig6.time_scale(ds, "t_L0") == pytest.approx(math.sqrt(0.04 / cases.G))
    for unit, scale in (("t_L0", math.sqrt(0.04 / cases.G)), ("t_c", tc), ("s", 1.0)):
        tab = fig6.interfaces_at_times(ds, [0.1 / scale], unit=unit)
        assert (tab["time"] == 0.1).all() and (tab["unit"] == unit).all()
        np.testing.assert_allclose(tab["t_s"], 0.1 / tc)
    # a time past the last snapshot takes the last one and says so
    late = fig6.interfaces_at_times(ds, [5.0], unit="s")
    assert late["beyond_end"].all() and (late["time"] == 0.2).all()
    assert fig6.snapshot_for(np.array([0.0, 0.1, 0.2]), 0.24) == (2, False)
    assert fig6.snapshot_for(np.array([0.0, 0.1, 0.2]), 0.26) == (2, True)
    with pytest.raises(ConfigError, match="time-unit"):
        fig6.interfaces_at_times(ds, [1.0], unit="minutes")


def test_default_times_are_the_papers_first_and_last_and_three_between():
    t = fig6.DEFAULT_TIMES
    assert len(t) == 5 and (t[0], t[-1]) == fig6.PAPER_TIMES == (0.416, 7.904)
    np.testing.assert_allclose(np.diff(t), (7.904 - 0.416) / 4)


def test_final_runout_and_bed_label():
    from granudep.isph.analysis import bed_label, final_runout
    out = final_runout(planted_run())
    assert out["front"] == 0.075 and out["runout_norm"] == pytest.approx((0.075 - 0.04) / 0.04)
    assert "1 %" in out["measure"] and out["time_to_rest"] == 0.15
    assert "slip length 18 mm" in bed_label(planted_run("navier"))
    assert bed_label(planted_run("no_slip")) == "no-slip bed"


def test_cli_draws_both_runs(tmp_path):
    files = []
    for slip in ("navier", "no_slip"):
        f = tmp_path / f"{slip}.nc"
        write_netcdf(planted_run(slip), f)
        files.append(str(f))
    out = tmp_path / "fig6.png"
    assert main(["figure", "fig6", "-o", str(out), *files, "--time-unit", "s", "--times", "0.05", "0.2", "1"]) == 0
    check_png(out)


def test_fig6_case_is_table2_quartz_a7_on_a_horizontal_bed():
    from granudep.isph.config import load_config
    cfg = load_config(ROOT / "config" / "isph" / "fig6-quartz-a7.yaml")
    m = cases.material("quartz_sand")
    assert cfg.case == "fig6-quartz-a7" and cfg.geometry.theta_deg == 0.0
    assert cfg.geometry.H0 / cfg.geometry.L0 == pytest.approx(7.0)
    for k in ("d", "rho_s", "rho", "phi_internal_deg"):
        assert getattr(cfg.material, k) == pytest.approx(m[k]), k
    assert cfg.wall.slip == "navier" and cfg.wall.slip_length == 0.018  # the 2D default: the paper's slip
    noslip = load_config(ROOT / "config" / "isph" / "fig6-quartz-a7.yaml", **{"wall.slip": "no_slip"})
    assert noslip.wall.slip == "no_slip"
