"""Reading matrix, converged-reference selection, claims verdicts, x_inf fall-back (planted)."""
import math
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

import synthetic_data as syn
from granudep.report.claims import paper_claims, scorecard, verdict
from granudep.report.da_vs_reference import compare, da_reading, matrix_maxima, reading_matrix
from granudep.report.reference_2d import reference_from_isph, select_reference_runs
from granudep.report.da_vs_reference import PAPER_MAX_ERRORS
from granudep.da.deposition import self_consistent


def _da(reading, runout, flow_time):
    dep = reading != "none"
    ds = syn.da_run("1D-A70", dep, final_runout_norm=runout, flow_time=flow_time)
    if dep:
        src, _, units = reading.partition("-")
        ds.attrs.update(ab_source=f"{src} (planted)", coefficient_units="dimensional" if units else "normalised",
                        A=-0.03, B=0.04)
    return ds


def test_reading_of_a_run():
    assert da_reading(_da("none", 1.0, 1.0)) == "none"
    assert da_reading(_da("computed", 1.0, 1.0)) == "computed"
    assert da_reading(_da("paper-dimensional", 1.0, 1.0)) == "paper-dimensional"


def test_reading_matrix_planted_errors():
    ref = pd.DataFrame({"case": ["1D-A70"], "final_runout_norm": [1.5], "flow_time": [1.0],
                        "provenance": ["planted"], "reference": ["2D paper resolution (dx = 4 mm)"], "dx": [0.004]})
    runs = [_da("none", 2.25, 1.5),                 # +50 %, +50 %
            _da("computed", 2.1, 1.4),              # +40 %, +40 %
            _da("paper", 1.8, 1.2),                 # +20 %, +20 %
            _da("paper-dimensional", 0.9, 0.5)]     # -40 %, -50 %
    t = compare(runs, [ref])
    m = reading_matrix(t, measures=("2d",))
    assert sorted(m.reading) == ["computed", "paper", "paper-dimensional"]
    r = m.set_index("reading")
    assert r.loc["computed", "runout_error"] == pytest.approx(0.4, abs=1e-9)
    assert r.loc["paper-dimensional", "flow_time_error"] == pytest.approx(-0.5, abs=1e-9)
    assert np.allclose(r["runout_error_nodep"], 0.5, atol=1e-9)   # one shared no-deposition run
    assert bool(r.loc["paper", "runout_improved"]) and bool(r.loc["paper-dimensional", "runout_improved"])
    assert not bool(r.loc["paper-dimensional", "flow_time_improved"])           # |-50 %| is not below 50 %
    assert r.loc["computed", "reference_dx"] == pytest.approx(0.004)
    mx = matrix_maxima(m).set_index("reading")
    assert mx.loc["paper", "runout_max_reduction"] == pytest.approx(0.3, abs=1e-9)   # 50 % -> 20 %
    assert mx.loc["paper-dimensional", "flow_time_max_reduction"] == pytest.approx(0.0, abs=1e-9)


def test_select_finest_and_requested_dx(tmp_path):
    runs = [syn.save(syn.isph_run("T22-A70", dx=dx, runout=r), tmp_path / f"T22-A70_{dx}.nc")
            for dx, r in ((0.004, 0.30), (0.002, 0.36), (0.003, 0.33))]
    other = syn.save(syn.isph_run("T22-A45", L0=0.25, H0=0.1125, dx=0.004), tmp_path / "T22-A45.nc")
    fine = select_reference_runs(runs + [other])
    assert sorted(fine) == sorted([runs[1], other])
    assert select_reference_runs(runs, dx=0.003) == [runs[2]]
    ref = reference_from_isph(select_reference_runs(runs), label="2D finest available")
    assert ref.reference[0] == "2D finest available (dx = 2 mm)"
    assert ref.final_runout_norm[0] == pytest.approx(0.36 / 0.2)


@pytest.mark.parametrize("ours,paper,test,tol,expect", [
    (8.5, 7.9, "rel", 0.10, "reproduced"), (9.0, 7.9, "rel", 0.10, "not reproduced"),
    (0.02, 0.03, "lt", 0.0, "reproduced"), (0.04, 0.03, "lt", 0.0, "not reproduced"),
    (57.0, 55.8, "abs", 2.0, "reproduced"), (float("nan"), 55.8, "abs", 2.0, "not checkable")])
def test_verdict(ours, paper, test, tol, expect):
    assert verdict(ours, paper, test, tol) == expect


def test_paper_claims_file_agrees_with_the_stated_maxima():
    c = paper_claims().set_index("claim_id")
    assert c.loc["fig16_max_runout_nodep", "paper_value"] == PAPER_MAX_ERRORS["no deposition"]["runout"]
    assert c.loc["fig16_max_flow_time_dep", "paper_value"] == PAPER_MAX_ERRORS["deposition"]["flow_time"]
    # "improves by up to 38 %" is the drop of the largest error, the same for both quantities
    for q in ("runout", "flow_time"):
        drop = PAPER_MAX_ERRORS["no deposition"][q] - PAPER_MAX_ERRORS["deposition"][q]
        assert drop == pytest.approx(c.loc["improves_38", "paper_value"], abs=1e-12)


def test_scorecard_without_outputs_is_not_checkable(tmp_path):
    card = scorecard(tmp_path)
    assert (card["verdict"] == "not checkable").all()
    from granudep.cases import table3
    assert card["claim_id"].str.startswith("table3_").sum() == 4 * len(table3())   # every Table 3 entry
    assert card["claim_id"].str.startswith("table5_").sum() == 8          # A and B of the four cases


def _rec(front):
    return SimpleNamespace(final_front=front)


def test_x_inf_fall_back_when_the_front_jumps():
    """F decreasing with a jump across the diagonal at x = 0.8: no fixed point exists; the run
    still completes with the evaluated x closest to the sign change and a warning."""
    def run(x):
        return _rec(0.9 if x < 0.8 else 0.7)
    res = self_consistent(run, 1.0, 0.2, tol=1e-4, residual_tol=0.02, max_iter=50)
    assert res.warning and "discontinuous" in res.warning and "jumps" in res.warning
    assert abs(res.x_inf - 0.8) < 0.11
    assert res.residual > 0.02


def test_x_inf_continuous_has_no_warning():
    res = self_consistent(lambda x: _rec(1.1 - 0.5 * x), 1.0, 0.2, tol=1e-6, residual_tol=0.02, max_iter=50)
    assert res.warning == "" and res.x_inf == pytest.approx(1.1 / 1.5, abs=1e-4)


def test_reading_matrix_and_residual_figures(tmp_path):
    from granudep.cli import main
    from granudep.regress.diagnose import diagnose, variant_summary
    ref = pd.DataFrame({"case": ["1D-A70"], "final_runout_norm": [1.5], "flow_time": [1.0],
                        "provenance": ["planted"], "reference": ["2D planted (dx = 4 mm)"]})
    t = compare([_da("none", 2.25, 1.5), _da("computed", 2.1, 1.4), _da("paper", 1.8, 1.2)], [ref])
    mpath = tmp_path / "matrix.csv"
    reading_matrix(t).to_csv(mpath, index=False)
    assert main(["figure", "reading-matrix", "-o", str(tmp_path / "rm.png"), str(mpath)]) == 0
    assert (tmp_path / "rm.png").stat().st_size > 1000
    sec = syn.save(syn.sections(), tmp_path / "T22-A70.nc")
    table, resid = diagnose([sec])
    assert {"baseline", "no gate", "fit onset", "onset 1 dx"} <= set(table.variant)
    base = table[table.variant == "baseline"].iloc[0]
    # the baseline refit is the regression's own fit: same sections, same onset rule
    from granudep.regress.api import regress
    co = regress([sec])["coefficients"].iloc[0]
    assert base.A == pytest.approx(co.A, rel=1e-9) and base.r2 == pytest.approx(co.r2, rel=1e-9)
    assert len(variant_summary(table)) == table.variant.nunique()
    table.to_csv(tmp_path / "d.csv", index=False)
    resid.to_csv(tmp_path / "r.csv", index=False)
    assert main(["figure", "fig12r", "-o", str(tmp_path / "r.png"), str(tmp_path / "d.csv"),
                 str(tmp_path / "r.csv")]) == 0
