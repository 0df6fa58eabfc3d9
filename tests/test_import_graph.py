"""The import graph of ``src/granudep``: no circle (imports inside functions count too), and the DA
model sits below the stages that plot, report or regress (it imports none of them)."""
from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "granudep"


def _modules() -> dict[str, Path]:
    out = {}
    for p in SRC.rglob("*.py"):
        parts = list(p.relative_to(SRC.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = p
    return out


def _targets(mods, cur: str, node) -> list[str]:
    """Modules of granudep one import statement of module ``cur`` names."""
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    else:
        base = cur.split(".")
        if node.level:
            base = base if mods[cur].name == "__init__.py" else base[:-1]
            base = base[:len(base) - (node.level - 1)]
            m = ".".join(base + ([node.module] if node.module else []))
        else:
            m = node.module
        subs = [f"{m}.{a.name}" for a in node.names if f"{m}.{a.name}" in mods]
        # ``from .. import module`` depends on that module, not on the package's __init__
        names = subs if node.module is None and len(subs) == len(node.names) else [m] + subs
    out = []
    for d in names:
        while d and d not in mods:
            d = d.rpartition(".")[0]
        if d and d != cur and d.startswith("granudep"):
            out.append(d)
    return out


def import_graph() -> dict[str, set[str]]:
    mods = _modules()
    graph = {}
    for m, p in mods.items():
        deps = set()
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                deps.update(_targets(mods, m, node))
        graph[m] = deps
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan, iterative)."""
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))
    return out


def test_the_cycle_finder_finds_a_planted_circle():
    g = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert cycles(g) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_circle_in_src():
    assert cycles(import_graph()) == []


def test_the_da_model_imports_no_plotting_report_or_regression_stage():
    graph = import_graph()
    for m, deps in graph.items():
        if m.startswith("granudep.da"):
            bad = sorted(d for d in deps if d.split(".")[1:2] and d.split(".")[1] in ("figures", "report", "regress"))
            assert not bad, f"{m} imports {bad}"
