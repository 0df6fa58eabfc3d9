"""The version: the release number plus, in a git checkout, the commit (git describe).

``__version__`` is ``0.1.0+g<commit>[.dirty]`` when the package runs from a git work tree (an
editable install, the repository itself), else ``0.1.0``: every output file and ``granudep
--version`` then name the commit that made them (``granudep_commit`` attribute). No build-time
tool (setuptools-scm) is needed, so the clean-clone CI and ``pip install -e .`` stay as they are.
"""
from __future__ import annotations

import functools
import subprocess
from pathlib import Path

RELEASE = "0.1.0"


@functools.lru_cache(maxsize=None)
def _git(*args: str) -> str | None:
    here = Path(__file__).resolve().parent
    try:
        out = subprocess.run(["git", "-C", str(here), *args], capture_output=True, text=True, timeout=5)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() if out.returncode == 0 and out.stdout.strip() else None


@functools.lru_cache(maxsize=None)
def commit() -> str | None:
    """The full commit hash of the source tree (``+dirty`` with uncommitted changes), or None."""
    top = _git("rev-parse", "--show-toplevel")
    if top is None or not (Path(top) / "src" / "granudep" / "_version.py").is_file():
        return None  # not our repository (e.g. site-packages inside someone else's checkout)
    sha = _git("rev-parse", "HEAD")
    if sha is None:
        return None
    dirty = _git("status", "--porcelain", "--untracked-files=no")
    return sha + ("+dirty" if dirty else "")


def _version() -> str:
    c = commit()
    if c is None:
        return RELEASE
    sha, _, dirty = c.partition("+")
    return f"{RELEASE}+g{sha[:10]}" + (".dirty" if dirty else "")


__version__ = _version()
