"""granudep summary: numbers come from the files; missing inputs give 'Not available' lines."""
from pathlib import Path

import pandas as pd
import pytest

import synthetic_data as syn
from granudep.cli import main
from granudep.report.da_vs_reference import compare
from granudep.report.markdown import md_table
from granudep.report.summary import build_summary


@pytest.fixture()
def inputs(tmp_path):
    reg = tmp_path / "regression"
    reg.mkdir()
    pd.DataFrame({"case": ["T22-A70"], "x_norm": [0.2], "t_s_critical_paper": [7.90], "t_s_critical": [8.137],
                  "rel_diff_pct": [3.0], "t_s_critical_fit": [7.5], "rel_diff_fit_pct": [-5.06], "status": ["ok"]}
                 ).to_csv(reg / "table3_comparison.csv", index=False)
    pd.DataFrame({"case": ["1D-A70"], "run_case": ["T22-A70"], "a": [0.7], "A_paper": [-0.0313], "A": [-0.0271],
                  "A_rel_diff_pct": [13.4], "B_paper": [0.0402], "B": [0.0533], "B_rel_diff_pct": [32.6],
                  "r2": [0.987]}).to_csv(reg / "table5_comparison.csv", index=False)
    ref = pd.DataFrame({"case": ["1D-A70"], "final_runout_norm": [1.5], "flow_time": [1.0], "provenance": ["planted"]})
    cmp = tmp_path / "cmp.csv"
    compare([syn.da_run("1D-A70", True, 1.8, 1.2), syn.da_run("1D-A70", False, 2.25, 1.5)], [ref]).to_csv(cmp, index=False)
    ver = tmp_path / "da.csv"
    pd.DataFrame({"check": ["ritter", "mass", "surge"], "quantity": ["front", "volume", "front speed"],
                  "value": [1.01, 1e-15, 1.1], "reference": [1.0, 0.0, 1.0], "error": [0.01, 1e-15, 0.1],
                  "tolerance": [0.02, 1e-12, float("inf")], "passed": [True, False, True],
                  "note": ["", "", ""]}).to_csv(ver, index=False)
    bench = tmp_path / "bench" / "isph"
    bench.mkdir(parents=True)
    (bench / "T22-A70.tsv").write_text("s\th:m:s\tmax_rss\n123.4\t0:02:03\t456.7\n")
    figs = tmp_path / "figures"
    figs.mkdir()
    (figs / "fig5_free_surface.png").write_bytes(b"\x89PNG" + b"0" * 2000)
    return {"regression": reg, "compare": cmp, "verification": [ver], "benchmarks": tmp_path / "bench",
            "figures": figs, "output": tmp_path / "summary.md"}


def test_summary_numbers_from_files(inputs):
    text = build_summary(**inputs)
    assert "| T22-A70 | 0.2 | 7.90 | 8.14 | +3.0 | 7.50 | -5.1 | ok |" in text
    assert "| 1D-A70 | T22-A70 | 0.7 | -0.0313 | -0.0271 | +13 | 0.0402 | 0.0533 | +33 | 0.987 |" in text
    assert "+20.0" in text and "+50.0" in text                     # planted DA errors
    assert "| 1D-A70 | planted | +50.0 | +20.0 | yes |" in text      # deposition improves the runout
    # the reported row (no finite tolerance) is counted apart, never as passed, even when an old
    # table wrote passed = True for it
    assert "1 of 2 checked rows pass; 1 reported" in text and "**NO**" in text and "| reported |" in text
    assert "| isph/T22-A70 | 123.4 | 457 |" in text
    assert "[fig5_free_surface.png](figures/fig5_free_surface.png)" in text
    # only the two studies beyond the paper (separate targets) were not given
    # + claims scorecard, regression diagnosis, reading matrix, ensembles and the convergence ensembles
    # not given (the DA per reading is a study target: its section says how to run it)
    assert text.count("Not available") == 7
    assert "convergence runs (`snakemake -j2 convergence`)" in text and "sensitivity table" in text


def test_summary_missing_inputs_do_not_crash(tmp_path):
    text = build_summary(regression=tmp_path / "nope", compare=None, verification=[tmp_path / "v.csv"],
                         benchmarks=None, figures=None)
    # table 3, table 5, compare, verification, convergence, sensitivity, benchmarks, figures, claims
    # scorecard, regression diagnosis, reading matrix (the DA per reading names its target instead)
    assert text.count("_Not available") == 11
    assert "table3_comparison.csv not found" in text


def test_cli_summary(inputs, tmp_path):
    out = tmp_path / "out" / "summary.md"
    args = ["summary", "-o", str(out), "--regression", str(inputs["regression"]), "--compare", str(inputs["compare"]),
            "--verification", *map(str, inputs["verification"]), "--benchmarks", str(inputs["benchmarks"])]
    assert main(args) == 0
    assert "## Table 3" in out.read_text()


CAPTIONS = Path(__file__).resolve().parents[2] / "workflow" / "report"


def _figure_lines(text):
    return [ln for ln in text.split("## Figures", 1)[1].splitlines() if ln.startswith("- [")]


def test_summary_lists_every_figure_given_with_its_caption(tmp_path):
    """The workflow passes every figure as NAME=PATH and the report's captions; each is listed
    with a non-empty caption (before, the summary rule gave no figures and the section said 'not given')."""
    names = sorted(p.stem for p in CAPTIONS.glob("*.rst"))
    assert len(names) >= 17
    figs = []
    for n in names:
        f = tmp_path / "figures" / f"{n}_drawn.png"
        f.parent.mkdir(exist_ok=True)
        f.write_bytes(b"\x89PNG" + b"0" * 3000)
        figs.append(f"{n}={f}")
    out = tmp_path / "summary.md"
    assert main(["summary", "-o", str(out), "--figures", *figs, "--captions", str(CAPTIONS)]) == 0
    lines = _figure_lines(out.read_text())
    assert len(lines) == len(names)
    for n, ln in zip(names, lines):
        assert f"[{n}_drawn.png](figures/{n}_drawn.png) (3 kB): " in ln
        caption = ln.split("): ", 1)[1]
        assert len(caption) > 20 and "no caption" not in caption and "**" not in caption and "{{" not in caption
    assert any("Fig 5 – free surface of T22-A70" in ln for ln in lines)


def test_summary_names_a_figure_without_caption_or_file(tmp_path):
    text = build_summary(figures=[f"fig99={tmp_path / 'fig99.png'}"], captions=CAPTIONS, output=tmp_path / "s.md")
    (line,) = _figure_lines(text)
    assert "**missing**" in line and "no caption (`fig99.rst` not found)" in line


def test_md_table_escapes_and_formats():
    t = md_table(pd.DataFrame({"a": ["x|y"], "b": [float("nan")], "c": [True]}), {"a": ("A", ""), "b": ("B", ".2f"), "c": ("C", "")})
    assert t.splitlines()[2] == "| x\\|y | – | yes |"


def test_summary_study_sections_read_the_runs(tmp_path):
    conv = tmp_path / "convergence"
    for sub in ("isph", "da", "regression"):
        (conv / sub).mkdir(parents=True)
    # planted 2D runs: runout 0.30, 0.36, 0.38 m at dx = 8, 6, 4 mm (ΔL/L0 = 1.5, 1.8, 1.9)
    for dx, runout in ((0.008, 0.30), (0.006, 0.36), (0.004, 0.38)):
        ds = syn.isph_run(dx=dx, runout=runout)
        ds.attrs["n_outflow"] = 3 if dx == 0.006 else 0
        syn.save(ds, conv / "isph" / f"T22-A70_dx{dx}.nc")
        d = conv / "regression" / f"T22-A70_dx{dx}"
        d.mkdir()
        pd.DataFrame({"x_norm": [0.2, 0.4], "t_s_critical": [100 * dx, 200 * dx], "dx": [dx, dx]}).to_csv(
            d / "critical.csv", index=False)
    for n, r in ((250, 1.6), (500, 1.7), (1000, 1.75)):
        syn.save(syn.da_run("1D-A70", True, r, 1.2, n=n), conv / "da" / f"1D-A70_n{n}_deposition.nc")
    sens = tmp_path / "sensitivity.csv"
    pd.DataFrame({"parameter": ["phi_basal_deg"] * 2, "value": [23.5, 25.5], "baseline": [0, 1],
                  "A": [-0.02, -0.01], "B": [0.03, 0.02], "final_runout_norm": [15.0, 12.0],
                  "flow_time": [3.0, 2.5]}).to_csv(sens, index=False)
    text = build_summary(convergence=conv, sensitivity=sens)
    assert "| T22-A70_dx0.004 | 4.0 | 1.900 |" in text and "| T22-A70_dx0.008 | 8.0 | 1.500 |" in text
    assert "| 3 |" in text                                           # outflow particles of the 6 mm run
    assert "runout +5.3 %" in text                                   # (1.9 - 1.8)/1.9
    assert "| 4.0 | 0.40 | 0.80 |" in text and "| 8.0 | 0.80 | 1.60 |" in text   # (t_s)_C rows
    assert "| 1D-A70 | deposition | 1.600 | 1.700 | 1.750 |" in text
    assert "+2.9 |" in text                                          # (1.75 - 1.70)/1.75
    assert "| phi_basal_deg | 23.5 | no | -0.0200 | -100 | 0.0300 | +50 | 15.000 | +25.0 | 3.000 | +20.0 |" in text
    assert "Not available" not in text.split("## Convergence", 1)[1].split("## Benchmarks", 1)[0]
    # the configured lists only: the 6 mm run and the N = 250 run are left out (files of an earlier list)
    sel = build_summary(convergence=conv, convergence_dx=[0.008, 0.004], convergence_n=[500, 1000])
    sec = sel.split("## Convergence", 1)[1].split("## Sensitivity", 1)[0]
    assert "T22-A70_dx0.006" not in sec and "| 6.0 |" not in sec
    assert "| T22-A70_dx0.004 | 4.0 | 1.900 |" in sec
    assert "runout +21.1 %" in sec                                   # (1.9 - 1.5)/1.9: 8 -> 4 mm now
    assert "| 1D-A70 | deposition | 1.700 | 1.750 |" in sec and "N=250" not in sec
    from granudep.report.captions import caption_numbers
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "convergence").symlink_to(conv, target_is_directory=True)
    nums = caption_numbers(tmp_path / "results", convergence_dx=[0.008, 0.004])
    assert "dx = 6 mm" not in nums["convergence"] and "dx = 4 mm" in nums["convergence"]
    assert "dx = 6 mm" in caption_numbers(tmp_path / "results")["convergence"]


def test_caption_numbers_from_outputs_and_rendered_in_captions(inputs, tmp_path):
    jinja2 = pytest.importorskip("jinja2")
    from pathlib import Path
    from types import SimpleNamespace
    from granudep.report.captions import caption_numbers
    root = tmp_path / "results"
    (root / "compare").mkdir(parents=True)
    inputs["regression"].rename(root / "regression")
    Path(inputs["compare"]).rename(root / "compare" / "comparison.csv")
    nums = caption_numbers(root)
    assert "3.0 % (onset), 5.1 % (fit intercept) over 1" in nums["table3"]
    assert nums["fig10"] == "T22-A70 at [x] = 0.2: (t_s)_C = 8.14 (paper 7.90)"
    assert nums["table5"] == "a = 0.7: A = -0.0271 (paper -0.0313), B = 0.0533 (paper 0.0402)"
    assert "no deposition, runout: largest absolute error 50 % at 1D-A70 (paper 55 %)" in nums["fig16"]
    assert "deposition, runout: largest absolute error 20 % at 1D-A70 (paper 17 %)" in nums["fig16"]
    assert not any("|" in v for v in nums.values())  # reStructuredText substitution syntax
    assert nums["sensitivity"].startswith("not computed yet") and nums["convergence"].startswith("not computed yet")
    caption = (Path(__file__).resolve().parents[2] / "workflow" / "report" / "fig16.rst").read_text()
    text = jinja2.Environment().from_string(caption).render(
        snakemake=SimpleNamespace(config={"_caption_numbers": nums}))
    assert "largest absolute error 50 % at 1D-A70 (paper 55 %)" in text
    # without numbers (config key absent) the caption still renders
    assert "not computed yet" in jinja2.Environment().from_string(caption).render(snakemake=SimpleNamespace(config={}))


def test_cli_writes_caption_numbers(inputs, tmp_path):
    import json
    out = tmp_path / "caps.json"
    rc = main(["summary", "-o", str(tmp_path / "s.md"), "--caption-numbers", str(out), "--results", str(tmp_path)])
    assert rc == 0
    nums = json.loads(out.read_text())
    assert {"table3", "table5", "fig5", "fig7", "fig8", "fig10", "fig15", "fig16", "fig17", "figA1", "figA2",
            "convergence", "sensitivity"} <= set(nums)
