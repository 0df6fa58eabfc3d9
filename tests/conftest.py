"""Suite-wide hooks: the workflow dry runs (independent `snakemake -n` subprocesses) start in the
background as soon as collection ends, so they overlap the computing tests (tests/workflow/wfhelp.py)."""
from __future__ import annotations

import os
import sys
from pathlib import Path

# One numba thread unless the caller sets NUMBA_NUM_THREADS (read by numba at import, so before any
# test module imports it): the kernels then run their serial builds (isph/parallel.py), the ones the
# workflow's warmup and one-thread jobs compile, so a CI run compiles each kernel once, and the second
# core runs the background dry runs. The thread-count tests start subprocesses with their own value.
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

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
