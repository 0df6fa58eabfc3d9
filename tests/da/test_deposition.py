"""Deposition (eqs 12, 14, 34, 36): conservation, the critical momentum switch, the x∞ iteration."""
import numpy as np
import pytest

from granudep.da.api import run_da
from granudep.da.physics import alpha_coefficient, critical_momentum, deposition_rate


def test_alpha_and_rate_follow_eq34_and_eq14():
    assert alpha_coefficient(0.02, 0.01, -1.0) == 0.0          # above (hu)_C: no deposition
    assert alpha_coefficient(0.005, 0.01, +1.0) == 0.0          # below but accelerating
    assert alpha_coefficient(0.005, 0.01, -1.0) == pytest.approx(0.5)
    assert alpha_coefficient(0.0, 0.01, -1.0) == pytest.approx(1.0)
    assert deposition_rate(0.5, -0.2, 1.0, 0.1) == pytest.approx(-0.1)
    assert deposition_rate(0.5, -0.2, 0.0, 0.1) == pytest.approx(-1.0)  # regularised 1/u
    # eq 36, normalised: p0 (A [x] + B), [x] clamped to [0, 1]
    assert critical_momentum(0.2, 0.2, 1.2, -0.03, 0.04, 2.0, True) == pytest.approx(0.08)
    assert critical_momentum(1.2, 0.2, 1.2, -0.03, 0.04, 2.0, True) == pytest.approx(0.02)
    assert critical_momentum(5.0, 0.2, 1.2, -0.03, 0.04, 2.0, True) == pytest.approx(0.02)


def test_volume_is_conserved_to_round_off(small_case):
    ds = run_da(small_case, x_inf_mode="user", x_inf=1.5)
    total = ds.flowing_volume.values + ds.deposited_volume.values
    v0 = 0.2 * 0.14
    assert ds.deposited_volume.values[-1] > 0.3 * v0           # deposition did happen
    assert np.max(np.abs(total - v0)) / v0 < 1e-13
    assert float(ds.volume_error) < 1e-13
    # the deposit grid holds what the particles lost, also per time
    np.testing.assert_allclose(ds.deposit_depth.sum("x_grid").values * 2e-3, ds.deposited_volume.values, rtol=1e-12)


def test_no_deposition_while_momentum_stays_above_critical(small_case):
    """With (hu)_C below every moving particle's momentum (B tiny, A = 0) nothing deposits and the
    run equals the run without deposition."""
    ds = run_da(small_case, ab_source="user", A=0.0, B=1e-12, x_inf_mode="user", x_inf=1.5)
    ref = run_da(small_case, deposition=False)
    assert float(ds.deposited_volume.max()) == 0.0
    np.testing.assert_array_equal(ds.x.values, ref.x.values)


def test_self_consistent_x_inf_converges_and_reports(small_case):
    ds = run_da(small_case)
    nodep = run_da(small_case, deposition=False)
    x_inf, L0 = ds.attrs["x_inf"], 0.2
    assert ds.attrs["x_inf_mode"] == "self-consistent" and ds.attrs["x_inf_iterations"] >= 2
    resid = abs(float(ds.front_position[-1]) - x_inf) / (x_inf - L0)
    assert resid == pytest.approx(ds.attrs["x_inf_residual"]) and resid <= 0.02
    assert float(ds.final_runout) < float(nodep.final_runout)   # deposition shortens the runout
    assert len(ds.x_inf_history) == ds.attrs["x_inf_iterations"]
