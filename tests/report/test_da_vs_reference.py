"""Reference table from 2D runs and relative errors of DA runs (planted, exact answers)."""
import math

import pandas as pd
import pytest

import synthetic_data as syn
from granudep import cases
from granudep.cli import main
from granudep.report.da_vs_reference import compare, improvement, max_errors, report_text
from granudep.report.reference_2d import load_reference, reference_from_isph
from granudep.config import ConfigError


@pytest.fixture(scope="module")
def isph_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("isph")
    return [syn.save(syn.isph_run("T22-A70", L0=0.2, H0=0.14, runout=0.3, t_stop=1.0), d / "T22-A70.nc"),
            syn.save(syn.isph_run("T22-A45", L0=0.25, H0=0.1125, runout=0.2, t_stop=0.8), d / "T22-A45.nc"),
            syn.save(syn.isph_run("T16-A50", L0=0.2, H0=0.1, theta=16.0, runout=0.1, t_stop=0.6),
                     d / "T16-A50.nc")]


def test_reference_rows_exact(isph_files):
    ref = reference_from_isph(isph_files)
    assert list(ref.case) == ["1D-A70", "1D-A45", "T16-A50"]  # Table 5 names; others keep their own
    # ΔL/L0 = runout / L0 exactly; flow time = t_stop (front constant afterwards, 1 mm tolerance)
    assert ref.final_runout_norm.tolist() == pytest.approx([1.5, 0.8, 0.5], abs=1e-12)
    assert ref.flow_time.tolist() == pytest.approx([1.0, 0.8, 0.6], abs=1e-12)
    tc = cases.characteristic_time(0.14, math.radians(22.0))
    assert ref.flow_time_norm[0] == pytest.approx(1.0 / tc, rel=1e-12)
    assert ref.a.tolist() == pytest.approx([0.7, 0.45, 0.5], rel=1e-12)
    assert "1.40 mm" in ref.front_definition[0]
    assert "dx=0.01 m" in ref.provenance[0] and "T22-A70.nc" in ref.provenance[0]


def test_isph_rows_form_one_reference_source(isph_files):
    ref = reference_from_isph(isph_files[:2])
    runs = [syn.da_run("1D-A70", True, final_runout_norm=1.8, flow_time=1.2),          # +20 % vs 1.5
            syn.da_run("1D-A45", True, final_runout_norm=1.2, flow_time=0.8, L0=0.25, H0=0.1125)]  # +50 % vs 0.8
    t = compare(runs, [ref])
    assert t.reference.nunique() == 1 and t.reference[0] == "granudep 2D ISPH, dx=0.01 m"
    mx = max_errors(t)
    assert len(mx) == 2  # runout and flow time, over both cases
    r = mx[mx.quantity == "runout"].iloc[0]
    assert r.max_abs_rel_error == pytest.approx(0.5, abs=1e-12) and r.case == "1D-A45"


def test_reference_front_definition_missing_attr_refused(tmp_path):
    ds = syn.isph_run()
    del ds.attrs["L0"]
    with pytest.raises(ConfigError, match="'L0'"):
        reference_from_isph([ds])


def _ref_table():
    return pd.DataFrame({"case": ["1D-A70", "1D-A30"], "final_runout_norm": [1.5, 2.0],
                         "flow_time": [1.0, 2.0], "provenance": ["planted", "planted"]})


def test_compare_planted_errors():
    runs = [syn.da_run("1D-A70", True, final_runout_norm=1.8, flow_time=1.2),   # +20 %, +20 %
            syn.da_run("1D-A70", False, final_runout_norm=2.25, flow_time=1.5),  # +50 %, +50 %
            syn.da_run("1D-A30", True, final_runout_norm=1.5, flow_time=2.5),   # −25 %, +25 %
            syn.da_run("1D-A30", False, final_runout_norm=2.2, flow_time=1.5)]  # +10 %, −25 %
    t = compare(runs, [_ref_table()])
    got = {(r.case, r.deposition): (r.runout_rel_error, r.flow_time_rel_error) for r in t.itertuples()}
    assert got[("1D-A70", 1)] == pytest.approx((0.2, 0.2), abs=1e-12)
    assert got[("1D-A70", 0)] == pytest.approx((0.5, 0.5), abs=1e-12)
    assert got[("1D-A30", 1)] == pytest.approx((-0.25, 0.25), abs=1e-12)
    assert got[("1D-A30", 0)] == pytest.approx((0.1, -0.25), abs=1e-12)
    imp = improvement(t).set_index("case")
    assert bool(imp.loc["1D-A70", "runout_improved"]) and bool(imp.loc["1D-A70", "flow_time_improved"])
    assert not bool(imp.loc["1D-A30", "runout_improved"])          # |−25 %| > |+10 %|
    assert not bool(imp.loc["1D-A30", "flow_time_improved"])       # |+25 %| = |−25 %|: not better
    mx = max_errors(t).set_index(["variant", "quantity"])
    assert mx.loc[("no deposition", "runout"), "max_abs_rel_error"] == pytest.approx(0.5, abs=1e-12)
    assert mx.loc[("deposition", "runout"), "max_abs_rel_error"] == pytest.approx(0.25, abs=1e-12)
    assert mx.loc[("deposition", "runout"), "case"] == "1D-A30"
    assert mx.loc[("no deposition", "flow_time"), "paper_max_error"] == pytest.approx(1.07)
    text = report_text(t)
    assert "+20.0 %" in text and "paper 55 %" in text and "improved: yes" in text


def test_compare_per_provenance_and_normalised_flow_time():
    user = pd.DataFrame({"case": ["1D-A70"], "final_runout_norm": [2.0], "flow_time_norm": [5.0],
                         "provenance": ["user measurement"]})
    run = syn.da_run("1D-A70", True, final_runout_norm=1.8, flow_time=1.2)
    t = compare([run], [_ref_table(), user])
    assert len(t) == 2
    u = t[t.provenance == "user measurement"].iloc[0]
    assert u.runout_rel_error == pytest.approx(-0.1, abs=1e-12)
    assert u.flow_time_basis == "t/t_c"
    assert u.flow_time_rel_error == pytest.approx(float(run.flow_time_norm) / 5.0 - 1.0, abs=1e-12)


def test_compare_run_without_reference_kept():
    t = compare([syn.da_run("1D-A124", True)], [_ref_table()])
    assert t.provenance.tolist() == ["no reference"] and math.isnan(t.runout_rel_error[0])


@pytest.mark.parametrize("drop,needle", [("provenance", "provenance"), ("case", "case"),
                                         ("final_runout_norm", "final_runout_norm"),
                                         ("flow_time", "flow_time (or flow_time_norm)")])
def test_reference_missing_column_refused(drop, needle):
    with pytest.raises(ConfigError, match=r"missing column\(s\) .*" + needle.replace("(", r"\(").replace(")", r"\)")):
        load_reference(_ref_table().drop(columns=[drop]))


def test_cli_reference_and_compare(isph_files, tmp_path, capsys):
    ref = tmp_path / "ref.csv"
    assert main(["reference", *isph_files[:1], "-o", str(ref)]) == 0
    da = [syn.save(syn.da_run("1D-A70", True, 1.8, 1.2), tmp_path / "dep.nc"),
          syn.save(syn.da_run("1D-A70", False, 2.25, 1.5), tmp_path / "nodep.nc")]
    out = tmp_path / "cmp.csv"
    assert main(["compare", *da, "--reference", str(ref), "-o", str(out)]) == 0
    t = pd.read_csv(out)
    assert sorted(t.runout_rel_error.round(12)) == [0.2, 0.5]
    assert "Does deposition improve" in capsys.readouterr().out
    bad = tmp_path / "bad.csv"
    _ref_table().drop(columns=["provenance"]).to_csv(bad, index=False)
    assert main(["compare", *da, "--reference", str(bad), "-o", str(tmp_path / "x.csv")]) == 2
    assert "provenance" in capsys.readouterr().err
    assert not (tmp_path / "x.csv").exists()


def test_failed_2d_run_refused():
    ds = syn.isph_run()
    ds.attrs["status"] = "failed: particle 3 left the domain at t=1.0 s"
    with pytest.raises(ConfigError, match="did not finish"):
        reference_from_isph([ds])


def test_2d_run_not_at_rest_flagged():
    ds = syn.isph_run()
    ds["time_to_rest"] = ds["time_to_rest"].copy(data=float("nan"))
    ref = reference_from_isph([ds])
    assert ref.note[0].startswith("not at rest at t_end = 1.6 s")
    t = compare([syn.da_run("1D-A70", True)], [ref])
    assert t.reference_note[0] == ref.note[0]
    assert reference_from_isph([syn.isph_run()]).note[0] == ""
