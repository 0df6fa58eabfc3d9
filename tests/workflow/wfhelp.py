"""Shared machinery of the workflow dry-run tests (tests/workflow/test_workflow*.py).

* One copy of the workflow (Snakefile, workflow/, config/, profiles/, benchmarks/) per session, in
  a fresh folder, so results or a running workflow in the checkout cannot change the job counts.
* Every `snakemake` here runs with a `scontrol` that fails at once first on PATH: the SLURM executor
  plugin, imported by every snakemake command line to build its options, asks
  `scontrol show config` for MinJobAge while building its help text; with slurm installed but no
  controller that call waits ~9 s (per invocation), and no dry run needs the answer (the real
  SLURM route is tests/workflow/test_slurm_real.py, slow, which keeps the real scontrol).
* The dry runs are independent subprocesses: tests/conftest.py hands the ones the selected tests
  will ask for to `prefetch` when collection ends, and one background worker runs them while the
  rest of the suite computes (2 cores: the numba tests use one); a test then waits only for its own
  result. `dry_run` runs anything not prefetched directly.
"""
from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]
SNAKEMAKE = [sys.executable, "-m", "snakemake"]

_lock = threading.Lock()
_state: dict = {"dir": None, "pool": None, "futures": {}}


def workdir() -> Path:
    """The session's copy of the workflow (created on first use)."""
    with _lock:
        if _state["dir"] is None:
            base = Path(tempfile.mkdtemp(prefix="granudep-wf-"))
            d = base / "wf"
            d.mkdir()
            shutil.copy(ROOT / "Snakefile", d / "Snakefile")
            for sub in ("workflow", "config", "profiles", "benchmarks"):
                shutil.copytree(ROOT / sub, d / sub)
            shim = base / "bin"
            shim.mkdir()
            (shim / "scontrol").write_text("#!/bin/sh\nexit 1\n")
            (shim / "scontrol").chmod(0o755)
            (base / "overlays").mkdir()
            _state["dir"] = d
        return _state["dir"]


def env() -> dict:
    e = dict(os.environ)
    e["PATH"] = f"{workdir().parent / 'bin'}{os.pathsep}{e.get('PATH', '')}"
    return e


def overlay(content) -> Path:
    """A config overlay file (YAML text, or a mapping dumped as YAML) at a path fixed by its content,
    so the prefetch and the test name the same file."""
    text = content if isinstance(content, str) else yaml.safe_dump(content)
    path = workdir().parent / "overlays" / f"{hashlib.sha1(text.encode()).hexdigest()[:12]}.yaml"
    with _lock:
        if not path.exists():
            path.write_text(text)
    return path


def _parse(proc: subprocess.CompletedProcess) -> tuple[int, str, dict[str, int]]:
    out = proc.stdout + proc.stderr
    counts = {}
    if "Job stats:" in out:
        table = out.split("Job stats:", 1)[1]
        for line in table.splitlines()[3:]:
            m = re.match(r"^(\S+)\s+(\d+)$", line.strip())
            if not m:
                break
            counts[m.group(1)] = int(m.group(2))
    return proc.returncode, out, counts


def _run(args: tuple[str, ...]) -> tuple[int, str, dict[str, int]]:
    proc = subprocess.run(SNAKEMAKE + ["-n", "-p", "--nolock", *args], cwd=workdir(), env=env(),
                          capture_output=True, text=True, timeout=300)
    return _parse(proc)


def prefetch(arg_sets) -> None:
    """Start the given dry runs in one background worker, in order (each once)."""
    with _lock:
        if _state["pool"] is None:
            _state["pool"] = ThreadPoolExecutor(max_workers=1, thread_name_prefix="dry-run")
        for args in arg_sets:
            args = tuple(args)
            if args not in _state["futures"]:
                _state["futures"][args] = _state["pool"].submit(_run, args)


def dry_run(wd: Path, *args: str) -> tuple[int, str, dict[str, int]]:
    """`snakemake -n -p --nolock ARGS` in the workflow copy: exit code, output, job-count table."""
    assert Path(wd) == workdir()
    with _lock:
        fut: Future | None = _state["futures"].get(tuple(args))
    return fut.result() if fut is not None else _run(tuple(args))


def shutdown() -> None:
    with _lock:
        pool, d = _state["pool"], _state["dir"]
        _state.update(pool=None, dir=None, futures={})
    if pool is not None:
        pool.shutdown(wait=True, cancel_futures=True)
    if d is not None:
        shutil.rmtree(d.parent, ignore_errors=True)
