"""Energy budget of the ISPH runs: discrete dissipation and the creation stop."""
import numpy as np
import pytest
import scipy.sparse as sp

from granudep.isph.config import load_config
from granudep.isph.energy import kinetic_energy, potential_energy, viscous_dissipation
from granudep.isph.errors import IsphBlowUp
from granudep.isph.stepper import IsphSolver


def test_viscous_dissipation_is_the_work_of_the_operator():
    """For A = I + K (K symmetric positive semi-definite), u* = A⁻¹(uⁿ + Δt g):
    ΔD = m u*·K u* ≥ 0, read off the vectors alone."""
    rng = np.random.default_rng(1)
    n = 40
    b = rng.normal(size=(n, n))
    k = sp.csr_matrix(0.1 * b @ b.T)
    a = (sp.identity(n) + k).toarray()
    un, vn = rng.normal(size=n), rng.normal(size=n)
    dt, gx, gy, m = 1e-3, 3.0, -9.0, 2.5
    us = np.linalg.solve(a, un + dt * gx)
    vs = np.linalg.solve(a, vn + dt * gy)
    d = viscous_dissipation(m, un, vn, us, vs, dt, gx, gy)
    exact = m * (us @ (k @ us) + vs @ (k @ vs))
    assert d > 0 and np.isclose(d, exact, rtol=1e-10)


def test_energy_terms():
    assert np.isclose(kinetic_energy(2.0, np.array([1.0, 0.0]), np.array([0.0, 2.0])), 5.0)
    # slope frame: g = (g sinθ, −g cosθ); a particle at (1, 1) on the flat has E_pot = m g
    assert np.isclose(potential_energy(2.0, np.array([1.0]), np.array([1.0]), 0.0, -9.81), 2.0 * 9.81)


def _tiny(**kw):
    return load_config({"case": "tiny", "geometry": {"L0": 0.04, "H0": 0.04, "domain_length": 0.3},
                        "numerics": {"dx": 0.01, "t_end": 0.02}, "output": {"progress_every_s": 1e9}}, **kw)


def test_energy_creation_stops_the_run_naming_time_and_step():
    s = IsphSolver(_tiny())
    s.step(1e-4)
    s.energy.dissipated += 0.02 * s.energy.e_ref        # plant a 2 % gain
    with pytest.raises(IsphBlowUp, match=r"energy rose above E_0 by 2\.\d+ % of E_ref at t=.* step 1"):
        s._check_energy()


def test_granular_collapse_budget_closes_from_below():
    """A few steps of a μ(I) collapse: dissipation grows, and E_kin + E_pot + D never exceeds E_0."""
    s = IsphSolver(_tiny())
    for _ in range(30):
        s.step(s.time_step())
    eb = s.energy
    assert eb.dissipated > 0.0
    assert eb.residual(s.mechanical_energy()) / eb.e_ref < 1e-3
