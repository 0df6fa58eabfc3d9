"""Bed laws: the wall-friction kernels against plain NumPy, the robust rest rule, the
sliding-layer physics that tells a rough bed from a Coulomb block, config errors, energy."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from granudep.config import ConfigError
from granudep.isph import walls
from granudep.isph.analysis import moving_share, time_to_rest_mass_share
from granudep.isph.config import load_config
from granudep.isph.stepper import IsphSolver
from granudep.isph.verification import advance, layer_config

MU_S, MU_2, I0, D, RHO_S = math.tan(math.radians(25.5)), math.tan(math.radians(32.76)), 0.279, 7e-4, 2500.0


def _tangential(u, v, nx, ny):
    un = u * nx + v * ny
    return np.hypot(u - un * nx, v - un * ny)


def test_wall_friction_mu_i_is_the_bulk_law():
    iw = np.array([0.0, 1e-3, 0.1, 0.279, 3.0, 1e6])
    got = np.array([walls.wall_friction_mu_i(x, MU_S, MU_2, I0) for x in iw])
    ref = MU_S + (MU_2 - MU_S) * iw / (I0 + iw)
    np.testing.assert_allclose(got, ref, rtol=1e-14)
    assert walls.wall_friction_mu_i(np.inf, MU_S, MU_2, I0) == MU_2
    assert np.all(np.diff(got) > 0)


def _reaction_case(seed=3, n=40):
    rng = np.random.default_rng(seed)
    u, v = rng.normal(0, 0.5, n), rng.normal(0, 0.05, n)
    planes = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    a_n = np.where(rng.random((n, 2)) < 0.7, rng.uniform(0, 20, (n, 2)), -1.0)
    return u, v, planes, a_n


def test_mu_w_i_drag_matches_numpy():
    u, v, planes, a_n = _reaction_case()
    n, dt, eps, rho, dx, ell = u.size, 1e-4, 1e-4, 1550.0, 0.004, D
    du, dv = np.ones(n), np.ones(n)
    walls.mu_w_i_drag_from_reaction(n, (u, v), a_n, planes, (MU_S, MU_2, I0, D, RHO_S), (rho, dx, ell, dt, eps), (du, dv))
    ref_u, ref_v = np.ones(n), np.ones(n)
    for q, (nx, ny, _) in enumerate(planes):
        an = a_n[:, q]
        ut = _tangential(u, v, nx, ny)
        pw = rho * np.maximum(an, 0) * dx
        with np.errstate(divide="ignore", invalid="ignore"):
            iw = ut / ell * D / np.sqrt(pw / RHO_S)
            mu = MU_S + (MU_2 - MU_S) * iw / (I0 + iw)
        k = np.where(an > 0, mu * an / np.maximum(ut, eps), 0.0)
        ref_u += dt * k * ny * ny
        ref_v += dt * k * nx * nx
    np.testing.assert_allclose(du, ref_u, rtol=1e-12)
    np.testing.assert_allclose(dv, ref_v, rtol=1e-12)


def test_stress_limited_drag_is_the_smaller_of_no_slip_and_coulomb():
    u, v, planes, a_n = _reaction_case(5)
    n, dt, eps, rho, dx, mu = u.size, 1e-4, 1e-4, 1550.0, 0.004, MU_S
    rng = np.random.default_rng(9)
    kns = rng.uniform(0, 50, (n, 2))
    p = rng.uniform(10, 200, n)
    du, dv = np.zeros(n), np.zeros(n)
    walls.stress_limited_drag(n, (u, v), kns, p, a_n, planes, (mu, dx, dt, rho, eps), (du, dv))
    ref_u, ref_v = np.zeros(n), np.zeros(n)
    for q, (nx, ny, _) in enumerate(planes):
        an = a_n[:, q]
        ut = _tangential(u, v, nx, ny)
        scale = np.maximum(rho * np.maximum(an, 0) * dx / p, 1.0)
        k = np.where(an > 0, np.minimum(kns[:, q] * scale, mu * an / np.maximum(ut, eps)), 0.0)
        ref_u += dt * k * ny * ny
        ref_v += dt * k * nx * nx
    np.testing.assert_allclose(du, ref_u, rtol=1e-12)
    np.testing.assert_allclose(dv, ref_v, rtol=1e-12)


def test_mass_share_rest_ignores_one_straggler_that_the_every_particle_rule_waits_for():
    t = np.arange(0.0, 2.0, 0.01)
    n = 200
    u = np.zeros((t.size, n))
    u[t < 1.0, :] = 0.5                      # the mass flows until t = 1 s
    u[:, 0] = np.where(t < 1.5, 0.5, 0.0)    # one particle (0.5 % of the mass) until 1.5 s
    v = np.zeros_like(u)
    assert moving_share(u, v)[t.size // 4] == 1.0
    t99 = time_to_rest_mass_share(t, u, v, share=0.99, duration=0.1)
    assert t99 == pytest.approx(1.0)
    # the every-particle rule (share -> 1) waits for the straggler
    assert time_to_rest_mass_share(t, u, v, share=1 - 1e-9, duration=0.1) == pytest.approx(1.5)
    # never at rest for long enough: NaN
    assert math.isnan(time_to_rest_mass_share(t[:105], u[:105], v[:105], share=0.99, duration=0.1))
    with pytest.raises(ValueError, match="share"):
        time_to_rest_mass_share(t, u, v, share=1.0)


def _sliding_layer(slip: str, dx: float = 0.004, t_end: float = 0.3):
    cfg = load_config(layer_config(22.0, 0.02, dx, wall={"slip": slip}))
    s = IsphSolver(cfg)
    s.u[:] = 1.0
    advance(s, t_end)
    base = s.y[:s.nf] < dx
    mean = float(np.mean(s.u[:s.nf]))
    return (1.0 - mean) / t_end, float(np.mean(s.u[:s.nf][base])) / mean


def test_sliding_layer_tells_a_rough_bed_from_a_coulomb_block():
    """A plug launched at 1 m/s on a 22° bed: the Coulomb bed (φ_B = φ) lets it slide as a block
    (basal layer as fast as the mean, g(tan φ_B cosθ − sinθ) = 0.66 m/s²); the rough-bed laws hold
    the basal layer and the layer decelerates faster by shearing (measured at 2 mm: slip ratio
    0.02–0.12, 1.5–1.6 m/s², benchmarks/bed_laws.py --sliding-layer)."""
    block = 9.81 * (math.tan(math.radians(25.5)) * math.cos(math.radians(22)) - math.sin(math.radians(22)))
    dec_c, slip_c = _sliding_layer("coulomb")
    assert slip_c > 0.9
    assert dec_c == pytest.approx(block, rel=0.15)
    for law in ("no_slip", "mu_w_i"):
        dec, slip = _sliding_layer(law)
        assert slip < 0.4, law
        assert dec > 1.5 * block, law


def test_friction_laws_need_the_wall_reaction():
    for law in ("mu_w_i", "stress_limited"):
        with pytest.raises(ConfigError, match=f"wall.slip: {law} needs the walls' normal reaction"):
            load_config("T22-A70", **{"wall.slip": law, "numerics.projection": "approximate"})
    with pytest.raises(ConfigError, match="wall.slip_shear_length"):
        load_config("T22-A70", **{"wall.slip_shear_length": 0.0})
    with pytest.raises(ConfigError, match="wall.bed_stress"):
        load_config("T22-A70", **{"wall.bed_stress": "top"})


@pytest.mark.parametrize("law, bed_stress", [("mu_w_i", "bed"), ("stress_limited", "bed"), ("no_slip", "bed"),
                                             ("no_slip", "hydrostatic"), ("no_slip", "wall")])
def test_bed_laws_never_create_energy_on_a_collapse(law, bed_stress):
    from granudep.isph.api import run_isph
    ds = run_isph("T22-A70", progress=False, dx=0.008, t_end=0.6, **{"wall.slip": law, "wall.bed_stress": bed_stress})
    assert float(ds.attrs["energy_max_excess"]) <= 2e-3
    wall = float(ds["wall_friction_energy"].values[-1])
    assert 0.0 < wall < float(ds["dissipated_energy"].values[-1])


def test_the_step_asks_the_bed_law_and_reads_no_slip_code_of_its_own():
    """Every decision of the bed law is the law object's (``isph.bed``): the class per ``wall.slip``,
    its hooks, and no stage of the step testing a slip code itself."""
    import inspect
    from types import SimpleNamespace

    from granudep.isph import bed, stepper, walls
    kinds = {name: type(bed.bed_law(code)).__name__ for name, code in walls.SLIP_CODES.items()}
    assert kinds == {"no_slip": "ViscousWall", "navier": "ViscousWall", "free_slip": "NoWallTerm",
                     "coulomb": "FrictionWall", "mu_w_i": "FrictionWall", "stress_limited": "FrictionWall",
                     "navier_overwrite": "NavierOverwrite"}
    friction = bed.bed_law(walls.SLIP_COULOMB)
    assert friction.needs_contact(SimpleNamespace(reaction_friction=False))
    assert not friction.needs_contact(SimpleNamespace(reaction_friction=True))
    assert bed.bed_law(walls.SLIP_NAVIER_OVERWRITE).needs_velocity_gradient
    assert not bed.bed_law(walls.SLIP_NAVIER).needs_velocity_gradient
    cfg = SimpleNamespace(numerics=SimpleNamespace(h_factor=1.3, dx=0.004), wall_layers=3,
                          wall=SimpleNamespace(slip_length=0.018))
    assert bed.bed_law(walls.SLIP_NO).wall_norm(cfg, 1.25) == 1.25
    assert bed.bed_law(walls.SLIP_NAVIER).wall_norm(cfg, 1.25) != 1.25
    assert bed.bed_law(walls.SLIP_NAVIER_OVERWRITE).after_projection(SimpleNamespace(grad=None), None) is None
    src = inspect.getsource(stepper)
    for name in ("FRICTION_LAWS", "SLIP_NAVIER_OVERWRITE", "SLIP_COULOMB", "navier_overwrite(", 'slip == "navier"'):
        assert name not in src, name
