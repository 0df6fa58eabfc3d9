"""The converged 2D reference: the finest ladder rung within the tolerance of the next coarser
one, else the workflow's run, every row labelled with its dx and why; the A, B readings' plain labels."""
import math

import pandas as pd
import pytest

import synthetic_data as syn
from granudep import cases
from granudep.cli import main
from granudep.io import var
from granudep.report.da_vs_reference import compare, reading_matrix
from granudep.report.reference_2d import reference_from_isph, select_converged_runs
from granudep.report.readme_status import status_block

L0 = 0.2
# T22-A70's 1 % volume front on the ladder, ΔL/L0 at 4 / 3 / 2 / 1.4 / 1 mm (the Coulomb-bed ladder of 2026-12-02):
# steps +6.3 / +4.1 / +4.2 / +2.3 % of the finer rung, all but the first within 5 %
LADDER_V99 = {0.004: 13.02, 0.003: 13.89, 0.002: 14.49, 0.0014: 15.13, 0.001: 15.49}


def _run(path, dx, v99, case="T22-A70", L0=L0, H0=0.14, runout_2d=None):
    """A 2D run at ``dx`` whose 1 % volume front ends at ΔL/L0 = ``v99`` (2 d front: ``runout_2d``)."""
    ds = syn.isph_run(case, L0=L0, H0=H0, dx=0.02, runout=(runout_2d if runout_2d is not None else v99) * L0)
    ds.attrs["dx"] = dx  # a coarse lattice (small file) labelled with the rung's dx
    ds.attrs["t_c"] = cases.characteristic_time(H0, math.radians(22.0))
    ds["final_front_v99"] = var(L0 * (1 + v99), (), "m", "1 % volume front, final")
    return syn.save(ds, path)


@pytest.fixture()
def ladder(tmp_path):
    (tmp_path / "isph").mkdir()
    (tmp_path / "ladder").mkdir()
    own = [_run(tmp_path / "isph" / "T22-A70.nc", 0.004, LADDER_V99[0.004]),
           _run(tmp_path / "isph" / "T22-A45.nc", 0.004, 9.0, case="T22-A45", L0=0.25, H0=0.1125)]
    # the 2 d front jumps by 20 % per rung: only the volume front converges
    rungs = [_run(tmp_path / "ladder" / f"T22-A70_dx{dx}.nc", dx, v, runout_2d=v * 1.2 ** i)
             for i, (dx, v) in enumerate(LADDER_V99.items())]
    return own, rungs


def test_finest_converged_rung_not_the_finest_file(ladder):
    own, rungs = ladder
    picked = {str(p): (b, ok) for p, b, ok in select_converged_runs(own, rungs)}
    b, ok = picked[rungs[-1]]                     # 1 mm: +2.3 % on 1.4 mm
    assert ok and "converged: dx = 1 mm" in b and "+2.3 %" in b and "dx = 1.4 mm" in b and "5 %" in b
    b, ok = picked[own[1]]                        # T22-A45 has no ladder: its workflow run, said so
    assert not ok and "workflow run dx = 4 mm" in b and "no finer run on disk" in b


def test_gap_in_the_ladder_is_not_converged(ladder):
    own, rungs = ladder
    gap = [rungs[0], rungs[3]]                    # 4 and 1.4 mm only: +14 % > 5 %
    (run, basis, ok), = [t for t in select_converged_runs(own[:1], gap)]
    assert run == own[0] and not ok
    assert "no converged run: workflow run dx = 4 mm" in basis and "no rung within 5 %" in basis and "+13.9 %" in basis


def test_measure_and_tolerance_are_choices(ladder):
    own, rungs = ladder
    (_, basis, ok), = select_converged_runs(own[:1], rungs, measure="2d")   # 2 d front: +17 % per rung
    assert not ok and "no converged run" in basis
    (run, basis, ok), = select_converged_runs(own[:1], rungs, tol=0.02)     # no step within 2 %
    assert not ok and run == own[0]
    (run, basis, ok), = select_converged_runs(own[:1], rungs[:3], tol=0.05)  # ladder to 2 mm: 2 mm
    assert ok and run == rungs[2] and "dx = 2 mm" in basis


def test_labels_say_converged_where_available_and_fallback(ladder):
    own, rungs = ladder
    picked = select_converged_runs(own, rungs)
    ref = reference_from_isph([p for p, _, _ in picked], label="2D converged",
                              basis=[(b, ok) for _, b, ok in picked])
    assert set(ref["reference"]) == {"2D converged where available (dx = 1 / 4 mm)"}
    fresh = select_converged_runs(own, [])
    ref0 = reference_from_isph([p for p, _, _ in fresh], label="2D converged", basis=[(b, ok) for _, b, ok in fresh])
    assert set(ref0["reference"]) == {"2D converged not available: workflow run (dx = 4 mm)"}
    assert ref0["reference_basis"].str.contains("no finer run on disk").all()


def _da(case, dep, runout, source="computed", units="normalised", **kw):
    ds = syn.da_run(case, dep, final_runout_norm=runout, flow_time=1.2, **kw)
    if dep:
        ds.attrs.update(ab_source=source, coefficient_units=units)
    return ds


def test_cli_reference_compare_and_status_label_every_row_with_dx(ladder, tmp_path):
    own, rungs = ladder
    conv = tmp_path / "results" / "compare" / "reference_converged.csv"
    assert main(["reference", *own, "--ladder", *rungs, "--converged", "--label", "2D converged",
                 "-o", str(conv)]) == 0
    ref = pd.read_csv(conv).set_index("case")
    assert ref.loc["1D-A70", "dx"] == pytest.approx(0.001) and ref.loc["1D-A45", "dx"] == pytest.approx(0.004)
    a45 = dict(L0=0.25, H0=0.1125)
    runs = [_da("1D-A70", False, 14.0), _da("1D-A70", True, 13.0), _da("1D-A70", True, 12.0, "paper"),
            _da("1D-A70", True, 11.0, "paper", "dimensional"),
            _da("1D-A45", False, 9.5, **a45), _da("1D-A45", True, 9.0, **a45)]
    table = compare(runs, [conv])
    assert {"reference_dx", "reference_basis", "reading_label"} <= set(table.columns)
    a70 = table[table.case == "1D-A70"]
    assert a70["reference_dx"].tolist() == pytest.approx([0.001] * 4)
    assert a70["reference_basis"].str.startswith("converged").all()
    assert a70.runout_rel_error[a70.reading == "none"].iloc[0] == pytest.approx(
        14.0 / ref.loc["1D-A70", "final_runout_norm"] - 1, rel=1e-9)
    # the A, B readings by their plain labels, in the file
    assert dict(zip(a70.reading, a70.reading_label)) == {"none": "no deposition", "computed": "computed",
                                                         "paper": "paper normalised",
                                                         "paper-dimensional": "paper dimensional"}
    mt = reading_matrix(table)
    assert set(mt.reading_label) == {"computed", "paper normalised", "paper dimensional"}
    assert mt["reference_basis"].str.len().gt(0).all()
    # the README status line names each case's dx and why
    main_rows = table[table.reading.isin(["computed", "none"])]
    main_rows.to_csv(tmp_path / "results" / "compare" / "comparison.csv", index=False)
    from granudep.report.summary import section_compare
    text = section_compare(tmp_path / "results" / "compare" / "comparison.csv")
    assert "| A, B reading | reference | ref. dx (mm) | why this reference |" in text
    assert "| 1D-A70 | deposition | computed | 2D converged where available (dx = 1 / 4 mm) | 1 | converged: dx = 1 mm" in text
    block = status_block(tmp_path / "results")
    line = next(s for s in block.splitlines() if "**DA vs 2D converged" in s)
    assert "2D converged where available (dx = 1 / 4 mm)" in line
    assert "1D-A70: converged: dx = 1 mm" in line and "1D-A45: no converged run: workflow run dx = 4 mm" in line


def test_scorecard_reads_a_fallback_as_no_converged_value(ladder, tmp_path):
    """The claims' "ours converged" column is filled only from a converged rung, never from the
    workflow run the converged reference fell back to (read as the paper-resolution value)."""
    from granudep.report.claims import scorecard
    own, rungs = ladder
    for name, ladder_files in (("fresh", []), ("ladder", rungs)):
        res = tmp_path / name
        (res / "compare").mkdir(parents=True)
        (res / "isph").mkdir()
        (res / "isph" / "T22-A70.nc").write_bytes(open(own[0], "rb").read())
        main(["reference", str(res / "isph" / "T22-A70.nc"), "--ladder", *ladder_files, "--converged",
              "--label", "2D converged", "-o", str(res / "compare" / "reference_converged.csv")])
        row = scorecard(res).set_index("claim_id").loc["rest_time_T22-A70"]
        if name == "fresh":
            assert row["basis"] == "paper resolution" and row["ours_converged"] != row["ours_converged"]
        else:
            assert row["basis"] == "converged" and row["converged_dx_mm"] == pytest.approx(1.0)


def test_a_rung_not_at_rest_is_never_the_converged_one(ladder, tmp_path):
    own, rungs = ladder
    from granudep.io import open_dataset
    ds = open_dataset(rungs[-1])
    ds["time_to_rest"] = var(float("nan"), (), "s", "time to rest")   # the 1 mm run stopped before rest
    stopped = syn.save(ds, tmp_path / "T22-A70_dx0.001_stopped.nc")
    (run, basis, ok), = select_converged_runs(own[:1], [*rungs[:-1], stopped])
    assert ok and run == rungs[-2] and "converged: dx = 1.4 mm" in basis
