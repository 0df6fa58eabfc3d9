"""Regression on planted section time series: onset, deposition rate, (hu)_C, A/B, tables."""
from __future__ import annotations

import logging
import math

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from granudep import cases
from granudep.config import ConfigError
from granudep.io import check_contract, provenance, var
from granudep.regress.api import regress
from granudep.abtable import interpolate_ab
from granudep.regress.coefficients import coefficient_table
from granudep.regress.paper_tables import table3_comparison, table5_comparison
from granudep.regress.config import RegressConfig
from granudep.regress.critical import growth_fit, linear_fit, onset_time, value_at

DX = 0.004


def make_sections(case="T22-A70", theta_deg=22.0, L0=0.2, H0=0.14, x_inf=0.6, dx=DX,
                  t_onset=None, rate=0.01, A=-0.03, B=0.04, c=0.02, t_end_s=16.0, nt=401, noise=0.0, seed=0):
    """Sections with h_D/H0 = rate (t_s − t_onset_k) (clipped to [0, 0.2]) and hu/p0 linear in t_s,
    planted so that hu/p0 = A [x] + B exactly at the rule onset (h_D = dx/2)."""
    n = 11
    xn = np.arange(n) / 10
    t_onset = 5.0 + 4.0 * xn if t_onset is None else np.asarray(t_onset, float)
    theta = math.radians(theta_deg)
    t_c = cases.characteristic_time(H0, theta)
    p0 = cases.momentum_scale(H0, theta)
    ts = np.linspace(0.0, t_end_s, nt)
    hd = H0 * np.clip(rate * (ts[None, :] - t_onset[:, None]), 0.0, 0.2)
    t_rule = t_onset + 0.5 * dx / (H0 * rate)
    rng = np.random.default_rng(seed)
    mc = A * xn + B + noise * rng.standard_normal(n)
    mom = p0 * (mc[:, None] + c * (t_rule[:, None] - ts[None, :]))
    ds = xr.Dataset(
        {"deposit_depth": var(hd, ("section", "time"), "m", "h_D"),
         "momentum": var(mom, ("section", "time"), "m2 s-1", "hu")},
        coords={"section": var(np.arange(n), ("section",), "1", "k"),
                "time": var(ts * t_c, ("time",), "s", "time"),
                "x": var(L0 + xn * (x_inf - L0), ("section",), "m", "x"),
                "x_norm": var(xn, ("section",), "1", "[x]")})
    ds.attrs.update(theta_deg=theta_deg, L0=L0, H0=H0, dx=dx, x_inf=x_inf)
    provenance(ds, case=case, config_yaml="synthetic: true\n", command="tests")
    return ds, {"t_onset": t_onset, "t_rule": t_rule, "mc": mc, "p0": p0}


def test_linear_fit_exact_and_r2():
    s, b, r2, n = linear_fit([0, 1, 2, 3], [1, 3, 5, 7])
    assert (s, b, r2, n) == pytest.approx((2.0, 1.0, 1.0, 4))
    s, b, r2, n = linear_fit([0, 1, 2], [0, 1, 0])
    assert s == pytest.approx(0.0) and r2 == pytest.approx(0.0)
    assert math.isnan(linear_fit([1.0], [2.0])[0])


def test_onset_rules():
    t = np.arange(10.0)
    hd = np.array([np.nan, 0, 0, 0.3, 0, 0, 0.5, 1.0, 1.5, 2.0])
    tc, i, status = onset_time(t, hd, 0.25)
    # the blip at t = 3 is not an onset: the last upward crossing is between t = 5 and 6
    assert status == "ok" and i == 6 and tc == pytest.approx(5.5)
    assert math.isnan(onset_time(t, np.ones(10), 0.25)[0])            # deposited from the start
    assert onset_time(t, np.ones(10), 0.25)[2] == "deposited from the first record"
    assert math.isnan(onset_time(t, np.r_[np.zeros(5), np.ones(4), 0.0], 0.25)[0])  # did not persist
    # a momentary re-mobilisation (one sample back to h_D = 0) is bridged when max_gap allows it
    hd = np.array([0, 0, 0.5, 1.0, 0, 1.0, 1.0, 1.0, 1.0, 1.0])
    assert onset_time(t, hd, 0.25)[0] == pytest.approx(4.25)                 # max_gap = 0: never bridged
    assert onset_time(t, hd, 0.25, max_gap=1.9)[0] == pytest.approx(4.25)    # around-gap samples 2 apart
    tc, i, status = onset_time(t, hd, 0.25, max_gap=2.0)
    assert (tc, i, status) == (pytest.approx(1.5), 2, "ok")
    # … and the growth fit leaves the bridged (empty) sample out
    rate, t_fit, r2, n = growth_fit(t, hd, i, 0.95, 2)
    assert n == 2 and rate == pytest.approx(0.5) and t_fit == pytest.approx(1.0)
    # bridging back to the first record means no onset was observed
    assert onset_time(t, np.r_[1.0, 0, np.ones(8)], 0.25, max_gap=2.0)[2] == "deposited from the first record"


def test_planted_ramp_gives_onset_time_and_rate():
    ds, truth = make_sections(rate=0.013)
    crit = regress(ds)["critical"]
    assert len(crit) == 11
    # rule onset: where the ramp crosses dx/2 (linear interpolation of linear data: exact)
    np.testing.assert_allclose(crit.t_s_critical, truth["t_rule"], atol=1e-9)
    # Fig-9 intercept of the growth-phase line: the planted start of growth
    np.testing.assert_allclose(crit.t_s_critical_fit, truth["t_onset"], atol=1e-9)
    np.testing.assert_allclose(crit.deposition_rate, 0.013, rtol=1e-9)
    np.testing.assert_allclose(crit.r2, 1.0, atol=1e-12)
    np.testing.assert_allclose(crit.momentum_critical_norm, truth["mc"], atol=1e-9)
    assert set(["case", "theta_deg", "a", "x_norm", "t_s_critical", "t_s_critical_fit", "deposition_rate",
                "r2", "momentum_critical_norm"]) <= set(crit.columns)


def test_growth_fit_stops_at_the_plateau():
    t = np.linspace(0, 10, 101)
    hd = np.clip(0.1 * (t - 2.0), 0, 0.3)  # grows from t = 2 to t = 5 then flat
    tc, i, _ = onset_time(t, hd, 0.015)
    rate, t_fit, r2, n = growth_fit(t, hd, i, 0.95, 3)
    assert rate == pytest.approx(0.1, rel=1e-9) and t_fit == pytest.approx(2.0, abs=1e-9)
    assert r2 == pytest.approx(1.0) and n == 28  # t = 2.2 … 4.9 (0.95·0.3 reached at t = 4.85 → 4.9)
    assert math.isnan(growth_fit(t, hd, -1, 0.95, 3)[0])


def test_value_at_interpolates_and_refuses_outside():
    assert value_at([0, 1, 2], [0, 10, 20], 1.5) == pytest.approx(15.0)
    assert math.isnan(value_at([0, 1, 2], [0, 10, 20], 2.5))
    assert math.isnan(value_at([0, 1, 2], [0, 10, 20], math.nan))


def test_planted_ab_recovered():
    ds, truth = make_sections(A=-0.031, B=0.0402)
    coeffs = regress(ds)["coefficients"]
    row = coeffs.iloc[0]
    assert row.A == pytest.approx(-0.031, abs=1e-9) and row.B == pytest.approx(0.0402, abs=1e-9)
    assert row.r2 == pytest.approx(1.0, abs=1e-12) and row.n_sections == 11
    # with planted scatter the fit still finds A, B within the scatter's standard error
    ds, truth = make_sections(A=-0.031, B=0.0402, noise=0.001, seed=3)
    row = regress(ds)["coefficients"].iloc[0]
    A_ref, B_ref, r2_ref, _ = linear_fit(np.arange(11) / 10, truth["mc"])
    assert row.A == pytest.approx(A_ref, abs=1e-9) and row.B == pytest.approx(B_ref, abs=1e-9)
    assert abs(row.A + 0.031) < 0.003 and 0.9 < row.r2 < 1.0


def test_fit_range_restricts_sections():
    ds, _ = make_sections()
    coeffs = regress(ds, fit_x_min=0.2, fit_x_max=0.8)["coefficients"]
    assert coeffs.n_sections.iloc[0] == 7 and coeffs.x_norm_used.iloc[0] == "0.2;0.3;0.4;0.5;0.6;0.7;0.8"
    with pytest.raises(ConfigError, match="regress.fit_x_max: must be > fit_x_min"):
        regress(ds, fit_x_min=0.8, fit_x_max=0.2)


def test_too_few_onsets_give_nan_ab_with_warning(caplog):
    ds, _ = make_sections(t_onset=np.r_[5.0, 6.0, np.full(9, 99.0)])  # only two sections deposit
    with caplog.at_level(logging.WARNING, logger="granudep"):
        out = regress(ds)
    row = out["coefficients"].iloc[0]
    assert math.isnan(row.A) and math.isnan(row.B) and row.n_sections == 2
    assert "need 3" in row.note and "need 3" in caplog.text
    assert out["critical"].status.tolist().count("no deposit at the end of the record") == 9


def _ab_table():
    rows = []
    for theta, aspects in ((16.0, (0.35, 0.5, 1.0, 1.2)), (22.0, (0.35, 0.5, 0.7, 1.0, 1.2, 1.5))):
        for a in aspects:
            rows.append({"case": f"T{theta:g}-A{round(100 * a)}", "theta_deg": theta, "a": a,
                         "A": -0.05 * a ** 2 + 0.001 * theta, "B": 0.1 / (1 + a) - 0.002 * theta, "r2": 0.99})
    return pd.DataFrame(rows)


def test_interpolate_ab_exact_on_nodes_and_linear_between(tmp_path):
    table = _ab_table()
    for _, r in table.iterrows():
        assert interpolate_ab(table, r.a, r.theta_deg) == pytest.approx((r.A, r.B), abs=1e-15)
    # between two a nodes at a node θ: the mean of the two nodes
    A, B = interpolate_ab(table, 0.6, 22.0)
    r05, r07 = table[(table.theta_deg == 22) & (table.a == 0.5)].iloc[0], table[(table.theta_deg == 22) & (table.a == 0.7)].iloc[0]
    assert (A, B) == pytest.approx(((r05.A + r07.A) / 2, (r05.B + r07.B) / 2), abs=1e-15)
    # between θ rows at a node a common to both: linear in θ
    A, B = interpolate_ab(table, 1.0, 20.0)
    n16 = table[(table.theta_deg == 16) & (table.a == 1.0)].iloc[0]
    n22 = table[(table.theta_deg == 22) & (table.a == 1.0)].iloc[0]
    assert (A, B) == pytest.approx((n16.A + (n22.A - n16.A) * 4 / 6, n16.B + (n22.B - n16.B) * 4 / 6), abs=1e-15)
    # the CSV path works the same
    path = tmp_path / "coefficients.csv"
    table.to_csv(path, index=False)
    assert interpolate_ab(path, 0.6, 22.0) == pytest.approx(interpolate_ab(table, 0.6, 22.0), abs=0)


def test_interpolate_ab_refuses_outside_unless_asked():
    table = _ab_table()
    with pytest.raises(ConfigError, match=r"a: 2.0 is outside the coefficient table's range \[0.35, 1.5\] at theta_deg = 22"):
        interpolate_ab(table, 2.0, 22.0)
    with pytest.raises(ConfigError, match=r"theta_deg: 30.0 is outside the coefficient table's range \[16, 22\]"):
        interpolate_ab(table, 0.7, 30.0)
    # θ between rows: the a-range is the one both rows cover (θ = 16 stops at 1.2)
    with pytest.raises(ConfigError, match=r"a: 1.5 is outside .*\[0.35, 1.2\] at theta_deg = 16 and 22"):
        interpolate_ab(table, 1.5, 19.0)
    with pytest.raises(ConfigError, match="a: must be a finite number > 0"):
        interpolate_ab(table, -1.0, 22.0)
    # extrapolation on request: linear from the two nearest nodes (exact for data linear in a, θ)
    lin = table.assign(A=-0.02 * table.a + 0.001 * table.theta_deg, B=0.05 - 0.01 * table.a)
    A, B = interpolate_ab(lin, 2.0, 25.0, extrapolate=True)
    assert (A, B) == pytest.approx((-0.04 + 0.025, 0.03), abs=1e-12)


def test_table3_comparison_reports_differences():
    ds, truth = make_sections(case="T22-A70")
    crit = regress(ds)["critical"]
    t3 = table3_comparison(crit)
    assert t3.x_norm.tolist() == [0.2, 0.4, 0.6, 0.8] and t3.section.tolist() == [2, 4, 6, 8]
    paper = [7.90, 8.83, 9.95, 11.04]
    assert t3.t_s_critical_paper.tolist() == paper
    np.testing.assert_allclose(t3.abs_diff, truth["t_rule"][[2, 4, 6, 8]] - paper, atol=1e-9)
    np.testing.assert_allclose(t3.rel_diff_pct, 100 * (truth["t_rule"][[2, 4, 6, 8]] - paper) / paper, atol=1e-9)
    np.testing.assert_allclose(t3.abs_diff_fit, truth["t_onset"][[2, 4, 6, 8]] - paper, atol=1e-9)
    assert table3_comparison(crit.assign(case="SYN")).empty  # no paper row: no comparison invented


def test_table5_comparison_maps_cases_and_units():
    coeffs = pd.DataFrame([{"case": f"T22-A{n}", "theta_deg": 22.0, "a": a, "L0": L0, "H0": H0,
                            "A": -0.05, "B": 0.06, "r2": 0.98, "n_sections": 9, "x_norm_used": "",
                            "p0": cases.momentum_scale(H0, math.radians(22.0)), "note": ""}
                           for n, a, L0, H0 in ((30, 0.3, 0.3, 0.09), (45, 0.45, 0.25, 0.1125),
                                                (70, 0.7, 0.2, 0.14), (124, 1.24, 0.15, 0.186))])
    t5 = table5_comparison(coeffs)
    assert t5.case.tolist() == ["1D-A30", "1D-A45", "1D-A70", "1D-A124"]
    assert t5.run_case.tolist() == ["T22-A30", "T22-A45", "T22-A70", "T22-A124"]
    # the paper's own number: p0 = 0.0814 m²/s for a = 0.3 (Section 4.3), which its printed B equals
    assert t5.p0.iloc[0] == pytest.approx(0.0814, abs=5e-5)
    assert t5.B_paper.iloc[0] == pytest.approx(t5.p0.iloc[0], abs=5e-5)
    # B·p0 of the printed values is ≈ 0.0065 m²/s for every case (within 6 %)
    assert np.all(np.abs(t5.B_paper_times_p0 / 0.0065 - 1) < 0.06)
    np.testing.assert_allclose(t5.A_abs_diff, -0.05 - t5.A_paper, atol=1e-15)
    np.testing.assert_allclose(t5.B_rel_diff_pct, 100 * (0.06 - t5.B_paper) / t5.B_paper, atol=1e-12)


def test_coefficients_dataset_contract_and_duplicate_refused():
    ds1, _ = make_sections(case="T22-A70")
    ds2, _ = make_sections(case="T16-A50", theta_deg=16.0, H0=0.10, A=-0.05, B=0.07)
    out = regress([ds1, ds2])
    nc = out["coefficients_nc"]
    check_contract(nc)
    assert nc.A.dims == ("case",) and nc.A_grid.dims == ("theta_grid", "aspect_ratio_grid")
    assert float(nc.A_grid.sel(theta_grid=16.0, aspect_ratio_grid=0.5)) == pytest.approx(-0.05, abs=1e-9)
    assert np.isnan(float(nc.A_grid.sel(theta_grid=16.0, aspect_ratio_grid=0.7)))
    with pytest.raises(ConfigError, match="given more than once"):
        regress([ds1, ds1])
    with pytest.raises(ConfigError, match="sections: file not found"):
        regress(["/nonexistent.nc"])


def test_regress_config_refuses_bad_values():
    with pytest.raises(ConfigError, match="regress.onset_depth_factor: must be > 0"):
        regress(make_sections()[0], onset_depth_factor=0.0)
    assert RegressConfig().fit_x_min == 0.0 and RegressConfig().fit_x_max == 1.0


def test_incomplete_run_noted_in_coefficients():
    ds, _ = make_sections()
    ds.attrs["run_complete"] = 0
    row = regress(ds)["coefficients"].iloc[0]
    assert "did not reach rest" in row.note and np.isfinite(row.A)  # fitted, but flagged
    assert regress(make_sections()[0])["coefficients"].note.iloc[0] == ""


def test_diagnosis_reads_hu_at_the_papers_critical_times_for_a_table3_case():
    from granudep.regress.diagnose import diagnose_case
    ds, truth = make_sections(case="T22-A70")
    ds["flow_depth"] = 0.0 * ds["deposit_depth"] + 0.1
    rows, _ = diagnose_case(ds)
    row = next(r for r in rows if r["variant"] == "paper t_C")
    t3 = cases.table3().set_index("case_id").loc["T22-A70"]
    xs = np.array([0.2, 0.4, 0.6, 0.8])
    k = np.rint(xs * 10).astype(int)
    T = np.array([t3[f"xM_{x}"] for x in xs])
    # planted: hu/p0 = mc + c (t_rule - t_s) at each section, read at the paper's times
    y = truth["mc"][k] + 0.02 * (truth["t_rule"][k] - T)
    A, B = np.polyfit(xs, y, 1)
    assert row["n_sections"] == 4
    assert row["A"] == pytest.approx(A, rel=1e-3) and row["B"] == pytest.approx(B, rel=1e-3)
    # the baseline on the same four sections is the planted line
    assert "A -0.0300, B 0.0400" in row["note"]
    # a case the paper's Table 3 does not list gets no such row
    ds2 = make_sections(case="T22-A45")[0]
    ds2["flow_depth"] = 0.0 * ds2["deposit_depth"] + 0.1
    rows2, _ = diagnose_case(ds2)
    assert not any(r["variant"] == "paper t_C" for r in rows2)
