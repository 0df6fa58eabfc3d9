"""No numba kernel in ``src/granudep`` takes more than ten arguments (docs/architecture.md, "Kernel
arguments"): arrays passed together travel as one tuple or NamedTuple, so that a new quantity does
not mean editing a dozen signatures."""
from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "granudep"
LIMIT = 10


def _kernels():
    for p in sorted(SRC.rglob("*.py")):
        for f in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            if isinstance(f, ast.FunctionDef) and any(
                    "jit" in ast.unparse(d) or "prange_kernel" in ast.unparse(d) for d in f.decorator_list):
                yield p.relative_to(SRC), f.name, len(f.args.args) + len(f.args.kwonlyargs)


def test_kernels_are_found():
    names = {name for _, name, _ in _kernels()}
    assert {"advance", "evaluate_into", "assemble_ppe", "pcg_dic_split"} <= names


def test_no_kernel_takes_more_than_ten_arguments():
    over = [f"{path}:{name} takes {n}" for path, name, n in _kernels() if n > LIMIT]
    assert not over, "kernels over the limit: " + "; ".join(over)
