#!/usr/bin/env python3
"""Table of every Snakemake rule's benchmark file: wall time and peak memory per job.

Usage: python benchmarks/workflow_summary.py [results/benchmarks] [-o results/benchmarks/summary.csv]

Each rule writes ``results/benchmarks/<rule or stage>/<job>.tsv`` (Snakemake ``benchmark:``):
columns ``s`` (wall seconds) and ``max_rss`` (MB). This prints one line per job, sorted by wall
time, the total wall time summed over jobs (CPU-serial equivalent), and writes the same table as
CSV. Standard library only, so it runs wherever Snakemake runs.
"""
from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path


def _num(text: str) -> float:
    try:
        return float(text)
    except (TypeError, ValueError):
        return float("nan")


def collect(root: Path) -> list[dict]:
    rows = []
    for path in sorted(root.rglob("*.tsv")):
        with path.open(newline="") as fh:
            records = list(csv.DictReader(fh, delimiter="\t"))
        if not records or "s" not in records[0]:
            continue
        rec = records[-1]  # the last repeat
        rel = path.relative_to(root).with_suffix("")
        rows.append({"job": str(rel), "stage": rel.parts[0] if len(rel.parts) > 1 else rel.name,
                     "wall_s": _num(rec.get("s")), "max_rss_mb": _num(rec.get("max_rss"))})
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("root", nargs="?", default="results/benchmarks", help="benchmark folder")
    parser.add_argument("-o", "--output", help="CSV to write (atomically)")
    args = parser.parse_args(argv)
    root = Path(args.root)
    rows = collect(root) if root.is_dir() else []
    if not rows:
        print(f"no benchmark files under {root}", file=sys.stderr)
    rows.sort(key=lambda r: -r["wall_s"] if r["wall_s"] == r["wall_s"] else 0.0)
    width = max([len(r["job"]) for r in rows] + [len("total (sum over jobs)")])
    print(f"{'job':<{width}}  {'wall s':>9}  {'max RSS MB':>10}")
    for r in rows:
        print(f"{r['job']:<{width}}  {r['wall_s']:9.1f}  {r['max_rss_mb']:10.1f}")
    total = sum(r["wall_s"] for r in rows if r["wall_s"] == r["wall_s"])
    print(f"{'total (sum over jobs)':<{width}}  {total:9.1f}")
    stages: dict[str, float] = {}
    for r in rows:
        if r["wall_s"] == r["wall_s"]:
            stages[r["stage"]] = stages.get(r["stage"], 0.0) + r["wall_s"]
    print("per stage: " + ", ".join(f"{k} {v:.1f} s" for k, v in sorted(stages.items(), key=lambda kv: -kv[1])))
    if args.output:
        import io

        from granudep.io import write_text  # atomic, with the usual permissions (mkstemp alone gave 0600)
        buf = io.StringIO(newline="")
        w = csv.DictWriter(buf, fieldnames=["job", "stage", "wall_s", "max_rss_mb"])
        w.writeheader()
        w.writerows(rows)
        write_text(buf.getvalue(), Path(args.output))
    return 0


if __name__ == "__main__":
    sys.exit(main())
