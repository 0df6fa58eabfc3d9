"""Figs 15–17 from synthetic DA runs, 2D runs and a compare table: files exist, are PNGs, non-trivial."""
import pandas as pd
import pytest

import synthetic_data as syn
from granudep.cli import main
from granudep.report.da_vs_reference import compare
from granudep.figures import runout

PNG = b"\x89PNG\r\n\x1a\n"


def check_png(path, min_bytes=8000):
    data = path.read_bytes()
    assert data[:8] == PNG
    assert len(data) > min_bytes  # a blank canvas of this size is ~3–5 kB


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("runout")
    f = {"isph": [syn.save(syn.isph_run("T22-A70"), d / "T22-A70.nc"),
                  syn.save(syn.isph_run("T22-A30", L0=0.3, H0=0.09, runout=0.4), d / "T22-A30.nc")],
         "da": []}
    for case, L0, H0 in (("1D-A70", 0.2, 0.14), ("1D-A30", 0.3, 0.09)):
        for dep, r in ((True, 1.8), (False, 2.25)):
            f["da"].append(syn.save(syn.da_run(case, dep, r, 1.2, L0=L0, H0=H0), d / f"{case}_{int(dep)}.nc"))
    ref = pd.DataFrame({"case": ["1D-A70", "1D-A30"], "final_runout_norm": [1.5, 1.3], "flow_time": [1.0, 1.0],
                        "flow_time_norm": [8.0, 10.0], "provenance": ["planted", "planted"]})
    f["ref"] = str(d / "ref.csv")
    ref.to_csv(f["ref"], index=False)
    f["cmp"] = str(d / "cmp.csv")
    compare(f["da"], [ref]).to_csv(f["cmp"], index=False)
    return f


def test_fig15_panels_and_lines(files):
    fig = runout.fig15(files["da"], files["isph"], [files["ref"]])
    axes = [a for a in fig.axes if a.get_visible()]
    assert len(axes) == 2
    # per panel: one 2D line + 2 DA lines, and the reference final-runout line
    ax = axes[0]
    labels = [l.get_label() for l in ax.get_lines()]
    assert any(l.startswith("2D ISPH") for l in labels)
    # the deposition line names its A, B reading (plain reading labels)
    assert any(l.startswith("DA, with deposition (A, B: ") for l in labels) and "DA, no deposition" in labels
    assert axes[0].get_title(loc="left").startswith("(a) 1D-A30")  # Table 5 order
    text = " ".join(t.get_text() for t in fig.texts)
    assert "1.40 mm" in text and "not available" in text


def test_fig16_values_and_errors(files):
    fig = runout.fig16(files["cmp"])
    ax = fig.axes[0]
    heights = sorted(round(p.get_height(), 9) for p in ax.patches)
    assert heights == sorted([1.5, 1.3, 1.8, 2.25, 1.8, 2.25])
    labels = {t.get_text() for t in ax.texts}
    assert "+20%" in labels and "+50%" in labels  # 1.8/1.5 − 1, 2.25/1.5 − 1


def test_fig17_two_times(files):
    fig = runout.fig17(files["da"][:1], times=[0.5, 1.6])
    labels = [l.get_label() for l in fig.axes[0].get_lines()]
    assert labels[0] == "h_T, t = 0.50 s" and labels[2] == "h_T, t = 1.60 s"


@pytest.mark.parametrize("name,extra", [
    ("fig15", lambda f: [*f["da"], *f["isph"], f["ref"]]),
    ("fig16", lambda f: [f["cmp"]]),
    ("fig17", lambda f: [f["da"][0], f["da"][2]]),
])
def test_cli_writes_png(files, tmp_path, name, extra):
    out = tmp_path / f"{name}.png"
    assert main(["figure", name, "-o", str(out), *extra(files)]) == 0
    check_png(out)


def test_cli_missing_input_is_one_line_error(tmp_path, capsys):
    assert main(["figure", "fig17", "-o", str(tmp_path / "x.png"), str(tmp_path / "nope.nc")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()
