"""Checkpoint/restart of DA runs.

A DA run with deposition is several simulations (the no-deposition run for x∞, then one per x∞
iterate). :class:`Checkpointer` keeps every finished simulation's record and the state of the
running one (particles, deposit grid, record so far, time, step and output counters) and writes
them to one pickle file (:class:`granudep.checkpoint.CheckpointFile`), atomically, at most every ``every_s`` wall seconds and when SIGTERM/SIGINT
asks for a stop. A restart replays the finished simulations from the file and continues the
running one from its last output time: the numba step kernels see exactly the arrays they would
have seen, so the result is bit-identical to an uninterrupted run.

The file holds the resolved config (YAML), the deposition flag and the granudep version; a restart
with anything different is refused (one line), so a checkpoint never continues another run.
"""
from __future__ import annotations

import pickle
from pathlib import Path
from typing import Any, Callable

from ..checkpoint import CheckpointFile
from ..progress import LOG
from ..signals import STOP, RunInterrupted

FORMAT = "granudep-da-checkpoint-1"


class DAInterrupted(RunInterrupted):
    """SIGTERM/SIGINT stopped a DA run at an output time; ``record`` is the running simulation's."""

    def __init__(self, message: str, signum: int, record=None, checkpoint: Path | None = None):
        super().__init__(message, signum)
        self.record = record
        self.checkpoint = checkpoint


class Checkpointer(CheckpointFile):
    def __init__(self, identity: str, path: str | Path | None = None, every_s: float = 600.0,
                 restart: str | Path | None = None, progress=None):
        super().__init__(identity, path, every_s, fmt=FORMAT, what="DA",
                         differs="different config, deposition flag or granudep version")
        self.completed: dict[str, Any] = {}
        self.current: tuple[str, bytes] | None = None
        self.restored = 0
        self.progress = progress
        if restart is not None:
            self.load(restart)

    # --- file ---------------------------------------------------------------------------------------
    def load(self, path: str | Path) -> None:
        data = self.read(path)
        self.completed = data["completed"]
        self.current = data["current"]
        LOG.info("restart from %s: %d finished simulation(s)%s", path, len(self.completed),
                 ", one in progress" if self.current else "")

    def save(self) -> Path | None:
        return self.write(completed=self.completed, current=self.current)

    # --- hooks --------------------------------------------------------------------------------------
    def simulate(self, key: str, run: Callable[[Any], Any]):
        """``run(hook)`` (a ``solver.simulate`` call given ``checkpoint=hook``) once per key."""
        if key in self.completed:
            self.restored += 1
            LOG.info("restart: simulation %s restored from the checkpoint", key.split("|", 1)[0])
            return self.completed[key]
        if self.progress is not None:
            self.progress.reset(key.split("|", 1)[0])
        rec = run(_Bound(self, key))
        self.completed[key] = rec
        self.current = None
        return rec

    def at_output(self, key: str, state_fn: Callable[[], tuple]) -> None:
        if self.progress is not None:
            self.progress.update(state_fn()[5])
        due = self.due()
        if not (due or STOP.requested):
            return
        self.current = (key, pickle.dumps(state_fn(), protocol=pickle.HIGHEST_PROTOCOL))
        written = self.save()
        if STOP.requested:
            state = state_fn()
            raise DAInterrupted(f"DA run stopped by {STOP.name()} at t = {state[5]:.4f} s (step {state[6]})",
                                STOP.signum, record=state[4], checkpoint=written)

    def resume(self, key: str):
        if self.current is not None and self.current[0] == key:
            state = pickle.loads(self.current[1])  # noqa: S301
            self.current = None
            LOG.info("restart: continuing %s from t = %.4f s (step %d)", key.split("|", 1)[0], state[5], state[6])
            return state
        return None


class _Bound:
    """The ``checkpoint`` object ``solver.simulate`` sees for one simulation."""

    def __init__(self, owner: Checkpointer, key: str):
        self.owner, self.key = owner, key

    def resume(self):
        return self.owner.resume(self.key)

    def at_output(self, state_fn) -> None:
        self.owner.at_output(self.key, state_fn)
