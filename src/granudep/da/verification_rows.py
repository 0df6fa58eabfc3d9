"""One row of the table ``granudep verify da`` writes (every DA check, constant slope or path)."""
from __future__ import annotations

from ..verification_gate import row_passed

COLUMNS = ["check", "quantity", "value", "reference", "error", "tolerance", "passed", "note"]


def row(check, quantity, value, reference, error, tolerance, note) -> dict:
    """A row: ``passed`` is ``|error| <= tolerance`` (``granudep.verification_gate.row_passed``)."""
    return {"check": check, "quantity": quantity, "value": float(value), "reference": float(reference),
            "error": float(error), "tolerance": float(tolerance), "passed": row_passed(error, tolerance),
            "note": note}
