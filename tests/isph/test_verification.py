"""Analytic checks of the 2D ISPH solver (the same functions `granudep verify isph` runs)."""
import math

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
    # a = g (mu_B cos(theta) - sin(theta)), mu_B = tan(phi_B). While the bed slides, the layer's momentum
    # balance makes the mean acceleration exactly this rigid-block value whatever the internal shear (it
    # only redistributes momentum within the layer), so the error is the discrete bed friction force's
    # alone, amplified by mu_B cos(theta) / (mu_B cos(theta) - sin(theta)) = 6.5 (the deceleration is the
    # small difference of friction and gravity). The check must resolve the bed friction angle to the
    # 0.1 deg to which it is given (phi_B = 25.5 deg): 0.1 deg more or less changes a by 2.9 %.
    # (Measured: -2.0 % at dx = 4 mm, -1.0 % at 2 mm; the row's own tolerance, 15 %, is 0.5 deg of phi_B.)
    from granudep.isph.config import load_config
    rows = v.sliding_block(quick=True)
    _assert_rows(rows)
    phi_b = load_config(v.layer_config(22.0, 0.02, 0.004, wall={"slip": "coulomb"})).wall.phi_basal_deg
    th = math.radians(22.0)

    def decel(phi_deg):
        return math.tan(math.radians(phi_deg)) * math.cos(th) - math.sin(th)

    tolerance = decel(phi_b + 0.1) / decel(phi_b) - 1.0
    assert 0.028 < tolerance < 0.030  # 2.9 %
    assert abs(rows[0]["error"]) <= tolerance, rows[0]


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
    # reported: the 20 mm and 12 mm layers at the chain's dx (5 and 3 particles) and the 3- and
    # 2-particle sheets at 2 mm; each a finite speed error below the 1 m/s launch speed
    thin = [r for r in rows if not np.isfinite(r["tolerance"])]
    assert len(thin) == 4 and all(0.0 <= r["value"] < 1.0 for r in thin), [r["value"] for r in thin]


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


#: the T22-A70 failure-plane angle from the horizontal, Rankine's 45 deg + phi/2 (phi = 25.5 deg)
RANKINE_DEG = 45.0 + 0.5 * 25.5


def _fit_resolution_deg(angle_from_bed_deg, dx, H0):
    """Angle change of the fitted failure plane when the failure surface moves by one ``dx`` (the
    lattice step of the bands' smallest initial x) between the lowest and the highest band: the fit
    spans initial heights 0.1..0.9 H0, so d(beta) = sin^2(beta) dx / (0.8 H0)."""
    return np.degrees(np.sin(np.radians(angle_from_bed_deg)) ** 2 * dx / (0.8 * H0))


@pytest.mark.slow
def test_t22a70_paper_model_departs_from_rankine_and_rests_late():
    # The paper model (Navier slip 0.018 m) at 4 mm does not reproduce the paper's failure plane and
    # time to rest (docs/verification.md: 65.3 deg, Rankine 57.75 +- 5, paper 55.8; t_s 19.6 t_c, paper
    # 13.5 +- 3; the no-slip bed gives 57.9 deg and 18.2). Asserted is that documented disagreement,
    # so that a NaN or a crash is not taken for it: the angle steeper than Rankine + 5 deg (the claim's
    # tolerance) and still a plane rising towards the back wall (< 90 deg); the rest time later than
    # the paper's + 3 t_c and within the run (30 t_c, at rest).
    rows = v.collapse_t22a70(quick=False)
    fp, ts, runout = rows
    assert np.isfinite(fp["value"]) and RANKINE_DEG + 5.0 < fp["value"] < 90.0, fp
    assert np.isfinite(ts["value"]) and 13.5 + 3.0 < ts["value"] < 30.0, ts
    assert ts["note"].startswith("status at rest"), ts
    assert np.isfinite(runout["value"]) and runout["value"] > 0.0, runout  # reported: the front advanced


def test_failure_plane_angle_of_a_short_collapse():
    from granudep.isph.analysis import failure_plane_angle
    from granudep.isph.api import run_isph
    dx = 0.01
    fps = {}
    for slip in ("no_slip", "navier"):  # navier: the default, the paper's slip length 0.018 m
        ds = run_isph("T22-A70", dx=dx, t_end=0.15, progress=False, **{"wall.slip": slip})
        fps[slip] = failure_plane_angle(ds, t_norm=1.0)
        assert fps[slip]["points"] >= 10  # a straight failure surface through most of the column's bands
        theta, H0 = float(ds.attrs["theta_deg"]), float(ds.attrs["H0"])
    # on a no-slip bed the active wedge is Rankine's, within the fit's resolution at 10 mm (1.7 deg)
    # (measured 57.6 deg; 57.9 at 4 mm)
    no_slip = fps["no_slip"]["angle_horizontal_deg"]
    assert abs(no_slip - RANKINE_DEG) <= _fit_resolution_deg(RANKINE_DEG - theta, dx, H0), no_slip
    # on the Navier bed the plane is steeper, as in the full 4 mm run (65.3 deg, the disagreement of
    # test_t22a70_paper_model_departs_from_rankine_and_rests_late): beyond Rankine + 5 deg and within
    # the 10 mm and 4 mm fits' resolutions (3.4 deg) of the 4 mm angle (measured 65.5 deg)
    navier = fps["navier"]["angle_horizontal_deg"]
    assert navier > RANKINE_DEG + 5.0, navier
    assert abs(navier - 65.3) <= _fit_resolution_deg(65.3 - theta, dx + 0.004, H0), navier


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
def test_dam_break_approximate_fails_the_energy_target_at_4_and_2_mm():
    # The approximate projection's pressure creates energy in the low-viscosity dam break (docs/model.md).
    # Asserted is that failure as measured, so that a crash or a NaN is not taken for it: at 4 mm the run
    # reaches t = 1 s and rises far above the 0.5 % target, by more than 10 % of E_ref (a gain, not a
    # marginal miss; measured +82 %, pressure work +92 %); at 2 mm the rise stops the run at the energy
    # limit (10 E_ref, measured at t = 0.31 s).
    rows = v.dam_break(quick=False, projection="approximate")
    by = {r["quantity"]: r for r in rows}
    stable4 = by["stable to t = 1 s, dx = 4 mm (1 = yes)"]
    energy4 = by["max (E_kin + E_pot + D - E_0)/E_ref, dx = 4 mm"]
    assert stable4["passed"], stable4
    assert np.isfinite(energy4["value"]) and 0.1 < energy4["value"] < 10.0 and not energy4["passed"], energy4
    stable2 = by["stable to t = 1 s, dx = 2 mm (1 = yes)"]
    energy2 = by["max (E_kin + E_pot + D - E_0)/E_ref, dx = 2 mm"]
    assert stable2["value"] == 0.0 and "failed: energy rose above E_0" in stable2["note"], stable2
    assert np.isfinite(energy2["value"]) and energy2["value"] >= 10.0, energy2


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
