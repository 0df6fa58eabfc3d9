"""The 1D reference of uniform μ(I) layers (granudep.isph.layer_reference)."""
import math

import numpy as np
import pytest

from granudep.isph import layer_reference as lr


def test_face_viscosity_matches_the_mu_i_law_and_its_cap():
    mat = lr.LayerMaterial()
    gdot = np.array([1e-6, 1.0, 50.0])
    p = np.array([100.0, 100.0, 100.0])
    inert = mat.d * gdot / np.sqrt(p / mat.rho_s)
    mu = mat.mu_s + (mat.mu_2 - mat.mu_s) * inert / (mat.i0 + inert)
    expect = np.minimum(mu * p / gdot, mat.eta_max)
    assert np.allclose(lr.face_viscosity(gdot, p, mat), expect, rtol=1e-12)
    assert lr.face_viscosity(gdot, p, mat)[0] == mat.eta_max


def test_bed_face_shear_rate_is_one_sided_over_half_a_cell():
    u = np.array([0.1, 0.3, 0.4])
    g = lr.face_shear_rate(u, 0.01)
    assert np.allclose(g, [0.1 / 0.005, 0.2 / 0.01, 0.1 / 0.01])


def test_layer_above_static_friction_tends_to_bagnold_mean_speed():
    # tan 30 deg = 0.577 between mu_s and mu_2: steady Bagnold flow, mean speed (2/5 of the 3/2-law
    # surface speed). Started from the Bagnold shape at 90 % of it, it relaxes to it.
    mat = lr.LayerMaterial()
    th = math.radians(30.0)
    h = 0.01
    i_th = mat.i0 * (math.tan(th) - mat.mu_s) / (mat.mu_2 - math.tan(th))
    u_surf = (2.0 / 3.0) * (i_th / mat.d) * math.sqrt(mat.rho / mat.rho_s * 9.81 * math.cos(th)) * h ** 1.5
    mean = 0.6 * u_surf
    r = lr.uniform_layer(h, 30.0, 0.9 * mean, n_cells=40, t_end=3.0, dt=2e-3, out_every=0.5)
    assert r.mean_speed[-1] == pytest.approx(mean, rel=0.01)
    assert math.isnan(r.t_stop)


def test_layer_below_static_friction_stops_and_converges():
    coarse = lr.uniform_layer(0.006, 22.0, 1.0, n_cells=10, t_end=0.8, dt=1e-3)
    fine = lr.uniform_layer(0.006, 22.0, 1.0, n_cells=40, t_end=0.8, dt=1e-3)
    assert 0.5 < fine.t_stop < 0.8                    # measured 0.638 s
    assert np.max(np.abs(coarse.mean_speed - fine.mean_speed)) < 2e-3
    assert fine.mean_speed[-1] < 1e-3
    # a thicker layer stops later (1D reference: 0.64 s at 6 mm, 1.02 s at 20 mm)
    thick = lr.uniform_layer(0.012, 22.0, 1.0, n_cells=20, t_end=1.0, dt=1e-3)
    assert thick.t_stop > fine.t_stop


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="h > 0"):
        lr.uniform_layer(-0.01, 22.0)


def test_viscosity_floor_brakes_thin_sheets_only():
    # granular.h's floor rho D sqrt(g D) = 0.129 Pa s exceeds the mu(I) viscosity of a 4 mm sheet at
    # 1 m/s (it stops at 0.37 s instead of 0.585 s) and does nothing to a 20 mm layer
    floor = lr.LayerMaterial(eta_min=0.129)
    assert lr.face_viscosity(np.array([1e4]), np.array([10.0]), floor)[0] == pytest.approx(0.129)
    thin = lr.uniform_layer(0.004, 22.0, 1.0, n_cells=20, t_end=0.8, dt=1e-3)
    thin_f = lr.uniform_layer(0.004, 22.0, 1.0, n_cells=20, t_end=0.8, dt=1e-3, mat=floor)
    assert thin_f.t_stop < 0.8 * thin.t_stop
    thick = lr.uniform_layer(0.02, 22.0, 1.0, n_cells=20, t_end=0.6, dt=1e-3)
    thick_f = lr.uniform_layer(0.02, 22.0, 1.0, n_cells=20, t_end=0.6, dt=1e-3, mat=floor)
    assert np.max(np.abs(thick.mean_speed - thick_f.mean_speed)) < 2e-3
