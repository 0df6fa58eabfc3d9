"""workflow/scripts/sensitivity_table.py: the sensitivity runs collected into the figure's table."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pandas as pd
import xarray as xr

ROOT = Path(__file__).resolve().parents[2]


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
    proc = subprocess.run([sys.executable, str(ROOT / "workflow/scripts/sensitivity_table.py"), "-o", str(out),
                           "--baseline-values", "critical_speed=0.1", "phi_basal_deg=25.5", "--", *runs],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    t = pd.read_csv(out)
    assert len(t) == 4
    cs = t[t.parameter == "critical_speed"].set_index("value")
    assert list(cs.index) == [0.05, 0.1]
    assert cs.loc[0.1, "baseline"] == 1 and cs.loc[0.05, "baseline"] == 0
    assert cs.loc[0.1, "A"] == -0.03 and cs.loc[0.05, "final_runout_norm"] == 1.7
    pb = t[t.parameter == "phi_basal_deg"].set_index("value")
    assert pb.loc[27.5, "B"] == 0.05 and pb.loc[25.5, "flow_time"] == 0.9
