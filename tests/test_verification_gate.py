"""Verification counts what it checks: a row without a finite tolerance is reported, never passed, and
`granudep verify` exits 1 when a checked row fails (`--report-only`: 0)."""
from __future__ import annotations

import math

import pandas as pd
import pytest

from granudep.cli import main
from granudep.verification_gate import count, exit_code, row_passed, statuses

COLUMNS = ["check", "quantity", "value", "reference", "error", "tolerance", "passed", "note"]


def _table(rows):
    return pd.DataFrame([dict(zip(COLUMNS, r)) for r in rows], columns=COLUMNS)


def test_row_passed_needs_a_finite_tolerance_and_a_finite_error():
    assert row_passed(0.01, 0.02) and row_passed(-0.01, 0.02) and row_passed(0.0, 0.0)
    assert not row_passed(0.03, 0.02)
    assert not row_passed(math.nan, 0.02)           # a checked quantity that could not be computed fails
    assert not row_passed(0.0, math.inf)            # reported: never passed
    assert not row_passed(math.nan, math.inf)


def test_both_suites_build_rows_with_the_shared_rule():
    from granudep.da.verification_rows import row as da_row
    from granudep.isph.verification import _row as isph_row
    for row in (da_row, isph_row):
        assert row("c", "q", 1.0, 1.0, 0.5, math.inf, "")["passed"] is False
        assert row("c", "q", 1.0, 1.0, 0.01, 0.02, "")["passed"] is True
        assert row("c", "q", 1.0, 1.0, -0.5, 0.02, "")["passed"] is False


def test_count_separates_checked_and_reported_rows():
    t = _table([("a", "q", 1, 1, 0.0, 0.1, True, ""), ("b", "q", 1, 1, 0.5, 0.1, False, ""),
                ("c", "q", 1, 1, 0.5, math.inf, True, ""),   # an old table's reported row marked passed
                ("d", "q", 1, 1, math.nan, math.inf, False, "")])
    c = count(t)
    assert (c.checked, c.passed, c.failed, c.reported, c.failing) == (2, 1, 1, 2, ["b"])
    assert c.sentence() == "1 of 2 checked rows pass; 2 reported"
    assert list(statuses(t)) == ["pass", "fail", "reported", "reported"]
    assert exit_code(t) == 1 and exit_code(t, report_only=True) == 0
    assert exit_code(t[t.check != "b"]) == 0


def _planted_suite(monkeypatch, rows):
    import granudep.isph.verification as v
    monkeypatch.setattr(v, "CHECKS", {"planted": lambda quick=False: rows})


@pytest.mark.parametrize("extra, expected", [([], 0), ([("planted", "bad", 2.0, 1.0, 1.0, 0.1)], 1)])
def test_verify_exits_1_when_a_checked_row_fails(monkeypatch, tmp_path, extra, expected):
    from granudep.isph.verification import _row
    rows = [_row("planted", "good", 1.0, 1.0, 0.0, 0.1), _row("planted", "reported", 9.0, 1.0, 8.0, math.inf)]
    rows += [_row(*r) for r in extra]
    _planted_suite(monkeypatch, rows)
    out = tmp_path / "isph.csv"
    assert main(["verify", "isph", "--checks", "planted", "-o", str(out)]) == expected
    assert out.is_file()  # the table is written either way
    assert main(["verify", "isph", "--checks", "planted", "--report-only", "-o", str(out)]) == 0
    # the merge of parts is as strict as the parts
    assert main(["verify", "isph", "--merge", str(out), "-o", str(tmp_path / "merged.csv")]) == expected


def test_workflow_and_ci_run_verify_in_the_strict_form():
    from pathlib import Path
    text = (Path(__file__).resolve().parents[1] / "workflow/rules/verify.smk").read_text()
    rules = "\n".join(line.split("#", 1)[0] for line in text.splitlines())  # the rules, not their comments
    # verify da, verify isph per part, and the two merges (the chain's parts, the fine parts)
    assert rules.count("granudep verify") == 4 and "--report-only" not in rules
