"""The energy bookkeeping of ``granudep.da.energy`` with deposition: the deposit booked as bed, so that
volume moved from the particles onto the grid at their own place changes E only by its kinetic energy,
and the energy rows of ``granudep verify da`` for runs with deposition."""
import math

import numpy as np
import pytest
import xarray as xr

from granudep.cases import G
from granudep.da.driver import smooth_deposit
from granudep.da.energy import energy_report, energy_series
from granudep.da.sph import deposit_to_grid, particle_depths

THETA = 22.0
QC = 3.0


def _two_states(fraction, L, dxg, u0=0.0, n=400):
    """A parabolic layer (0.6 m long, 0.1 m deep) on a 22° slope at two times: as released, and after
    every particle put ``fraction`` of its volume onto the grid at its own place (nothing moved)."""
    x = np.linspace(0.2, 0.8, n)
    dx = x[1] - x[0]
    V0 = (0.1 * (1.0 - ((x - 0.5) / 0.3) ** 2) + 1e-4) * dx
    ng = int(round(1.2 / dxg))
    fields = {k: [] for k in ("x", "u", "h", "volume", "deposit_depth", "deposited_volume")}
    for f in (0.0, fraction):
        V = V0 * (1.0 - f)
        dep = np.zeros(ng)
        for i in range(n):
            deposit_to_grid(dep, x[i], V0[i] * f, dxg)
        fields["x"].append(x)
        fields["u"].append(np.full(n, u0))
        fields["h"].append(particle_depths(x, V, L, QC, False))
        fields["volume"].append(V)
        fields["deposit_depth"].append(smooth_deposit(dep, max(L, dxg), QC, dxg))
        fields["deposited_volume"].append(dep.sum())
    dims = {"deposit_depth": ("time", "x_grid"), "deposited_volume": ("time",)}
    ds = xr.Dataset({k: (dims.get(k, ("time", "particle")), np.asarray(v)) for k, v in fields.items()},
                    coords={"x_grid": (np.arange(ng) + 0.5) * dxg})
    ds.attrs.update(theta_deg=THETA, dx_grid=dxg, deposition=1, phi_basal_deg=25.5)
    return ds, V0


def _hydrostatic(ds, k=0):
    return float((ds.volume[k] * G * math.cos(math.radians(THETA)) * ds.h[k] / 2.0).sum())


@pytest.mark.parametrize("dxg", [1e-3, 5e-3])
def test_moving_volume_onto_the_grid_keeps_the_energy(dxg):
    """Half of every particle's volume deposited in place: the two-layer hydrostatic energy
    ∫ g cosθ (h + h_D)²/2 is unchanged up to the smoothing error O((L/ℓ)²) = (0.01/0.3)² ≈ 1.1e-3 of it,
    while the flowing layer's own share drops by 1 − (1 − ½)² = 75 %."""
    ds, _ = _two_states(0.5, 0.01, dxg)
    E = energy_series(ds)
    hyd = _hydrostatic(ds)
    assert abs(E[1] - E[0]) < 1e-3 * hyd
    flow = _hydrostatic(ds, 1)
    assert (flow - hyd) / hyd == pytest.approx(-0.75, rel=1e-9)


def test_booking_error_is_second_order_in_the_smoothing_length():
    """Halving L (at dx_grid = 1 mm) divides the booking error by about 4: observed order ≥ 1.5."""
    errs = []
    for L in (0.01, 0.005):
        ds, _ = _two_states(0.5, L, 1e-3)
        E = energy_series(ds)
        errs.append(abs(E[1] - E[0]) / _hydrostatic(ds))
    assert math.log2(errs[0] / errs[1]) > 1.5


def test_deposited_volume_takes_its_kinetic_energy_with_it():
    """Deposition at u = 1 m/s: E drops by the kinetic energy of the deposited volume, Σ f V u²/2."""
    ds, V0 = _two_states(0.5, 0.01, 1e-3, u0=1.0)
    E = energy_series(ds)
    lost = 0.5 * float((0.5 * V0).sum())
    assert E[1] - E[0] == pytest.approx(-lost, abs=1e-3 * _hydrostatic(ds))


@pytest.fixture(scope="module")
def a70_deposition():
    from granudep.da.verification import energy_deposition_configs
    from granudep.da.api import run_da
    return run_da(energy_deposition_configs(300)["1D-A70"], deposition=True, progress=False)


def test_a_run_with_deposition_does_not_gain_energy(a70_deposition):
    """1D-A70 with deposition at N = 300 (two thirds of the volume deposited): E with the deposit booked
    never rises by more than the verify row's 1e-4 of E_0 − E_end; left out, it rises by percents."""
    from granudep.da.energy import largest_rise
    from granudep.da.verification import ENERGY_RISE_TOL
    ds = a70_deposition
    assert float(ds.deposited_volume[-1]) > 0.5 * float(ds.flowing_volume[0])
    rep = energy_report(ds)
    assert 0.0 < rep["coulomb_ratio"] <= 1.0
    assert rep["largest_rise"] <= ENERGY_RISE_TOL
    assert largest_rise(energy_series(ds, with_deposit=False))[0] > 100 * ENERGY_RISE_TOL


def test_the_rise_check_sees_energy_planted_in_a_deposition_run(a70_deposition):
    """The pile at rest set moving again at its last output with kinetic energy 1e-3 of E_0 − E_end
    (ten times the row's tolerance; energy from nowhere): the check reads the rise."""
    from granudep.da.verification import ENERGY_RISE_TOL
    ds = a70_deposition.copy(deep=True)
    E = energy_series(ds)
    planted = 1e-3 * (E[0] - E[-1])
    V = ds.volume.values[-1]
    du = math.sqrt(2.0 * planted / float(V.sum()))
    ds["u"][-1] = ds.u[-1] + du * (V > 0)
    rise = energy_report(ds)["largest_rise"]
    assert rise > ENERGY_RISE_TOL
    assert rise == pytest.approx(1e-3, rel=0.05)


def test_verify_rows_with_deposition_quick():
    """``granudep verify da --quick`` carries the two deposition energy rows, both passing."""
    from granudep.da.verification import check_energy_deposition
    rows = check_energy_deposition(quick=True)
    assert [r["quantity"] for r in rows] == ["W_min / (E0 - E_end), 1D-A70 with deposition",
                                             "largest rise of E between outputs / (E0 - E_end), 1D-A70 with deposition"]
    assert all(r["passed"] for r in rows)
