"""The Navier bed (the paper's basal slip velocity): lattice normalisation, the analytic film and
Bagnold layer, the authors' overwrite form against a plain-NumPy reference, and its config checks."""
import math

import numpy as np
import pytest

from granudep.config import ConfigError
from granudep.isph import verification as v
from granudep.isph import walls
from granudep.isph.config import load_config
from granudep.isph.setup import lattice_constants


def _assert_rows(rows):
    for r in rows:
        assert r["passed"], f"{r['check']}: {r['quantity']} = {r['value']:.4g} (error {r['error']:.3g} > {r['tolerance']})"


def _linear_profile_stress(b, h_factor=1.3, layers=3, norm=None):
    """Σ_layers (y_i + b) Σ_w 2 F β (capped Morris β) for u = y + b on the unit lattice, divided by ``norm``."""
    from granudep.kernels import wendland_dwdr
    eps2 = 0.01 * h_factor ** 2
    total = 0.0
    for layer in range(int(math.ceil(2 * h_factor)) + 1):
        yi = layer + 0.5
        for xw in range(-6, 7):
            for lw in range(layers):
                yw = -(lw + 0.5)
                r = math.hypot(xw, yi - yw)
                if r >= 2 * h_factor:
                    continue
                f = -wendland_dwdr(r, h_factor) * r / (r * r + eps2)
                total += (yi + b) * 2.0 * f * min(1.5, (yi - yw) / (yi + b))
    return total / norm


@pytest.mark.parametrize("b", [0.0, 0.5, 1.0, 4.5, 9.0])
def test_each_slip_length_is_normalised_by_its_own_linear_profile(b):
    # the discrete wall stress of u = y + b is exactly eta du/dy = 1 with the law's own norm ...
    own = lattice_constants(1.3, 0.01, 3, b)["wall_ns"]
    assert _linear_profile_stress(b, norm=own) == pytest.approx(1.0, rel=1e-12)
    # ... and was 1.35 times that with the no-slip norm once b >= dx (an effective slip length ~0.73 b)
    no_slip = lattice_constants(1.3, 0.01, 3)["wall_ns"]
    if b >= 1.0:
        assert _linear_profile_stress(b, norm=no_slip) == pytest.approx(1.349, abs=2e-3)


def test_navier_film_matches_the_analytic_slip_profile_at_2_mm():
    # b = 4 and 18 mm at dx = 2 mm: relative L2 <= 5 % (measured 0.9 % and 0.27 %; the no-slip norm gave
    # an effective slip length of 0.73 b and a surface speed 16 % low at b = 18 mm)
    rows = v.navier_film(quick=True)
    assert len(rows) == 2
    _assert_rows(rows)
    b18 = [r for r in rows if "b = 18 mm" in r["quantity"]][0]
    b_eff = float(b18["note"].split("effective slip length ")[1].split(" mm")[0])
    assert abs(b_eff - 18.0) < 0.9  # within 5 % of the slip length in metres


@pytest.mark.slow
def test_navier_film_and_bagnold_at_both_resolutions():
    rows = v.navier_film(quick=False) + v.navier_bagnold(quick=False)
    checked = [r for r in rows if math.isfinite(r["tolerance"])]
    reported = [r for r in rows if not math.isfinite(r["tolerance"])]
    # the checked rows: the film at dx = 2 and 1 mm and the Bagnold layer at 1 and 0.5 mm, b = 4 and 18 mm
    assert sorted((r["check"], r["quantity"].split(", ", 1)[1]) for r in checked) == sorted(
        [("navier_film", f"b = {b} mm, dx = {dx} mm") for b in (4, 18) for dx in (2, 1)]
        + [("navier_bagnold", f"b = {b} mm, dx = {dx} mm") for b in (4, 18) for dx in (1, 0.5)])
    _assert_rows(checked)
    # the reported rows: the Bagnold layer at the coarse dx (2 mm at least), never "passed"
    assert {r["quantity"] for r in reported if "dx = 2 mm" in r["quantity"]} == {
        f"relative L2 error of u(y), b = {b} mm, dx = 2 mm (reported: collapse resolution)" for b in (4, 18)}
    assert all(r["check"] == "navier_bagnold" and not r["passed"] for r in reported)
    # ... and each reads a layer that flows with the slip-shifted Bagnold profile, coarsely resolved: a
    # relative L2 error of 1 is a layer at rest (u = 0) and one that runs away reads above 1, while a
    # profile of the right shape within half its magnitude reads below 0.5 (at 2 mm: 5.6 % and 3.6 %)
    for r in reported:
        assert math.isfinite(r["value"]) and 0.0 < r["value"] < 0.5, (r["quantity"], r["value"])


def _overwrite_reference(x, y, grad, wx, wy, wnx, wny, nf, band, ls, u, v):
    """Plain NumPy twin of :func:`walls.navier_overwrite` (all-pairs distances)."""
    u, v = u.copy(), v.copy()
    for i in range(nf):
        d = np.hypot(wx - x[i], wy - y[i])
        k = int(np.argmin(d))
        if not d[k] < band:
            continue
        n = np.array([wnx[k], wny[k]])
        g = np.array([[2 * grad[i, 0], grad[i, 1] + grad[i, 2]], [grad[i, 1] + grad[i, 2], 2 * grad[i, 3]]])
        t = (np.eye(2) - np.outer(n, n)) @ g @ n
        u[i], v[i] = ls * t
    return u, v


def test_navier_overwrite_kernel_matches_numpy_reference():
    from granudep.isph.bundles import WallSurface, pairs_of
    rng = np.random.default_rng(3)
    dx = 0.004
    gx, gy = np.meshgrid(np.arange(8) * dx + dx / 2, np.arange(4) * dx + dx / 2)
    x = gx.ravel() + rng.normal(0, 0.05 * dx, gx.size)
    y = gy.ravel() + rng.normal(0, 0.05 * dx, gx.size)
    nf = x.size
    wxg, wyg = np.meshgrid(np.arange(-2, 10) * dx + dx / 2, -(np.arange(3) + 0.5) * dx)
    wx, wy = wxg.ravel(), wyg.ravel()
    nw = wx.size
    wnx, wny = np.zeros(nw), np.ones(nw)
    surf = WallSurface(nx=wnx, ny=wny, c=np.zeros(nw))
    xa, ya = np.concatenate((x, wx)), np.concatenate((y, wy))
    nb = pairs_of(xa, ya, nf, 2 * 1.3 * dx, 0.0, 1.3 * dx)
    grad = rng.normal(size=(nf, 4))
    u0, v0 = rng.normal(size=nf), rng.normal(size=nf)
    band, ls = walls.OVERWRITE_BAND * dx, 0.006
    u, vv = u0.copy(), v0.copy()
    n = walls.navier_overwrite(nb, nf, grad, u, vv, surf, band, ls)
    ru, rv = _overwrite_reference(x, y, grad, wx, wy, wnx, wny, nf, band, ls, u0, v0)
    assert n == 8  # the first layer only
    np.testing.assert_allclose(u, ru, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(vv, rv, rtol=1e-12, atol=1e-15)
    assert np.all(vv[:8] == 0.0)  # no normal component at a horizontal bed


def test_navier_overwrite_beyond_two_dx_is_refused():
    with pytest.raises(ConfigError, match=r"wall.slip_length: must be <= 2 dx"):
        load_config("T22-A70", **{"wall.slip": "navier_overwrite", "wall.slip_length": 0.018})
    load_config("T22-A70", **{"wall.slip": "navier_overwrite", "wall.slip_length": 0.008})


def test_navier_without_slip_length_is_refused():
    with pytest.raises(ConfigError, match=r"wall.slip_length: must be > 0 for wall.slip: navier"):
        load_config("T22-A70", **{"wall.slip": "navier", "wall.slip_length": 0.0})


def test_default_bed_is_the_papers_navier_slip():
    cfg = load_config("T22-A70")
    assert cfg.wall.slip == "navier" and cfg.wall.slip_length == 0.018
    assert cfg.material.mu_s == pytest.approx(math.tan(math.radians(25.5)))
    assert cfg.material.I0_standard == 0.279


def test_friction_and_inertial_number_conventions():
    cfg = load_config("T22-A70", **{"material.mu_s_form": "sin_phi", "material.inertial_number": "doubled"})
    assert cfg.case == "T22-A70"  # a convention of the paper's model, not another material
    assert cfg.material.mu_s == pytest.approx(math.sin(math.radians(25.5)))
    assert cfg.material.I0_standard == pytest.approx(0.1395)
    with pytest.raises(ConfigError, match=r"material.mu_s_form"):
        load_config("T22-A70", **{"material.mu_s_form": "cot_phi"})
