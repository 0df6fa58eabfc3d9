"""Monitoring sections on synthetic particle sets with known answers (eqs 15–17)."""
from __future__ import annotations

import numpy as np
import pytest

from granudep.config import ConfigError
from granudep.io import check_contract, open_dataset, write_netcdf
from granudep.monitor import sections as S
from granudep.monitor.api import deceleration_mask, monitor, monitor_wm
from monitor_synth import lattice, make_run, planted_frame, strip_run

DX = 0.004


def test_section_centres_span_gate_to_runout():
    xm = S.section_centres(0.2, 0.6, 11)
    assert xm.shape == (11,)
    np.testing.assert_allclose(xm, 0.2 + 0.04 * np.arange(11), atol=1e-15)


def test_divr_full_support_is_two_and_bed_mirror_restores_it():
    # interior of a deposited lattice: eq 16 ≈ 2 (2D); the first row needs the bed images
    x, y = lattice(0.0, 0.2, 20, DX)
    dep = np.ones(x.size, dtype=bool)
    h = 1.3 * DX
    with_mirror = S.divr_deposited(x, y, dep, DX * DX, h, True)
    without = S.divr_deposited(x, y, dep, DX * DX, h, False)
    interior = (np.abs(x - 0.1) < DX) & (y < 10 * DX)
    # lattice sum of a Wendland C2 kernel at h = 1.3 dx: within 3 % of the continuous value 2
    assert np.all(np.abs(with_mirror[interior] - 2.0) < 0.06)
    bottom = interior & (y < DX)
    assert np.all(without[bottom] < 1.6)          # the bed would look like an interface ...
    assert np.all(with_mirror[bottom] > 1.6)      # ... unless its images are counted


def test_divr_only_counts_deposited_neighbours_and_flags_nan():
    x, y = lattice(0.0, 0.1, 10, DX)
    x[0] = np.nan
    dep = y < 4 * DX
    d = S.divr_deposited(x, y, dep, DX * DX, 1.3 * DX, True)
    assert np.isnan(d[0])
    far_above = y > 7 * DX  # more than 2h above the deposit: no deposited neighbour at all
    assert np.all(d[far_above] == 0.0)


@pytest.mark.parametrize("h_ratio", [1.0, 1.3, 1.5])
@pytest.mark.parametrize("m_deposit", [1, 6, 12])
def test_planted_interface_gives_exact_depths(h_ratio, m_deposit):
    n_rows = 15
    ds = monitor(strip_run(n_rows=n_rows, m_deposit=m_deposit, h_ratio=h_ratio))
    hd = ds.deposit_depth.isel(time=0).values
    h = ds.flow_depth.isel(time=0).values
    # on the ideal lattice the top deposited row is the only eq-16 layer: Y_F/D = m dx exactly
    np.testing.assert_allclose(hd, m_deposit * DX, atol=1e-12)
    np.testing.assert_allclose(h, (n_rows - m_deposit) * DX, atol=1e-12)
    np.testing.assert_allclose(ds.total_depth.isel(time=0).values, n_rows * DX, atol=1e-12)
    assert np.all(ds.interface_source.values == S.SOURCE_EQ16)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_jittered_interface_within_one_spacing(seed):
    # particles displaced by up to ±0.2 dx: h and h_D within one particle spacing (the
    # resolution of a particle interface)
    ds = monitor(strip_run(n_rows=15, m_deposit=6, jitter=0.2, seed=seed))
    hd = ds.deposit_depth.isel(time=0).values
    h = ds.flow_depth.isel(time=0).values
    assert np.all(np.abs(hd - 6 * DX) <= DX)
    assert np.all(np.abs(h - 9 * DX) <= DX)


def test_uniform_strip_gives_exact_eq15_average():
    rng = np.random.default_rng(4)
    x, y = lattice(0.18, 0.62, 10, DX)
    x = x + rng.uniform(-0.3, 0.3, x.size) * DX  # irregular membership
    u = rng.normal(0.7, 0.2, x.size)
    v = np.zeros_like(u)
    run = make_run([(x, y, u, v)])
    for wf in (1.0, 2.0, 3.5):
        ds = monitor(run, width_factor=wf)
        for k, xm in enumerate(ds.x.values):
            inside = np.abs(x - xm) <= 0.5 * wf * DX
            assert ds.n_particles.values[k, 0] == inside.sum()
            assert ds.velocity.values[k, 0] == pytest.approx(u[inside].mean(), rel=1e-12)


def test_uniform_velocity_section_average_and_momentum():
    ds = monitor(strip_run(n_rows=10, m_deposit=0, u_flow=0.8))
    np.testing.assert_allclose(ds.velocity.values, 0.8, rtol=1e-12)
    np.testing.assert_allclose(ds.deposit_depth.values, 0.0, atol=1e-15)
    np.testing.assert_allclose(ds.momentum.values, 10 * DX * 0.8, rtol=1e-12)
    p0 = ds.attrs["p0"]
    np.testing.assert_allclose(ds.momentum_norm.values, 10 * DX * 0.8 / p0, rtol=1e-12)
    assert np.all(ds.interface_source.values == S.SOURCE_NO_DEPOSIT)


def test_fully_deposited_section():
    ds = monitor(strip_run(n_rows=10, m_deposit=10))
    np.testing.assert_allclose(ds.flow_depth.values, 0.0, atol=1e-15)
    np.testing.assert_allclose(ds.deposit_depth.values, 10 * DX, atol=1e-12)
    np.testing.assert_allclose(ds.total_depth.values, ds.deposit_depth.values, atol=0)
    np.testing.assert_allclose(ds.momentum.values, 0.0, atol=1e-15)
    assert np.all(ds.interface_source.values == S.SOURCE_ALL_DEPOSITED)


def test_empty_sections_are_nan():
    # material only up to x = 0.4: sections 6..10 (x = 0.44 … 0.6) hold no particle
    x, y = lattice(0.18, 0.40, 8, DX)
    u, v = planted_frame(x, y, DX, 3, 0.5)
    ds = monitor(make_run([(x, y, u, v)]))
    empty = ds.x.values > 0.4 + DX
    for name in ("velocity", "flow_depth", "deposit_depth", "total_depth", "momentum",
                 "free_surface_height", "interface_height"):
        assert np.all(np.isnan(ds[name].values[empty])), name
        assert np.all(np.isfinite(ds[name].values[~empty])), name
    assert np.all(ds.interface_source.values[empty] == S.SOURCE_EMPTY)
    assert np.all(ds.n_particles.values[empty] == 0)


def test_free_surface_flag_excludes_interface_particles_and_fallback_agrees():
    n_rows, m = 12, 5
    run = strip_run(n_rows=n_rows, m_deposit=m)
    fs = run.free_surface.values.copy()
    fs[0, np.abs(run.y.values[0] - (m - 0.5) * DX) < 1e-9] = 1  # flag the interface row
    run["free_surface"] = run.free_surface.copy(data=fs)
    ds = monitor(run)
    assert np.all(ds.interface_source.values == S.SOURCE_FALLBACK)
    np.testing.assert_allclose(ds.deposit_depth.values, m * DX, atol=1e-12)


def test_section_reduce_ignores_candidates_above_the_flow():
    # one section; candidate particle above the highest flowing particle is not an interface
    x = np.array([0.0, 0.0, 0.0, 0.0])
    y = np.array([0.5, 1.5, 2.5, 3.5]) * DX
    dep = np.array([True, False, False, True])   # a deposited particle sits on top of a flowing pair
    cand = np.array([False, False, False, True])
    sums = S.section_reduce(x, y, np.zeros(4), dep, cand, 0.0, 1.0, DX, 1)
    assert sums[0, 8] == 0  # no interface particle
    d = S.depths_from_sums(sums, DX)
    assert d["interface_source"][0] == S.SOURCE_FALLBACK
    assert d["deposit_depth"][0] == pytest.approx(DX)  # the deposited particle below the flow


def test_section_membership_includes_the_edges():
    x = np.array([-DX, -DX * 1.0001, DX, 0.5 * DX])
    y = np.full(4, 0.5 * DX)
    ones = np.ones(4, dtype=bool)
    sums = S.section_reduce(x, y, np.ones(4), ~ones, ~ones, 0.0, 1.0, DX, 1)
    assert sums[0, 0] == 3  # |x − x_M| ≤ W/2 inclusive, 1.0001·W/2 outside


def test_time_coordinates_and_contract_roundtrip(tmp_path):
    ds = monitor(strip_run())
    assert ds.velocity.dims == ("section", "time")
    assert ds.sizes["section"] == 11
    np.testing.assert_allclose(ds.x_norm.values, np.arange(11) / 10, atol=1e-12)
    t_c = np.sqrt(0.14 / (9.81 * np.cos(np.radians(22.0))))
    np.testing.assert_allclose(ds.t_s.values, ds.time.values / t_c, rtol=1e-12)
    assert ds.attrs["x_inf"] == 0.6 and ds.attrs["case"] == "SYN-A70"
    check_contract(ds)
    path = write_netcdf(ds, tmp_path / "s.nc")
    back = open_dataset(path)
    for name in ("velocity", "flow_depth", "deposit_depth", "total_depth", "momentum",
                 "free_surface_height", "interface_height", "x", "x_norm", "t_s"):
        assert name in back.variables
        assert back[name].attrs["units"] and back[name].attrs["long_name"]
    np.testing.assert_array_equal(back.deposit_depth.values, ds.deposit_depth.values)


def test_bad_input_is_refused_with_the_key():
    run = strip_run()
    with pytest.raises(ConfigError, match="monitor.width_factor: must be > 0"):
        monitor(run, width_factor=-1.0)
    with pytest.raises(ConfigError, match="monitor.divergence_threshold: must be > 0.0 and < 2.0"):
        monitor(run, divergence_threshold=2.5)
    with pytest.raises(ConfigError, match="run.attrs.smoothing_length"):
        monitor(run.drop_attrs().assign_attrs({k: v for k, v in run.attrs.items() if k != "smoothing_length"}))
    with pytest.raises(ConfigError, match="x_inf: must be > L0"):
        monitor(run, x_inf=0.1)
    with pytest.raises(ConfigError, match="run: file not found"):
        monitor("/nonexistent/run.nc")


def test_deceleration_mask():
    m = np.array([[np.nan, 1.0, 3.0, 2.0, 1.0, 0.05, 0.02],
                  [np.nan] * 7])
    mask = deceleration_mask(m, 0.01)
    assert mask[0].tolist() == [False, False, True, True, True, True, False]
    assert not mask[1].any()


def test_width_sensitivity_zero_for_uniform_flow():
    ds = monitor_wm(strip_run(n_rows=10, m_deposit=3, u_flow=0.5))
    assert ds.momentum_norm.dims == ("width_factor", "section", "time")
    assert ds.width_factor.values.tolist() == [1.0, 2.0, 3.0, 4.0]
    np.testing.assert_allclose(ds.rms_deviation.values, 0.0, atol=1e-15)
    check_contract(ds)


def test_width_sensitivity_matches_separate_monitor_runs():
    # x-dependent, decelerating flow: each width averages a different particle set
    x, y = lattice(0.181, 0.621, 8, DX)  # off-centre lattice: each width holds a different set
    times = np.linspace(0.0, 1.0, 21)
    frames = []
    for t in times:
        u0 = 1.0 * (1 - t) if t > 0.2 else 5.0 * t
        u = u0 * (1.0 + 40.0 * (x - 0.4) ** 2 + 0.3 * np.sin(x / DX))
        u = np.where(y > 2 * DX, u, 0.0)
        frames.append((x, y, u, np.zeros_like(u)))
    run = make_run(frames, times=times)
    wm = monitor_wm(run)
    ref = monitor(run, width_factor=2.0).momentum_norm.values
    mask = deceleration_mask(ref, 0.01)
    assert np.all(mask.sum(axis=1) >= 10)  # a real deceleration window in every section
    for j, w in enumerate(wm.width_factor.values):
        mine = monitor(run, width_factor=float(w)).momentum_norm.values
        np.testing.assert_allclose(wm.momentum_norm.values[j], mine, rtol=1e-12)
        d = (mine - ref)[mask].reshape(-1)
        expect = [np.sqrt(np.mean(((mine - ref)[k][mask[k]]) ** 2)) for k in range(11)]
        np.testing.assert_allclose(wm.rms_deviation.values[j], expect, rtol=1e-12, atol=1e-15)
        if w != 2.0:
            assert np.all(wm.rms_deviation.values[j] > 0) and d.size
    np.testing.assert_array_equal(wm.deceleration.values.astype(bool), mask)


@pytest.mark.slow
def test_kernels_also_work_uncompiled():
    """The numba kernels give the same answers as plain Python (NUMBA_DISABLE_JIT=1)."""
    import os
    import subprocess
    import sys
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    here = os.path.dirname(__file__)
    res = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", here, "-k",
                          "planted_interface or divr or empty or section_reduce or membership"],
                         env=env, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stdout[-2000:] + res.stderr[-2000:]


def test_incomplete_run_is_flagged(caplog):
    import logging
    run = strip_run()
    run["time_to_rest"] = run.time_to_rest.copy(data=np.nan)
    run.attrs["status"] = "failed: particle 1 left the domain"
    with caplog.at_level(logging.WARNING, logger="granudep"):
        ds = monitor(run)
    assert ds.attrs["run_complete"] == 0 and "failed" in ds.attrs["run_status"]
    assert "did not reach rest" in caplog.text
    assert monitor(strip_run()).attrs["run_complete"] == 1
    # no rest time, but every particle below the critical speed at the end: the record is complete
    run = strip_run(u_flow=0.05)
    run["time_to_rest"] = run.time_to_rest.copy(data=np.nan)
    assert monitor(run).attrs["run_complete"] == 1
    run = strip_run(u_flow=0.5)
    run["time_to_rest"] = run.time_to_rest.copy(data=np.nan)
    assert monitor(run).attrs["run_complete"] == 0


def test_x_inf_is_the_runs_volume_front_unless_another_front_is_named():
    """x_inf (eq 35) defaults to the 1 % volume front: the 2 d attached front of a 2D run is not resolved
    at dx >= 2 d (T22-A70 at 1.4 mm: 2.12 m against a volume front of 3.31 m)."""
    run = strip_run()
    run = run.assign(final_front_v99=0.55, final_front_2d=0.5)
    assert monitor(run).attrs["x_inf"] == 0.55
    assert monitor(run, x_inf_front="2d").attrs["x_inf"] == 0.5
    assert monitor(run, x_inf_front="position").attrs["x_inf"] == 0.6
    with pytest.raises(ConfigError, match="monitor.x_inf_front: must be one of"):
        monitor(run, x_inf_front="front")
    with pytest.raises(ConfigError, match="run.final_front_5mm: missing"):
        monitor(run, x_inf_front="5mm")


def _divr_naive(x, y, dep, volume, h, mirror):
    """All pairs, plain NumPy: eq 16 over deposited sources (and their bed images)."""
    from granudep.kernels import wendland_dwdr
    ok = np.isfinite(x) & np.isfinite(y)
    src = ok & dep
    sx, sy = x[src], y[src]
    if mirror:
        sx, sy = np.concatenate([sx, sx]), np.concatenate([sy, -sy])
    out = np.full(x.size, np.nan)
    for i in np.flatnonzero(ok):
        r = np.hypot(x[i] - sx, y[i] - sy)
        r = r[(r > 0) & (r < 2 * h)]
        out[i] = -np.sum(volume * r * np.array([wendland_dwdr(v, h) for v in r]))
    return out


def test_divr_matches_all_pairs_reference_on_a_disordered_cloud():
    rng = np.random.default_rng(3)
    x, y = lattice(0.0, 0.05, 12, DX)
    x = x + 0.3 * DX * rng.uniform(-1, 1, x.size)
    y = np.abs(y + 0.3 * DX * rng.uniform(-1, 1, y.size))
    x[5] = np.nan
    dep = rng.uniform(size=x.size) < 0.6
    for mirror in (True, False):
        got = S.divr_deposited(x, y, dep, DX * DX, 1.3 * DX, mirror)
        ref = _divr_naive(x, y, dep, DX * DX, 1.3 * DX, mirror)
        np.testing.assert_array_equal(np.isnan(got), np.isnan(ref))
        np.testing.assert_allclose(got[~np.isnan(ref)], ref[~np.isnan(ref)], rtol=1e-12, atol=1e-12)
