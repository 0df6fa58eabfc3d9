"""The convergence table: spread beside the dx change, observed order, and the robust rest measure."""
import math

import pandas as pd
import pytest

from granudep.report.ensemble_convergence import convergence_table, robust_rest_measure, spread_pct
from granudep.richardson import observed_order


def _level(dx, rows):
    """rows: (case, quantity, values) -> the `granudep ensemble --quantities` table at dx."""
    out = []
    for case, q, vals in rows:
        s = pd.Series(vals, dtype=float)
        out.append({"case": case, "quantity": q, "n": len(s), "mean": s.mean(), "min": s.min(), "max": s.max(),
                    "std": s.std(ddof=1) if len(s) > 1 else math.nan, "member0": s.iloc[0], "dx": dx})
    return pd.DataFrame(out)


def test_spread_is_range_over_mean_and_undefined_for_one_member():
    assert spread_pct({"n": 3, "mean": 10.0, "min": 9.0, "max": 11.0}) == pytest.approx(20.0)
    assert math.isnan(spread_pct({"n": 1, "mean": 10.0, "min": 10.0, "max": 10.0}))


def test_a_quantity_is_well_defined_only_when_spread_and_dx_change_are_both_small():
    coarse = _level(0.004, [("T22-A70", "runout_v99", [8.0, 8.1, 8.2]),       # spread 2.5 %
                            ("T22-A70", "rest_time", [20.0, 22.0, 29.0]),     # spread 39 %
                            ("T16-A50", "runout_v99", [2.0, 2.02, 2.04])])    # spread 2 %, then +25 %
    fine = _level(0.002, [("T22-A70", "runout_v99", [8.3, 8.4, 8.5]),
                          ("T22-A70", "rest_time", [21.0, 23.0, 24.0]),
                          ("T16-A50", "runout_v99", [2.5, 2.52, 2.54])])
    t = convergence_table([coarse, fine], threshold_pct=10.0).set_index(["case", "quantity"])
    assert t.loc[("T22-A70", "runout_v99"), "verdict"].startswith("well-defined")
    assert t.loc[("T22-A70", "rest_time"), "verdict"].startswith("ill-conditioned")
    assert t.loc[("T16-A50", "runout_v99"), "verdict"].startswith("not converged")
    assert t.loc[("T22-A70", "runout_v99"), "change_pct"] == pytest.approx(100 * 0.3 / 8.1)
    # the rest time moves by +3.7 %, well inside its 39 % spread: not a finding
    assert not t.loc[("T22-A70", "rest_time"), "change_exceeds_spread"]
    assert t.loc[("T16-A50", "runout_v99"), "change_exceeds_spread"]


def test_the_observed_order_uses_the_single_finest_run_and_matches_richardson():
    # f = 10 + 4 h^2 (h in mm): exact second order on the means
    f = {h: 10 + 4 * h ** 2 for h in (4.0, 2.0, 1.4)}
    levels = [_level(0.004, [("C", "runout_v99", [f[4.0] - 1, f[4.0], f[4.0] + 1])]),
              _level(0.002, [("C", "runout_v99", [f[2.0] - 1, f[2.0], f[2.0] + 1])]),
              _level(0.0014, [("C", "runout_v99", [f[1.4]])])]
    row = convergence_table(levels).iloc[0]
    assert row["order"] == pytest.approx(2.0, rel=1e-6)
    assert row["extrapolated"] == pytest.approx(10.0, rel=1e-6)
    assert row["single"] == pytest.approx(f[1.4]) and row["dx_single_mm"] == pytest.approx(1.4)
    ref = observed_order([1.4, 2.0, 4.0], [f[1.4], f[2.0], f[4.0]])
    assert row["order"] == pytest.approx(ref["order"])
    assert "one lattice run" in row["order_note"]


def test_the_robust_rest_measure_is_chosen_by_spread_and_dx_change():
    coarse = _level(0.004, [("T22-A70", "rest_time", [20.0, 22.0, 29.0]),
                            ("T22-A70", "rest_time_mass99", [19.0, 19.5, 20.0])])
    fine = _level(0.002, [("T22-A70", "rest_time", [21.0, 23.0, 24.0]),
                          ("T22-A70", "rest_time_mass99", [19.5, 20.0, 20.2])])
    r = robust_rest_measure(convergence_table([coarse, fine])).iloc[0]
    assert r["robust"] == "rest_time_mass99"
    assert r["worst_rest_time_pct"] == pytest.approx(100 * 9 / 23.667, rel=1e-3)


def test_one_level_gives_no_row():
    assert convergence_table([_level(0.004, [("C", "runout_v99", [1.0, 1.1])])]).empty


def test_the_summary_section_shows_the_table_and_names_the_target_when_absent(tmp_path):
    from granudep.report.summary import section_ensemble_convergence
    assert "`snakemake -j2 convergence_ensemble` has not run" in section_ensemble_convergence(None)
    coarse = _level(0.004, [("T22-A70", "rest_time", [20.0, 22.0, 29.0])])
    fine = _level(0.002, [("T22-A70", "rest_time", [21.0, 23.0, 24.0])])
    convergence_table([coarse, fine]).to_csv(tmp_path / "t.csv", index=False)
    text = section_ensemble_convergence(tmp_path / "t.csv")
    assert "| T22-A70 | time to rest, every particle" in text and "ill-conditioned: spread 38.0 %" in text


def test_the_spread_of_the_finer_ensemble_counts_too():
    # 4 mm members agree (2 %), 2 mm members scatter by 40 %: the quantity is not well-defined
    coarse = _level(0.004, [("T22-A70", "rest_time", [20.0, 20.2, 20.4])])
    fine = _level(0.002, [("T22-A70", "rest_time", [17.0, 20.0, 25.0])])
    row = convergence_table([coarse, fine]).iloc[0]
    assert row["verdict"].startswith("ill-conditioned: spread 38.")


def test_no_robust_rest_measure_is_claimed_when_both_scatter():
    coarse = _level(0.004, [("T22-A70", "rest_time", [20.0, 22.0, 29.0]),
                            ("T22-A70", "rest_time_mass99", [19.0, 21.5, 28.0])])
    fine = _level(0.002, [("T22-A70", "rest_time", [21.0, 23.0, 24.0]),
                          ("T22-A70", "rest_time_mass99", [19.5, 20.0, 20.2])])
    r = robust_rest_measure(convergence_table([coarse, fine]), threshold_pct=10.0).iloc[0]
    assert not r["within_threshold"]
