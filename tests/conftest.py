"""Suite-wide hooks: the workflow dry runs (independent `snakemake -n` subprocesses) start in the
background as soon as collection ends, so they overlap the computing tests (tests/workflow/wfhelp.py)."""
from __future__ import annotations

import sys
from pathlib import Path

_WORKFLOW_TESTS = Path(__file__).resolve().parent / "workflow"


def pytest_collection_finish(session):
    wanted = []
    for item in session.items:
        ask = getattr(getattr(item, "module", None), "dry_run_args", None)
        if ask is not None:
            wanted.extend(ask(item))
    if wanted:
        sys.path.insert(0, str(_WORKFLOW_TESTS))
        import wfhelp
        wfhelp.prefetch(wanted)


def pytest_sessionfinish(session, exitstatus):
    wfhelp = sys.modules.get("wfhelp")
    if wfhelp is not None:
        wfhelp.shutdown()
