"""granudep.calibration: the objective, the scan's minimiser and the member-wise range, on planted scans."""
import math

import numpy as np
import pandas as pd
import pytest

from granudep import calibration as cal
from granudep.config import ConfigError


def test_paper_times_are_table3s_row():
    t = cal.paper_times("T22-A70")
    assert np.allclose(t, [7.90, 8.83, 9.95, 11.04])
    with pytest.raises(ValueError, match="no Table 3 row"):
        cal.paper_times("T99-A1")


def test_objective_is_the_mean_squared_relative_difference():
    paper = np.array([2.0, 4.0, 5.0, 10.0])
    assert cal.objective(paper, paper) == 0.0
    # +10 %, -10 %, 0, +20 %: (0.01 + 0.01 + 0 + 0.04) / 4
    assert cal.objective(paper * [1.1, 0.9, 1.0, 1.2], paper) == pytest.approx(0.015)
    assert math.isnan(cal.objective([2.0, np.nan, 5.0, 10.0], paper))  # a missing time is no fit


@pytest.mark.parametrize("vertex", [3.3, 7.0, 11.9])
def test_parabola_minimum_recovers_the_vertex(vertex):
    x = np.arange(0.0, 20.0, 2.0)
    y = 0.5 * (x - vertex) ** 2 + 0.1
    assert cal.parabola_minimum(x[::-1], y[::-1]) == pytest.approx(vertex, abs=1e-9)  # any order


def test_parabola_minimum_at_the_end_of_the_scan_is_the_end_point():
    x = np.arange(0.0, 20.0, 2.0)
    assert cal.parabola_minimum(x, (x - 30.0) ** 2) == 18.0
    # a NaN point (a member that did not deposit) is left out: the lowest finite point is 2 or 6 mm,
    # and the parabola through it and its finite neighbours has its vertex at 4 mm
    assert cal.parabola_minimum(x, np.where(x == 4.0, np.nan, (x - 4.0) ** 2)) == pytest.approx(4.0)
    assert math.isnan(cal.parabola_minimum(x, np.full(x.size, np.nan)))


def _plant(folder, ls_values, members, case="T22-A70"):
    """table3_comparison.csv per ls/member: times = paper (1 + 0.05 (ls - best_k)), best_k = 6 + k."""
    paper = cal.paper_times(case)
    for ls in ls_values:
        for k in range(members):
            d = folder / f"ls{ls:g}" / f"m{k}" / "regression"
            d.mkdir(parents=True)
            t = paper * (1.0 + 0.05 * (ls - (6.0 + k)))
            pd.DataFrame({"case": case, "x_norm": cal.X_NORMS, "t_s_critical": t}).to_csv(
                d / "table3_comparison.csv", index=False)


def test_scan_and_calibrate_on_a_planted_scan(tmp_path):
    # J_k(ls) = 0.0025 (ls - 6 - k)^2 exactly: member minimisers 6, 7, 8 mm; the mean times are
    # paper (1 + 0.05 (ls - 7)), whose J has its vertex at 7 mm
    _plant(tmp_path, [0, 2, 4, 6, 8, 10, 12], members=3)
    scan = cal.scan_table(tmp_path, "T22-A70")
    assert len(scan) == 7 * 4 and set(scan["member"]) == {-1, 0, 1, 2}
    row = scan[(scan["slip_length_mm"] == 4.0) & (scan["member"] == 1)]
    assert float(row["objective"].iloc[0]) == pytest.approx(0.0025 * 9)
    res = cal.calibrate(scan)
    assert res["slip_length_mm"] == pytest.approx(7.0)
    assert (res["range_min_mm"], res["range_max_mm"]) == pytest.approx((6.0, 8.0))
    assert res["members"] == 3 and res["scan_points"] == 7


def test_cli_writes_the_scan_result_and_figure(tmp_path):
    from granudep.cli import main
    _plant(tmp_path / "cal", [0, 4, 8, 12], members=2)
    out = tmp_path / "out"
    assert main(["calibration", str(tmp_path / "cal"), "-o", str(out / "scan.csv"), "--result",
                 str(out / "result.csv"), "--figure", str(out / "cal.png")]) == 0
    res = pd.read_csv(out / "result.csv")
    assert res["slip_length_mm"].iloc[0] == pytest.approx(6.5)  # members 6 and 7: the mean's vertex 6.5
    assert (out / "cal.png").stat().st_size > 1000


def test_cli_refuses_a_folder_without_scan_points(tmp_path):
    from granudep.calibration import _cmd
    import argparse
    args = argparse.Namespace(folder=str(tmp_path), case="T22-A70", output=str(tmp_path / "s.csv"),
                              result=str(tmp_path / "r.csv"), figure=None)
    with pytest.raises(ConfigError, match="no ls<mm>/m<k>/regression"):
        _cmd(args)
    args.folder = str(tmp_path / "absent")
    with pytest.raises(ConfigError, match="folder not found"):
        _cmd(args)
