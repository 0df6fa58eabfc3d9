"""The earth-pressure switch (``numerics.earth_pressure_switch``): the symmetric pair-form pass against
its dense NumPy twin, its limits, the energy identity it is built on, and the energy checks of
``granudep.da.energy``."""
import math

import numpy as np
import pytest

import naive_da as nv
from granudep.config import ConfigError
from granudep.da.config import resolve
from granudep.da.sph import S_DH, S_DU, S_KB, evaluate_into, new_stage, new_window, symmetric_pressure_gradient


def _lattice(n=160, wall=False, seed=3):
    rng = np.random.default_rng(seed)
    dx = 1e-3
    x = np.sort((np.arange(n) + 0.5) * dx + rng.uniform(-0.2, 0.2, n) * dx + (0.0 if wall else 0.05))
    V = dx * (0.1 + 0.5 * x) * (1.0 + 0.1 * rng.uniform(-1, 1, n))
    u = 0.3 - 2.0 * x + 0.05 * rng.uniform(-1, 1, n)
    return x, u, V, 4 * dx, 3.0


def _kernel_pass(x, u, V, L, qc, wall, k):
    n = x.size
    W, S = new_window(n), new_stage(n)
    E = evaluate_into(x, u, V, L, qc, wall, W, S, np.empty(0))
    dh, du = S[S_DH].copy(), S[S_DU].copy()
    symmetric_pressure_gradient(x, L, qc, wall, W, E, k, np.empty(2 * n), S)
    return S[S_DH], S[S_KB], dh, du


@pytest.mark.parametrize("wall", [False, True])
def test_symmetric_pass_matches_dense_numpy(wall):
    x, u, V, L, qc = _lattice(wall=wall)
    rng = np.random.default_rng(5)
    k = np.where(rng.uniform(size=x.size) < 0.5, 0.9, 2.0)      # mixed states: every pair kind occurs
    kdh, kbar, _, _ = _kernel_pass(x, u, V, L, qc, wall, k)
    ref, refbar = nv.symmetric_pressure(x, V, L, qc, wall, k)
    assert np.max(np.abs(kdh - ref)) <= 1e-13 * np.max(np.abs(ref))
    assert np.max(np.abs(kbar - refbar)) <= 1e-13


def test_uniform_k_is_k_times_the_depth_gradient():
    """With one k everywhere the pair form is k ∂h/∂x of eqs 21-22 (the operator the analytic checks verify)."""
    x, u, V, L, qc = _lattice()
    kdh, kbar, dh, _ = _kernel_pass(x, u, V, L, qc, False, np.full(x.size, 2.5))
    assert np.max(np.abs(kdh - 2.5 * dh)) <= 1e-13 * np.max(np.abs(dh))
    assert np.allclose(kbar, 2.5, rtol=0, atol=1e-14)


def test_pair_form_power_is_minus_sum_of_k_minus_one_times_dh_dt():
    """The identity behind the switch (no Shepard factor: interior particles, full support):
    Σ_i V_i u_i a_i + d/dt Σ_i V_i g h_i/2 = −(g/2) Σ_i V_i (k_i − 1) dh_i/dt, with a_i the pair-form
    acceleration and dh_i/dt = Σ_j V_j ∇W_ij (u_j − u_i); dense NumPy, a periodic-free interior block."""
    x, u, V, L, qc = _lattice(n=120)
    g = 9.81
    r = x[:, None] - x[None, :]
    _, gW = nv.kernel(r, L, qc)
    k = np.where(np.random.default_rng(1).uniform(size=x.size) < 0.5, 0.9, 2.0)
    a = g * np.sum(V[None, :] * 0.5 * (k[:, None] + k[None, :]) * gW, axis=1)
    dhdt = np.sum(V[None, :] * gW * (u[None, :] - u[:, None]), axis=1)
    lhs = np.sum(V * u * a) + np.sum(V * g * dhdt / 2.0)
    rhs = -(g / 2.0) * np.sum(V * (k - 1.0) * dhdt)
    assert lhs == pytest.approx(rhs, rel=1e-10, abs=1e-14 * np.sum(np.abs(V * u * a)))


def test_switch_sign_is_the_sign_of_minus_dh_dt():
    """k_i comes from the sign of the corrected ∂u/∂x_i (eqs 28-29); its sign is that of −dh_i/dt of
    the SPH continuity sum, so k_p goes exactly with dh_i/dt > 0 — the condition of the identity above."""
    x, u, V, L, qc = _lattice()
    _, _, _, du = _kernel_pass(x, u, V, L, qc, False, np.ones(x.size))
    r = x[:, None] - x[None, :]
    _, gW = nv.kernel(r, L, qc)
    dhdt = np.sum(V[None, :] * gW * (u[None, :] - u[:, None]), axis=1)
    nz = np.abs(dhdt) > 1e-12 * np.max(np.abs(dhdt))
    assert np.all(np.sign(du[nz]) == -np.sign(dhdt[nz]))


def test_switch_option_is_validated():
    assert resolve("1D-A70").numerics.earth_pressure_switch == "strain"
    assert resolve("1D-A70", earth_pressure_switch="symmetric").numerics.earth_pressure_switch == "symmetric"
    with pytest.raises(ConfigError, match="earth_pressure_switch"):
        resolve("1D-A70", earth_pressure_switch="pairwise")
    with pytest.raises(ConfigError, match="earth_pressure_strain"):
        resolve("1D-A70", earth_pressure_strain=0.0)
    with pytest.raises(ConfigError, match="earth_pressure_strain"):
        resolve("1D-A70", earth_pressure_strain=1.5)


def _strained(k, rates, dt, ka, kp, eps):
    from granudep.da.physics import earth_pressure_strained
    out = []
    for r in rates:
        k = earth_pressure_strained(k, r, dt, ka, kp, 1.0 / eps)
        out.append(k)
    return np.array(out)


def test_strained_k_reaches_eqs_8_9_after_the_strain_eps():
    """Sustained compression (∂u/∂x < 0) takes k from 1 to k_p after a strain (k_p − 1)/(k_p − k_a) ε_k and
    holds it there; sustained stretching then takes it down to k_a after a strain ε_k: eqs 8–9 in a flow."""
    ka, kp, eps, dt = 0.893, 2.017, 0.05, 1e-3
    rate = -2.0                                                     # 2 s⁻¹ compression: strain 2e-3 per step
    k = _strained(1.0, [rate] * 40, dt, ka, kp, eps)
    strain_to_kp = (kp - 1.0) / (kp - ka) * eps
    n_steps = strain_to_kp / (abs(rate) * dt)                       # 22.6 steps
    assert k[int(n_steps) - 1] < kp and k[int(n_steps) + 1] == kp and k[-1] == kp
    assert k[0] == pytest.approx(1.0 + (kp - ka) / eps * abs(rate) * dt, rel=1e-14)
    back = _strained(kp, [-rate] * 40, dt, ka, kp, eps)           # stretching: down to k_a after ε_k
    assert back[int(eps / (abs(rate) * dt)) + 1] == ka and back[10] > ka


def test_strained_k_keeps_its_value_under_a_jittering_strain_rate():
    """A pile whose ∂u/∂x flips sign from step to step (the state that pumped energy with the sign switch)
    keeps its k within the strain it actually undergoes, instead of jumping between k_a and k_p."""
    ka, kp, eps, dt = 0.893, 2.017, 0.05, 1e-4
    rates = 0.3 * np.where(np.arange(200) % 2 == 0, 1.0, -1.0)      # ±0.3 s⁻¹, alternating
    k = _strained(1.5, rates, dt, ka, kp, eps)
    assert np.ptp(k) <= (kp - ka) / eps * 0.3 * dt * 1.000001      # one step's strain, 6.7e-4
    assert abs(k[-1] - 1.5) < 1e-12


def test_strained_wave_factor_is_the_elastic_wave_speed():
    """dP/dh of P = k g h²/2 with dk = (k_p − k_a)/ε_k dh/h, at k = k_p, over g h."""
    from granudep.da.physics import earth_pressure_wave_factor
    ka, kp, eps, g, h = 0.893, 2.017, 0.05, 9.81, 0.04
    S = (kp - ka) / eps
    P = lambda hh, k: k * g * hh ** 2 / 2.0                         # noqa: E731
    dh = 1e-7
    dPdh = (P(h + dh, kp + S * dh / h) - P(h - dh, kp - S * dh / h)) / (2 * dh)
    assert earth_pressure_wave_factor(ka, kp, 1.0 / eps) == pytest.approx(dPdh / (g * h), rel=1e-6)


def test_k_one_runs_are_the_same_with_either_switch():
    """earth_pressure 'one' does not read the switch: bit for bit the same run."""
    from granudep.da.api import run_da
    base = {"case": "1D-A70", "numerics": {"n_particles": 120, "earth_pressure": "one", "t_end": 0.3},
            "output": {"dt_output": 0.1}}
    a = run_da(base, deposition=False)
    b = run_da({**base, "numerics": {**base["numerics"], "earth_pressure_switch": "symmetric"}}, deposition=False)
    assert np.array_equal(a.x.values, b.x.values) and np.array_equal(a.u.values, b.u.values)


@pytest.mark.parametrize("switch", ["particle", "symmetric", "strain"])
def test_energy_checks_pass_on_a_small_collapse(switch):
    """1D-A70 at N = 200 without deposition: W_min/ΔE below 1 and E never rising between outputs."""
    from granudep.da.api import run_da
    from granudep.da.energy import energy_report
    ds = run_da({"case": "1D-A70", "numerics": {"n_particles": 200, "earth_pressure_switch": switch, "t_end": 4.0}},
                deposition=False)
    rep = energy_report(ds)
    assert 0.9 < rep["coulomb_ratio"] <= 1.0
    assert rep["n_rises"] == 0 and rep["largest_rise"] <= 1e-9
    assert math.isfinite(float(ds.final_runout))


def test_doubling_study_table_and_converged_n():
    """``granudep da --convergence``: one run per N of the ladder, change per doubling, energy columns."""
    from granudep.da.convergence import converged_n, doubling_study, format_table, ladder
    assert ladder(250, 2000) == [250, 500, 1000, 2000]
    df = doubling_study("1D-A70", False, 60, 240, t_end=4.0)
    assert list(df.n) == [60, 120, 240]
    assert not np.isfinite(df.change_per_doubling.iloc[0])
    assert np.all(df.coulomb_ratio <= 1.0) and np.all(df.n_energy_rises == 0)
    text = format_table(df)
    assert "converged N" in text and "W_min/dE" in text
    fake = df.assign(change_per_doubling=[np.nan, 0.05, 0.004])
    assert converged_n(fake) == 120
    assert converged_n(fake.assign(change_per_doubling=[np.nan, 0.05, 0.02])) is None


def test_cli_convergence_writes_the_study(tmp_path, capsys):
    from granudep.cli import main
    out = tmp_path / "study.csv"
    rc = main(["da", "1D-A70", "--no-deposition", "--convergence", "--n-min", "60", "--n-max", "120", "-o", str(out),
               "--set", "numerics.t_end=3.0"])
    assert rc == 0 and out.exists()
    text = capsys.readouterr().out
    assert "doubling study" in text and "converged N" in text


@pytest.mark.slow
def test_energy_row_passes_with_the_strain_switch_and_fails_with_the_particle_switch():
    """The verify row on the 1 km path at N = 4000: the sign switch of eqs 8-9 (particle) gains energy
    there (a rise of E late in the run), the strained k (the default) does not."""
    from granudep.da.verification import check_energy
    good = check_energy()
    assert all(r["passed"] for r in good), good
    bad = check_energy(switch="particle")
    assert not all(r["passed"] for r in bad), bad
