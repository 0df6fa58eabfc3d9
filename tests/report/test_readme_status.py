"""`granudep readme-status`: the README's status block generated from results/ files, idempotently."""
from __future__ import annotations

import pandas as pd
import pytest

from granudep.cli import main
from granudep.report.readme_status import BEGIN, END, status_block, update_readme

README = f"# x\n\nHand-written text (t_s = 14.6, keep).\n\n{BEGIN}\nold numbers\n{END}\n\n## After\n\nmore text\n"


@pytest.fixture()
def results(tmp_path):
    r = tmp_path / "results"
    (r / "verification").mkdir(parents=True)
    (r / "regression").mkdir()
    (r / "compare").mkdir()
    pd.DataFrame({"check": ["a", "a", "b"], "quantity": ["q1", "q2", "q3"], "passed": [True, True, True]}
                 ).to_csv(r / "verification/da.csv", index=False)
    pd.DataFrame({"check": ["h", "dam_break", "surge"], "quantity": ["q", "E", "front"], "passed": [True, False, False],
                  "tolerance": [0.1, 0.005, float("inf")]}).to_csv(r / "verification/isph.csv", index=False)
    pd.DataFrame({"claim_id": ["failure_plane_angle", "rest_time_T22-A70", "x"], "case": ["T22-A70"] * 3,
                  "paper_value": [55.8, 13.5, 1.0], "ours_paper_res": [61.23, 14.44, 1.0],
                  "verdict": ["not reproduced", "reproduced", "reproduced"]}).to_csv(r / "claims.csv", index=False)
    pd.DataFrame({"rel_diff_pct": [10.0, -30.0], "rel_diff_fit_pct": [5.0, 15.0]}
                 ).to_csv(r / "regression/table3_comparison.csv", index=False)
    pd.DataFrame({"a": [0.7, 0.3], "A_rel_diff_pct": [-424.0, 53.5], "B_rel_diff_pct": [186.0, -49.3],
                  "r2": [0.29, 0.65]}).to_csv(r / "regression/table5_comparison.csv", index=False)
    pd.DataFrame({"case": ["1D-A70", "1D-A70"], "deposition": [0, 1], "reference": ["2D run"] * 2,
                  "runout_rel_error": [0.92, 0.90], "final_runout_norm": [13.0, 12.35]}
                 ).to_csv(r / "compare/comparison.csv", index=False)
    return r


def test_block_reads_the_numbers_from_the_files(results):
    block = status_block(results)
    assert block.startswith(BEGIN) and block.endswith(END)
    assert "DA 3 of 3 checked rows pass; 0 reported" in block
    assert "2D ISPH 1 of 2 checked rows pass; 1 reported (failing: `dam_break`)" in block
    assert "61.2° from the horizontal (paper 55.8°" in block
    assert "T22-A70 14.4 (paper ≈ 13.5, reproduced)" in block
    assert "2 reproduced, 0 indeterminate, 1 not reproduced, 0 not checkable of 3 claims" in block
    assert "mean |difference| 20.0 % (onset) and 10.0 % (fit intercept) over 2" in block
    assert block.index("a = 0.3: A +54 %") < block.index("a = 0.7: A -424 %")  # sorted by a
    assert "shortens the DA runout by 5 %" in block and "92 % without deposition, 90 % with it" in block
    # a changed output changes the block
    pd.DataFrame({"rel_diff_pct": [50.0], "rel_diff_fit_pct": [5.0]}).to_csv(
        results / "regression/table3_comparison.csv", index=False)
    assert "mean |difference| 50.0 % (onset)" in status_block(results)


def test_missing_output_is_named_not_guessed(results):
    (results / "claims.csv").unlink()
    block = status_block(results)
    assert "`results/claims.csv` missing" in block and "Failure plane" not in block


def test_command_is_idempotent_and_leaves_the_rest_alone(results, tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text(README, encoding="utf-8")
    assert main(["readme-status", str(readme), "--results", str(results), "--check"]) == 1  # stale
    assert readme.read_text(encoding="utf-8") == README  # --check writes nothing
    assert main(["readme-status", str(readme), "--results", str(results)]) == 0
    once = readme.read_text(encoding="utf-8")
    assert main(["readme-status", str(readme), "--results", str(results)]) == 0
    assert readme.read_text(encoding="utf-8") == once
    assert main(["readme-status", str(readme), "--results", str(results), "--check"]) == 0
    assert "old numbers" not in once and "61.2°" in once
    head, tail = README.split(BEGIN)[0], README.split(END)[1]
    assert once.startswith(head) and once.endswith(tail)


def test_readme_without_markers_is_refused(tmp_path, results, capsys):
    readme = tmp_path / "README.md"
    readme.write_text("# no block\n", encoding="utf-8")
    assert main(["readme-status", str(readme), "--results", str(results)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "marker pair" in err[0]
    with pytest.raises(Exception):
        update_readme(README + BEGIN, "x")


def test_project_readme_has_one_block():
    from pathlib import Path
    text = (Path(__file__).resolve().parents[2] / "README.md").read_text(encoding="utf-8")
    assert text.count(BEGIN) == 1 and text.count(END) == 1


def test_table3_is_also_given_per_slope_angle(results):
    pd.DataFrame({"case": ["T10-A35", "T22-A70", "T22-A70"], "rel_diff_pct": [4.0, 10.0, -30.0],
                  "rel_diff_fit_pct": [1.0, 5.0, 15.0]}).to_csv(results / "regression/table3_comparison.csv", index=False)
    block = status_block(results)
    assert "onset per slope: 10°: 4.0 %, 22°: 20.0 %;" in block
    # the validation figure leaves out the calibration case (T22-A70): only T10-A35 counts
    assert "4.0 % over the 1 case other than T22-A70." in block


def test_a_variant_chain_gets_its_own_line(results):
    assert "Variant" not in status_block(results)  # no variants folder, no line
    v = results / "variants" / "no-slip"
    (v / "regression").mkdir(parents=True)
    pd.DataFrame({"claim_id": ["rest_time_T22-A70", "x"], "case": ["T22-A70"] * 2, "paper_value": [13.5, 1.0],
                  "ours_paper_res": [18.22, 2.0], "verdict": ["not reproduced", "reproduced"]}
                 ).to_csv(v / "claims.csv", index=False)
    pd.DataFrame({"case": ["T16-A50", "T22-A70"], "rel_diff_pct": [-40.0, -50.0]}
                 ).to_csv(v / "regression/table3_comparison.csv", index=False)
    (results / "variants" / "unfinished").mkdir()
    block = status_block(results)
    line = [ln for ln in block.splitlines() if "Variant `no-slip`" in ln][0]
    assert "claims: 1 reproduced, 0 indeterminate, 1 not reproduced, 0 not checkable of 2" in line and "45.0 % (onset; 16°: 40.0 %, 22°: 50.0 %" in line
    assert "40.0 % over the 1 case other than T22-A70" in line and "calibrated on" not in line
    assert "t_s T22-A70 18.2" in line and "config/variants/no-slip.yaml" in line
    assert "Variant `unfinished`" in block and "has not finished" in block


def test_the_calibrated_variant_says_what_was_calibrated_and_scores_the_other_cases(results):
    v = results / "variants" / "calibrated"
    (v / "regression").mkdir(parents=True)
    pd.DataFrame({"claim_id": ["x"], "case": ["T22-A70"], "paper_value": [1.0], "ours_paper_res": [1.0],
                  "verdict": ["reproduced"]}).to_csv(v / "claims.csv", index=False)
    # the calibration case fits (2 %), the validation cases do not (30 %, 10 %): the held-out mean is theirs
    pd.DataFrame({"case": ["T22-A70", "T22-A70", "T16-A50", "T22-A150"], "rel_diff_pct": [2.0, -2.0, -30.0, 10.0]}
                 ).to_csv(v / "regression/table3_comparison.csv", index=False)
    (results / "calibration").mkdir()
    pd.DataFrame({"case": ["T22-A70"], "slip_length_mm": [5.1], "range_min_mm": [5.06], "range_max_mm": [5.91],
                  "members": [3], "objective_min": [0.0086], "scan_points": [15]}
                 ).to_csv(results / "calibration/result.csv", index=False)
    line = [ln for ln in status_block(results).splitlines() if "Variant `calibrated`" in ln][0]
    assert "L_s calibrated on the T22-A70 row of Table 3; every other number is a prediction" in line
    assert "20.0 % over the 2 cases other than T22-A70" in line
    assert "L_s = 5.10 mm (member minimisers 5.06–5.91 mm" in line



def test_the_run_line_prefers_the_last_full_reproduction(results):
    import json
    bench = results / "benchmarks"
    bench.mkdir(exist_ok=True)
    rec = {"started_utc": "s", "ended_utc": "e", "targets": ["all"], "cores": 2, "commit": "abc"}
    (bench / "run.json").write_text(json.dumps({**rec, "wall_s": 6.0}))
    line = [ln for ln in status_block(results).splitlines() if "**Last run**" in ln][0]
    assert "0.1 min" in line and "not a full reproduction" in line
    (bench / "run_full.json").write_text(json.dumps({**rec, "wall_s": 1052.3}))
    line = [ln for ln in status_block(results).splitlines() if "**Last run**" in ln][0]
    assert "17.5 min" in line and "the last full reproduction" in line


def test_the_da_errors_are_also_read_against_every_members_2d_runs(tmp_path):
    from granudep.report.readme_status import _members_range
    rows = lambda e0, e1: pd.DataFrame({"reference": ["2D"] * 2, "deposition": [0, 1], "case": ["1D-A70"] * 2,
                                        "runout_rel_error": [e0, e1]})
    (tmp_path / "compare").mkdir()
    rows(0.20, 0.18).to_csv(tmp_path / "compare/comparison.csv", index=False)
    assert _members_range(tmp_path, "2D") == ""  # one member: nothing to add
    (tmp_path / "ensemble/m1/compare").mkdir(parents=True)
    rows(0.30, 0.25).to_csv(tmp_path / "ensemble/m1/compare/comparison.csv", index=False)
    text = _members_range(tmp_path, "2D")
    assert "2 ensemble members" in text and "20–30 % without deposition" in text and "18–25 % with it" in text
