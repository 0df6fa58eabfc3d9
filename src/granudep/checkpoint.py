"""The checkpoint file shared by the DA and ISPH stages (long runs survive interruption).

:class:`CheckpointFile` is one pickle file holding a run's state, written atomically (temporary
file + rename, :func:`granudep.io.atomic_path`) at most every ``every_s`` wall seconds and when
SIGTERM/SIGINT asks for a stop. It records the run's identity (the resolved config as YAML and the
granudep version, :func:`identity`); a restart from a file of another run, a missing or an
unreadable file is refused with one line naming ``--restart``. The stages keep what the state is:
:mod:`granudep.da.checkpoint` (finished simulations + the running one), :mod:`granudep.isph.run`
(the solver and the time loop's state, :class:`granudep.isph.run.RunState`).
"""
from __future__ import annotations

import pickle
import time
from pathlib import Path
from typing import Any

from ._version import __version__
from .config import ConfigError, to_yaml
from .io import atomic_path
from .progress import LOG


def identity(cfg) -> str:
    """What a checkpoint must match to be continued: the resolved config and the version."""
    return f"granudep {__version__}\n{to_yaml(cfg)}"


class CheckpointFile:
    """One stage's checkpoint file: ``fmt`` names the format, ``what`` the stage ("DA", "ISPH"),
    ``differs`` what another run's identity may differ in (for the refusal line)."""

    def __init__(self, identity: str, path: str | Path | None = None, every_s: float = 600.0, *,
                 fmt: str, what: str, differs: str = "different config or granudep version"):
        if not every_s >= 0:
            raise ConfigError(f"--checkpoint-every: must be >= 0 s (got {every_s!r})")
        self.identity = identity
        self.path = Path(path) if path is not None else None
        self.every_s = float(every_s)
        self.fmt, self.what, self.differs = fmt, what, differs
        self._last = time.perf_counter()

    def read(self, path: str | Path) -> dict[str, Any]:
        """The payload of a checkpoint of this run; ConfigError (one line) otherwise."""
        path = Path(path)
        if not path.is_file():
            raise ConfigError(f"--restart: checkpoint file not found: {path}")
        try:
            with open(path, "rb") as fh:
                data = pickle.load(fh)  # noqa: S301 -- our own file, next to our own outputs
        except Exception as exc:  # noqa: BLE001 -- any unreadable file: one line
            raise ConfigError(f"--restart: {path} is not a readable granudep checkpoint "
                              f"({type(exc).__name__}: {' '.join(str(exc).split())[:120]})") from None
        if not isinstance(data, dict) or data.get("format") != self.fmt:
            raise ConfigError(f"--restart: {path} is not a granudep {self.what} checkpoint")
        if data.get("identity") != self.identity:
            raise ConfigError(f"--restart: {path} was written by another run ({self.differs}); "
                              f"rerun without --restart or with the same inputs")
        return data

    def due(self) -> bool:
        return self.path is not None and time.perf_counter() - self._last >= self.every_s

    def write(self, **payload) -> Path | None:
        if self.path is None:
            return None
        data = {"format": self.fmt, "identity": self.identity, "version": __version__, **payload}
        blob = pickle.dumps(data, protocol=pickle.HIGHEST_PROTOCOL)
        atomic_path(self.path, lambda tmp: tmp.write_bytes(blob))
        self._last = time.perf_counter()
        LOG.debug("checkpoint written: %s", self.path)
        return self.path

    def remove(self) -> None:
        if self.path is not None:
            self.path.unlink(missing_ok=True)
