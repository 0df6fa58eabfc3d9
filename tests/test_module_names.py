"""Module names say what they make (issue 15); the old `compare` names keep working."""
from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "granudep"


def test_old_compare_names_are_the_new_modules():
    import granudep.compare
    import granudep.da_vs_reference
    import granudep.regress.compare
    import granudep.regress.paper_tables
    assert granudep.compare is granudep.da_vs_reference
    assert granudep.regress.compare is granudep.regress.paper_tables
    from granudep.compare import compare, reference_from_isph  # noqa: F401
    from granudep.regress.compare import table3_comparison, table5_comparison  # noqa: F401


def _imports(path: Path) -> set[str]:
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            out.add("." * node.level + (node.module or ""))
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return out


def test_report_and_claims_do_not_import_upward_into_figures():
    for name in ("report.py", "claims.py", "da_vs_reference.py", "readme_status.py"):
        bad = [m for m in _imports(SRC / name) if "figures" in m]
        assert not bad, f"{name} imports {bad}"
