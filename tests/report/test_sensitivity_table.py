"""`granudep sensitivity-table`: the sensitivity runs collected into the figure's table."""
from __future__ import annotations

from pathlib import Path

import pandas as pd
import xarray as xr

from granudep.cli import main


def _run(tmp: Path, name: str, A: float, B: float, runout: float, tf: float) -> str:
    coeffs = tmp / f"{name}.csv"
    pd.DataFrame({"case": ["T22-A70"], "theta_deg": [22.0], "a": [0.7], "A": [A], "B": [B], "r2": [0.9]}
                 ).to_csv(coeffs, index=False)
    da = tmp / f"{name}.nc"
    xr.Dataset({"final_runout_norm": ((), runout), "flow_time": ((), tf)}).to_netcdf(da)
    return f"{name}={coeffs},{da}"


def test_table_marks_the_baseline_once_per_parameter(tmp_path):
    runs = [_run(tmp_path, "baseline", -0.03, 0.04, 1.5, 0.9),
            _run(tmp_path, "critical_speed_0.05", -0.02, 0.03, 1.7, 1.0),
            _run(tmp_path, "phi_basal_deg_27.5", -0.04, 0.05, 1.2, 0.8)]
    out = tmp_path / "sens.csv"
    rc = main(["sensitivity-table", "-o", str(out), "--baseline-values", "critical_speed=0.1",
               "phi_basal_deg=25.5", "--", *runs])
    assert rc == 0
    t = pd.read_csv(out)
    assert len(t) == 4
    cs = t[t.parameter == "critical_speed"].set_index("value")
    assert list(cs.index) == [0.05, 0.1]
    assert cs.loc[0.1, "baseline"] == 1 and cs.loc[0.05, "baseline"] == 0
    assert cs.loc[0.1, "A"] == -0.03 and cs.loc[0.05, "final_runout_norm"] == 1.7
    pb = t[t.parameter == "phi_basal_deg"].set_index("value")
    assert pb.loc[27.5, "B"] == 0.05 and pb.loc[25.5, "flow_time"] == 0.9


def test_missing_baseline_or_paper_value_is_one_line(tmp_path, capsys):
    run = _run(tmp_path, "critical_speed_0.05", -0.02, 0.03, 1.7, 1.0)
    out = tmp_path / "sens.csv"
    assert main(["sensitivity-table", "-o", str(out), "--baseline-values", "critical_speed=0.1", "--", run]) == 2
    assert capsys.readouterr().err.strip() == "granudep: error: sensitivity-table: no baseline run given"
    base = _run(tmp_path, "baseline", -0.03, 0.04, 1.5, 0.9)
    assert main(["sensitivity-table", "-o", str(out), "--baseline-values", "phi_basal_deg=25.5", "--", base, run]) == 2
    assert "no value for 'critical_speed'" in capsys.readouterr().err
    assert not out.exists()
