"""Module names say what they make (the old `compare` aliases are gone); the report
stage is one package with its own CLI and no upward import."""
from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "granudep"


def test_the_old_compare_names_are_gone():
    """``granudep.compare`` and ``granudep.regress.compare`` were aliases of the modules named for what
    they make; nothing imports them any more."""
    import importlib.util
    assert importlib.util.find_spec("granudep.compare") is None
    assert importlib.util.find_spec("granudep.regress.compare") is None
    import granudep.regress.paper_tables  # noqa: F401
    import granudep.report.da_vs_reference  # noqa: F401


def _imports(path: Path) -> set[str]:
    out = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            out.add("." * node.level + (node.module or ""))
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return out


def test_report_and_claims_do_not_import_upward_into_figures():
    files = sorted((SRC / "report").glob("*.py"))
    assert {f.name for f in files} >= {"summary.py", "claims.py", "da_vs_reference.py", "readme_status.py",
                                       "captions.py", "cli.py"}
    for path in files:
        bad = [m for m in _imports(path) if "figures" in m]
        assert not bad, f"report/{path.name} imports {bad}"


def test_the_report_stage_registers_its_own_commands():
    from granudep.cli import build_parser
    from granudep.report import cli
    sub = build_parser()._subparsers._group_actions[0]
    for name in ("reference", "compare", "summary", "sensitivity-table", "readme-status"):
        assert sub.choices[name].get_default("func").__module__.startswith("granudep.report."), name
    assert sub.choices["reference"].get_default("func") is cli._cmd_reference
    figures = sub.choices["figure"]._subparsers._group_actions[0].choices
    assert {f.get_default("func").__module__ for f in figures.values()} == {"granudep.figures.cli"}
