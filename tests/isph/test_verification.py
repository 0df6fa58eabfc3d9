"""Analytic checks of the 2D ISPH solver (the same functions `granudep verify isph` runs)."""
import numpy as np
import pytest

from granudep.isph import verification as v


def _assert_rows(rows):
    """Every checked row passes; a row without a finite tolerance is reported (never passed) and only
    has to carry its number."""
    from granudep.verification_gate import is_reported
    for r in rows:
        if is_reported(r["tolerance"]):
            assert not r["passed"], r
            continue
        assert r["passed"], f"{r['check']}: {r['quantity']} = {r['value']:.4g} (error {r['error']:.3g} > {r['tolerance']})"


def test_hydrostatic_layer_stays_at_rest_with_hydrostatic_base_pressure():
    # bounds: max speed < 1 mm/s after 0.5 s; base pressure within 3 % of rho g H
    _assert_rows(v.hydrostatic(quick=True))


def test_newtonian_open_channel_poiseuille_matches_analytic_profile():
    # relative L2 error <= 2 %
    _assert_rows(v.film_flow(quick=True))


def test_coulomb_wall_friction_decelerates_sliding_layer_at_analytic_rate():
    # a = g (tan(phi_B) cos(theta) - sin(theta)) within 15 %
    _assert_rows(v.sliding_block(quick=True))


def test_decelerating_layer_follows_the_1d_reference():
    # a 20 mm layer (10 particles) launched at 1 m/s on 22 deg below mu_s: mean speed within 0.03 m/s
    # of the converged 1D finite-volume solution over t <= 1 s (measured: 0.027 m/s)
    rows = v.decelerating_layer(quick=True)
    assert len(rows) == 1
    _assert_rows(rows)


def test_wall_stress_option_follows_the_1d_reference_on_a_thick_layer():
    # bed_stress = wall (the mu(I) law at the wall's own p_w and shear rate): 10 particles across,
    # within the same 0.03 m/s of the converged 1D solution (measured: 0.014 m/s, bed 0.027)
    from granudep.isph.layer_reference import uniform_layer
    ref = uniform_layer(0.02, 22.0, 1.0, n_cells=20, t_end=1.0, dt=1.0e-3, out_every=0.05)
    t, m = v.decelerating_layer_history(0.02, 0.002, bed_stress="wall", t_end=1.0)
    err = np.max(np.abs(m - np.interp(t, ref.t, ref.mean_speed)))
    assert err < 0.03
    assert m[-1] < 0.05 and np.all(np.diff(m) < 1e-3)  # it decelerates and (nearly) stops


@pytest.mark.slow
def test_decelerating_layer_fine_and_thin_sheets_reported():
    rows = v.decelerating_layer(quick=False)
    _assert_rows(rows)
    thin = [r for r in rows if not np.isfinite(r["tolerance"])]
    assert len(thin) == 2 and all(np.isfinite(r["value"]) for r in thin)


@pytest.mark.slow
def test_hydrostatic_and_poiseuille_fine():
    _assert_rows(v.hydrostatic(quick=False) + v.film_flow(quick=False))


@pytest.mark.slow
def test_bagnold_profile():
    # target 3 % L2 at dx = 1 and 0.5 mm, steady state (t = 7.5..10 s; an
    # earlier 4.5..5 s window caught the 1 mm layer still relaxing). With the shifting band: 2.6 % and
    # 1.4 % (the band removed a pressure offset under the surface; without it 2.5 % / 4.6 %,
    # failing at 0.5 mm). The "stress" pair viscosity took 1 mm from 6.2 % (t = 1 s) to 2.5 %.
    _assert_rows(v.bagnold(quick=False))


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="the paper model (Navier slip 0.018 m) at 4 mm: failure plane 65.3 deg "
                   "(Rankine 57.75 +- 5, paper 55.8), t_s 19.6 t_c (paper 13.5 +- 3); no-slip bed: 57.9 deg, 18.2")
def test_t22a70_failure_plane_and_time_to_rest():
    rows = v.collapse_t22a70(quick=False)
    fp, ts = rows[0], rows[1]
    assert abs(fp["error"]) <= 5.0 and abs(ts["error"]) <= 3.0, (fp["value"], ts["value"])


def test_failure_plane_angle_of_a_short_collapse(tmp_path):
    from granudep.isph.analysis import failure_plane_angle
    from granudep.isph.api import run_isph
    ds = run_isph("T22-A70", dx=0.01, t_end=0.15)
    fp = failure_plane_angle(ds, t_norm=1.0)
    # a straight failure surface from the toe into the column: between 25 and 75 deg from the bed
    assert fp["points"] >= 3 and 25.0 < fp["angle_deg"] < 75.0


def test_dam_break_default_never_gains_energy_at_8_mm():
    # the default (adjoint-pair) projection: stable to t = 1 s and within the 0.5 % energy target
    rows = v.dam_break(quick=True)
    assert {r["check"] for r in rows} == {"dam_break"}
    stable = [r for r in rows if r["quantity"].startswith("stable")][0]
    assert stable["passed"], stable["note"]
    energy = [r for r in rows if r["quantity"].startswith("max (E_kin")][0]
    assert energy["passed"], energy


def test_dam_break_approximate_rows_are_reported():
    # the previous default, kept as an option: stable at 8 mm, its energy rise reported (no tolerance)
    rows = v.dam_break_approximate(quick=True)
    assert {r["check"] for r in rows} == {"dam_break_approximate"}
    stable = [r for r in rows if r["quantity"].startswith("stable")][0]
    assert stable["passed"], stable["note"]
    energy = [r for r in rows if r["quantity"].startswith("max (E_kin")][0]
    assert energy["tolerance"] == float("inf") and energy["value"] < 0.05


@pytest.mark.slow
def test_dam_break_energy_target_at_4_and_2_mm():
    _assert_rows(v.dam_break(quick=False))


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="the approximate projection's pressure creates energy in the low-"
                                       "viscosity dam break (+62 % of E_ref by 1 s at 4 mm; 2 mm blows up)")
def test_dam_break_approximate_fails_the_energy_target_at_4_and_2_mm():
    _assert_rows(v.dam_break(quick=False, projection="approximate"))


def test_cli_runs_parts_of_the_suite_and_merges_them_in_order(tmp_path, capsys):
    from granudep.cli import main
    a, b, out = tmp_path / "a.csv", tmp_path / "b.csv", tmp_path / "isph.csv"
    assert main(["verify", "isph", "--quick", "--checks", "sliding_block", "-o", str(a)]) == 0
    assert main(["verify", "isph", "--quick", "--checks", "hydrostatic", "-o", str(b)]) == 0
    assert main(["verify", "isph", "--merge", str(b), str(a), "-o", str(out)]) == 0
    import pandas as pd
    table = pd.read_csv(out)
    assert list(table["check"]) == ["hydrostatic", "hydrostatic", "coulomb_sliding_block"]
    assert table.equals(pd.concat([pd.read_csv(b), pd.read_csv(a)], ignore_index=True))


@pytest.mark.parametrize("argv, message", [
    (["--checks", "bogus"], "--checks: must be comma-separated names of hydrostatic"),
    (["--merge", "nope.csv"], "--merge: file not found: nope.csv"),
])
def test_cli_refuses_unknown_checks_and_missing_parts(tmp_path, capsys, argv, message):
    from granudep.cli import main
    assert main(["verify", "isph", *argv, "-o", str(tmp_path / "x.csv")]) == 2
    assert message in capsys.readouterr().err


def test_flat_collapse_config_is_the_table2_material_on_a_horizontal_bed():
    from granudep.isph.config import load_config
    cfg = load_config(v.flat_collapse_config("quartz_sand", 1.0, 0.004))
    assert cfg.geometry.theta_deg == 0.0 and cfg.geometry.H0 == pytest.approx(0.1)
    assert cfg.material.phi_internal_deg == 31.0 and cfg.wall.phi_basal_deg == 31.0
    assert cfg.material.rho == 1430.0 and cfg.case == "flat-quartz-sand-a1"
    with pytest.raises(ValueError, match="aspect"):
        v.flat_collapse_config("glass_beads", 0.0)


def test_coarse_flat_collapse_spreads_loses_height_and_stops_without_gaining_energy():
    from granudep.isph.api import run_isph
    ds = run_isph(v.flat_collapse_config("glass_beads", 0.5, 0.008), progress=False)
    l0 = float(ds.attrs["L0"])
    assert ds.attrs["status"] == "at rest"
    assert l0 < float(ds["final_front_v99"]) < 3 * l0          # it spreads, not to the domain end
    # the column slumps: its potential energy falls (measured 16 % at 8 mm; the back corner of an
    # a = 0.5 column stays put, so the highest particle does not move at this dx) and no particle rises
    ep = ds["potential_energy"].values
    assert ep[-1] < 0.9 * ep[0]
    assert float(ds["y"].isel(time=-1).max()) <= float(ds["y"].isel(time=0).max()) + 1e-6
    # never above E_0 by more than the dam-break bound (the run itself stops at 1 %)
    assert float(ds.attrs["energy_max_excess"]) <= 0.005
    # rest: the first snapshot from which the max speed stays below rest_speed (0.1 m/s), not the
    # 5 t_c fallback that a flow never reaching 10x the rest speed used to get
    t, vmax, ts = ds["time"].values, ds["max_speed"].values, float(ds["time_to_rest"])
    assert ts < 5.0 * float(ds.attrs["t_c"])
    k = int(np.argmin(abs(t - ts)))
    assert (vmax[k:] < 0.1).all() and vmax[k - 1] >= 0.1
