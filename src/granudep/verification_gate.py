"""How a verification table is counted, shared by both suites, the CLI, the summary and the README.

A row is **checked** when its tolerance is finite: it passes when its error is finite and
``|error| <= tolerance``, and fails otherwise. A row whose tolerance is not finite is **reported**:
it carries a measured number beside a reference but can never pass or fail, so it is counted apart
and never as passed. ``granudep verify`` exits 1 when a checked row fails.
"""
from __future__ import annotations

import math
import re
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


# --- the chain's resolution beside the checked rows ------------------------------------------------
# A check's rows differ by resolution only in their ``dx = N mm`` (or ``h/dx = N``) words; the same
# quantity at the chain's dx (isph.dx = 4 mm) is reported beside the row that is checked at a finer dx.
_DX_WORDS = re.compile(r"(?:h/)?dx ?= ?([0-9]+(?:\.[0-9]+)?)( ?mm)?")
_DX_NOTE = re.compile(r"\bdx ?= ?([0-9]+(?:\.[0-9]+)?) ?(mm)?")
_H_NOTE = re.compile(r"\bh ?= ?([0-9.]+ ?(?:mm|m))")


def row_dx_mm(quantity: str, note: str = "") -> float:
    """The particle spacing of a verification row in mm, read from its quantity (``dx = 2 mm``) or its
    note (``dx=4 mm``, ``dx=0.004`` in metres); NaN when the row names none."""
    m = re.search(r"\bdx ?= ?([0-9]+(?:\.[0-9]+)?) ?mm", str(quantity))
    if m:
        return float(m.group(1))
    m = _DX_NOTE.search(str(note))
    if not m:
        return math.nan
    return float(m.group(1)) * (1.0 if m.group(2) else 1e3)  # a bare number in a note is in metres


def pair_key(check: str, quantity: str, note: str = "") -> str:
    """The quantity of a row with its resolution words removed (plus the layer depth of a note, so
    that a layer of another depth is another quantity)."""
    q = _DX_WORDS.sub("", str(quantity))
    q = re.sub(r" \(reported[^)]*\)", "", q)
    q = re.sub(r"[ ,]+$", "", re.sub(r",\s*,", ",", q)).strip()
    h = _H_NOTE.search(str(note))
    return f"{check}\t{q}" + (f"\th={h.group(1).replace(' ', '')}" if h else "")


def chain_dx_pairs(table: pd.DataFrame, chain_dx_mm: float) -> pd.DataFrame:
    """Per checked row that has the same quantity at the chain's dx in the table: check, quantity,
    the checked row's dx, error, tolerance and status, and the chain-dx row's dx, error and status."""
    s = statuses(table)
    notes = table["note"] if "note" in table else pd.Series("", index=table.index)
    dxs = [row_dx_mm(q, n) for q, n in zip(table["quantity"], notes)]
    keys = [pair_key(c, q, n) for c, q, n in zip(table["check"], table["quantity"], notes)]
    chain = {}
    for i, (k, d) in enumerate(zip(keys, dxs)):
        if math.isfinite(d) and abs(d - chain_dx_mm) < 1e-9:
            chain.setdefault(k, i)
    rows = []
    for i, (k, d) in enumerate(zip(keys, dxs)):
        if s.iloc[i] == REPORTED or k not in chain or chain[k] == i:
            continue
        j = chain[k]
        rows.append({"check": table["check"].iloc[i], "quantity": table["quantity"].iloc[i], "dx_mm": d,
                     "error": float(table["error"].iloc[i]), "tolerance": float(table["tolerance"].iloc[i]),
                     "status": s.iloc[i], "chain_dx_mm": chain_dx_mm, "chain_error": float(table["error"].iloc[j]),
                     "chain_status": s.iloc[j], "chain_tolerance": float(pd.to_numeric(table["tolerance"].iloc[j],
                                                                                       errors="coerce"))})
    return pd.DataFrame(rows, columns=["check", "quantity", "dx_mm", "error", "tolerance", "status", "chain_dx_mm",
                                       "chain_error", "chain_status", "chain_tolerance"])


def with_chain_dx_error(table: pd.DataFrame, chain_dx_mm: float) -> pd.DataFrame:
    """``table`` with a column ``chain_dx_error``: beside each checked row, the error of the same
    quantity at the chain's dx (NaN where the suite has no such row)."""
    out = table.copy()
    pairs = chain_dx_pairs(table, chain_dx_mm)
    col = pd.Series(math.nan, index=out.index)
    for r in pairs.itertuples():
        hit = (out["check"] == r.check) & (out["quantity"] == r.quantity)
        col[hit] = r.chain_error
    out["chain_dx_error"] = col
    return out


def checked_at_dx(table: pd.DataFrame, dx_mm: float) -> int:
    """How many checked rows are at this particle spacing."""
    s = statuses(table)
    notes = table["note"] if "note" in table else pd.Series("", index=table.index)
    return int(sum(st != REPORTED and math.isfinite(d := row_dx_mm(q, n)) and abs(d - dx_mm) < 1e-9
                   for st, q, n in zip(s, table["quantity"], notes)))


def chain_dx_lines(table: pd.DataFrame, chain_dx_mm: float = 4.0) -> list[str]:
    """'bagnold: 0.026 at 1 mm (checked, pass), 0.2 at 4 mm (the chain's dx, reported)' per checked
    row of ``table`` whose quantity the suite also measures at the chain's dx, and the count of
    checked rows at the chain's dx."""
    if not {"check", "quantity", "error", "tolerance"} <= set(table.columns):
        return []
    out = []
    for r in chain_dx_pairs(table, chain_dx_mm).itertuples():
        unit = " m/s" if "m/s" in r.quantity else ""
        if "(1 = yes)" in r.quantity:    # a yes/no row (stable or not): its error is 0 or 1, not a percentage
            def fmt(e):
                return "yes" if e == 0 else "no"
        elif "E_0" in r.quantity or "E_ref" in r.quantity:  # an energy excess: a signed fraction of E_ref
            def fmt(e):
                return f"{e:.2e} E_ref"
        else:
            fmt = (lambda e: f"{e:.3f}{unit}") if unit else (lambda e: f"{100 * e:.1f} %")
        what = pair_key(r.check, r.quantity).split("\t")[1]
        out.append(f"`{r.check}` ({what}): "
                   f"{fmt(r.error)} at {r.dx_mm:g} mm (checked, {r.status}), {fmt(r.chain_error)} at "
                   f"{r.chain_dx_mm:g} mm (the chain's dx, {r.chain_status})")
    if out:
        out.append(f"{checked_at_dx(table, chain_dx_mm)} of {count(table).checked} checked rows are at the chain's dx")
    return out
