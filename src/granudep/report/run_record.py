"""The record of one workflow run (``results/benchmarks/run.json``): when it started and ended, its
wall time, the targets, the cores and the commit. Written by the Snakefile's ``onsuccess`` handler
(never on a dry run), read by ``granudep readme-status``, so that the README's run time is the run's
own measurement, not a typed number."""
from __future__ import annotations

import json
import math
import time
from pathlib import Path

from ..io import write_text
from .._version import commit


def write_run_record(path: str | Path, started: float, targets, cores, n_jobs: int | None = None) -> Path:
    """Write the record of a run that started at ``started`` (epoch s) and succeeded now."""
    ended = time.time()
    record = {"started_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(started)),
              "ended_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(ended)),
              "wall_s": round(ended - started, 1), "targets": sorted(targets or []) or ["all"],
              "cores": cores, "jobs": n_jobs, "commit": commit() or "unknown"}
    return write_text(json.dumps(record, indent=1) + "\n", path)


def read_run_record(path: str | Path) -> dict | None:
    """The record, or None when missing or unreadable."""
    p = Path(path)
    try:
        rec = json.loads(p.read_text()) if p.is_file() else None
    except (OSError, ValueError):
        return None
    if not isinstance(rec, dict) or not math.isfinite(float(rec.get("wall_s", math.nan))):
        return None
    return rec
