"""granudep.report.da_readings: every (hu)_C reading through the DA, with a stand-in for the DA run."""
import math

import pandas as pd
import pytest

from granudep.report.da_readings import DA_CASES, pivot_markdown, reading_runs

RUNS_2D = {"1D-A30": "T22-A30", "1D-A45": "T22-A45", "1D-A70": "T22-A70", "1D-A124": "T22-A124"}


def reference():
    return pd.DataFrame({"case": list(RUNS_2D), "final_runout_norm": [4.0, 6.0, 8.0, 12.0],
                         "path": [f"results/isph/{r}.nc" for r in RUNS_2D.values()]})


def diagnosis():
    rows = []
    for run in RUNS_2D.values():
        rows.append({"case": run, "variant": "baseline", "a": 0.5, "A": -0.03, "B": 0.04, "r2": 0.8})
        rows.append({"case": run, "variant": "no gate", "a": 0.5, "A": -0.02, "B": 0.02, "r2": 0.9})
    rows.append({"case": "T22-A70", "variant": "W_M = 3 dx", "a": 0.7, "A": float("nan"), "B": 0.03, "r2": 0.7})
    rows.append({"case": "T10-A35", "variant": "baseline", "a": 0.35, "A": -0.1, "B": 0.1, "r2": 0.9})
    return pd.DataFrame(rows)


def fake_runout(calls):
    base = {"1D-A30": 5.0, "1D-A45": 7.5, "1D-A70": 10.0, "1D-A124": 15.0}

    def runout(case, n, deposition):
        calls.append((case, n, deposition))
        if deposition is False:
            return base[case]
        return base[case] * (1.0 - 10.0 * deposition["B"])   # larger B: more deposition, shorter
    return runout


def test_reading_runs_compares_each_reading_with_the_2d_reference_and_the_run_without_deposition():
    calls = []
    df = reading_runs(diagnosis(), reference(), 321, runout=fake_runout(calls))
    # 8 finite readings of the Table 5 geometries; the NaN A and the non-Table-5 case are skipped
    assert len(df) == 8
    assert set(df.case) == set(DA_CASES)
    assert all(n == 321 for _, n, _ in calls)
    assert sum(d is False for _, _, d in calls) == 4
    r = df[(df.case == "1D-A70") & (df.reading == "baseline")].iloc[0]
    assert r.run_2d == "T22-A70"
    assert r.runout_norm == pytest.approx(10.0 * 0.6)
    assert r.runout_error == pytest.approx(6.0 / 8.0 - 1.0)
    assert r.runout_error_nodeposition == pytest.approx(10.0 / 8.0 - 1.0)
    assert r.shortening == pytest.approx(0.4)
    dep = [d for c, _, d in calls if c == "1D-A70" and d is not False]
    assert {"ab_source": "user", "A": -0.03, "B": 0.04} in dep


def test_reading_runs_takes_the_table5_cases_the_reference_has_and_refuses_none():
    calls = []
    df = reading_runs(diagnosis(), reference().iloc[2:3], 100, runout=fake_runout(calls))   # 1D-A70 only
    assert set(df.case) == {"1D-A70"} and len(df) == 2
    assert {c for c, _, _ in calls} == {"1D-A70"}
    with pytest.raises(ValueError, match="no row for any Table 5 case"):
        reading_runs(diagnosis(), reference().iloc[0:0], 100, runout=fake_runout([]))


def test_pivot_shows_every_reading_and_the_no_deposition_row():
    df = reading_runs(diagnosis(), reference(), 100, runout=fake_runout([]))
    text = pivot_markdown(df)
    lines = text.splitlines()
    assert lines[0] == "| reading | " + " | ".join(DA_CASES) + " |"
    assert any(l.startswith("| baseline |") for l in lines)
    assert any(l.startswith("| no gate |") for l in lines)
    # no deposition: 1D-A30 5.0 against 4.0 -> +25 %
    assert lines[-1].startswith("| *no deposition* | +25 %")
    # no gate at 1D-A30: B = 0.02 -> 5.0 * 0.8 = 4.0 -> +0 %, 20.0 % shorter
    assert "+0 % (20.0 % shorter)" in text
    assert not any(math.isnan(v) for v in df.runout_error)


def test_cli_names_the_unreadable_file(tmp_path, capsys):
    from granudep.cli import main
    ref = tmp_path / "ref.csv"
    reference().to_csv(ref, index=False)
    with pytest.raises(SystemExit, match="diagnosis: cannot read"):
        main(["da-readings", str(tmp_path / "missing.csv"), "--reference", str(ref), "-o", str(tmp_path / "o.csv")])


def test_cli_rejects_a_particle_count_out_of_range(tmp_path, capsys):
    from granudep.cli import main
    with pytest.raises(SystemExit):
        main(["da-readings", "d.csv", "--reference", "r.csv", "--n-particles", "5", "-o", str(tmp_path / "o.csv")])
    assert "[20, 1000000]" in capsys.readouterr().err


def test_summary_section_shows_the_readings_table(tmp_path):
    from granudep.report.summary import section_da_readings
    df = reading_runs(diagnosis(), reference(), 100, runout=fake_runout([]))
    path = tmp_path / "da_readings.csv"
    df.to_csv(path, index=False)
    text = section_da_readings(path)
    assert "N = 100" in text and "| *no deposition* |" in text
    assert "| baseline | 1D-A70 | 0.5 | -0.0300 | 0.0400 | 0.800 | 6.00 | 8.00 | -25.0% | 40.0% |" in text
    # not run: a study target of its own, and the section says how to run it
    assert "`snakemake -j2 da_readings`" in section_da_readings(tmp_path / "none.csv")
