"""How a verification table is counted, shared by both suites, the CLI, the summary and the README.

A row is **checked** when its tolerance is finite: it passes when its error is finite and
``|error| <= tolerance``, and fails otherwise. A row whose tolerance is not finite is **reported**:
it carries a measured number beside a reference but can never pass or fail, so it is counted apart
and never as passed. ``granudep verify`` exits 1 when a checked row fails.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import pandas as pd

PASS, FAIL, REPORTED = "pass", "fail", "reported"


def is_reported(tolerance) -> bool:
    """A row without a finite tolerance (NaN, ±inf or missing) is reported, not checked."""
    try:
        return not math.isfinite(float(tolerance))
    except (TypeError, ValueError):
        return True


def row_passed(error, tolerance) -> bool:
    """The ``passed`` column of a row: a checked row within its tolerance; False for a reported row."""
    if is_reported(tolerance):
        return False
    e = float(error)
    return bool(math.isfinite(e) and abs(e) <= float(tolerance))


def _truthy(values: pd.Series) -> pd.Series:
    return values.astype(str).str.strip().str.lower().isin(["true", "1", "yes"])


def statuses(table: pd.DataFrame) -> pd.Series:
    """``pass`` / ``fail`` / ``reported`` per row of a verification table (read from a CSV or built in
    memory). The tolerance decides whether a row is checked; for a checked row the ``passed`` column
    decides (tables written before the tolerance column existed count every row as checked)."""
    passed = _truthy(table["passed"]) if "passed" in table else pd.Series(False, index=table.index)
    if "tolerance" in table:
        reported = pd.to_numeric(table["tolerance"], errors="coerce").map(is_reported)
    else:
        reported = pd.Series(False, index=table.index)
    out = pd.Series(FAIL, index=table.index, dtype=object)
    out[passed] = PASS
    out[reported.astype(bool)] = REPORTED
    return out


@dataclass
class Counts:
    checked: int = 0
    passed: int = 0
    reported: int = 0
    failing: list = field(default_factory=list)  # names of the checks with a failed row, in table order

    @property
    def failed(self) -> int:
        return self.checked - self.passed

    def sentence(self) -> str:
        """``N of M checked rows pass; K reported``: the one wording of the summary and the README."""
        return f"{self.passed} of {self.checked} checked rows pass; {self.reported} reported"

    def __add__(self, other: "Counts") -> "Counts":
        return Counts(self.checked + other.checked, self.passed + other.passed, self.reported + other.reported,
                      list(dict.fromkeys(self.failing + other.failing)))


def count(table: pd.DataFrame) -> Counts:
    """The counts of one verification table."""
    s = statuses(table)
    failing = list(dict.fromkeys(table.loc[s == FAIL, "check"].astype(str))) if "check" in table else []
    return Counts(checked=int((s != REPORTED).sum()), passed=int((s == PASS).sum()),
                  reported=int((s == REPORTED).sum()), failing=failing)


def exit_code(table: pd.DataFrame, report_only: bool = False) -> int:
    """1 when a checked row fails (the workflow and CI stop there), else 0; ``report_only``: always 0."""
    return 0 if report_only or count(table).failed == 0 else 1
