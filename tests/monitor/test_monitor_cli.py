"""End to end on a synthetic run file: granudep monitor → monitor-wm → regress (in process)."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from granudep import cases
from granudep.cli import main
from granudep.io import open_dataset, write_netcdf
from monitor_synth import ramp_run

DX = 0.004


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("run") / "T22-A70.nc"
    write_netcdf(ramp_run(case="T22-A70", dx=DX), path)
    return path


def test_monitor_wm_regress_chain(run_file, tmp_path, capsys):
    sec = tmp_path / "sections" / "T22-A70.nc"
    assert main(["monitor", str(run_file), "-o", str(sec), "--width-factor", "2"]) == 0
    ds = open_dataset(sec)
    assert ds.sizes == {"section": 11, "time": 51}
    t_c = cases.characteristic_time(0.14, np.radians(22.0))
    # before t = 0.56 s no row is at rest; from then on m rows = floor((t − 0.5)·20)
    t = ds.time.values
    m = np.floor(np.maximum(t - 0.5, 0) * 20 + 1e-9) * (t >= 0.5)
    np.testing.assert_allclose(ds.deposit_depth.values, np.broadcast_to(m * DX, (11, t.size)), atol=1e-12)

    wm = tmp_path / "wm.nc"
    assert main(["monitor-wm", str(run_file), "-o", str(wm)]) == 0
    assert "RMS deviation" in capsys.readouterr().out
    np.testing.assert_allclose(open_dataset(wm).rms_deviation.values, 0.0, atol=1e-12)  # uniform strip

    out = tmp_path / "regression"
    assert main(["regress", str(sec), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "Table 3" in printed and "T22-A70" in printed
    crit = pd.read_csv(out / "critical.csv")
    for col in ("case", "theta_deg", "a", "x_norm", "t_s_critical", "t_s_critical_fit", "deposition_rate",
                "r2", "momentum_critical_norm"):
        assert col in crit.columns
    # h_D jumps from 0 (t = 0.54 s) to dx (t = 0.56 s): the dx/2 crossing is at 0.55 s
    np.testing.assert_allclose(crit.t_s_critical * t_c, 0.55, atol=1e-9)
    # the staircase grows by 20 rows per second: normalised rate 20 dx t_c / H0 within 5 %
    np.testing.assert_allclose(crit.deposition_rate, 20 * DX * t_c / 0.14, rtol=0.05)
    coeffs = pd.read_csv(out / "coefficients.csv")
    assert coeffs.A.iloc[0] == pytest.approx(0.0, abs=1e-9)  # identical sections: no trend in [x]
    assert np.isnan(coeffs.r2.iloc[0])  # constant (hu)_C: R² undefined, not a spurious number
    assert coeffs.B.iloc[0] == pytest.approx(crit.momentum_critical_norm.mean(), rel=1e-9)
    t3 = pd.read_csv(out / "table3_comparison.csv")
    assert t3.t_s_critical_paper.tolist() == [7.90, 8.83, 9.95, 11.04]
    assert (out / "coefficients.nc").is_file() and (out / "table5_comparison.csv").is_file()


def test_cli_bad_input_exits_2(run_file, tmp_path, capsys):
    assert main(["monitor", str(run_file), "-o", str(tmp_path / "s.nc"), "--width-factor", "-1"]) == 2
    assert "monitor.width_factor: must be > 0" in capsys.readouterr().err
    assert not (tmp_path / "s.nc").exists()
    assert main(["monitor-wm", str(run_file), "-o", str(tmp_path / "w.nc"), "--widths", "1", "3"]) == 2
    assert "monitor.wm_reference" in capsys.readouterr().err
    assert main(["regress", str(tmp_path / "missing.nc"), "-o", str(tmp_path / "r")]) == 2
    assert "sections: file not found" in capsys.readouterr().err
