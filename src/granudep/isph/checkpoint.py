"""Checkpoint/restart of ISPH runs (long runs survive interruption).

The state of a run is one :class:`granudep.isph.run.RunState`: the solver (particle arrays in
their current renumbering, ``ids``, the warm-start arrays ``visc_du``/``visc_dv``/``visc_dt``,
``p_wall``/``wall_dry``/``wall_an``, statistics, energy budget, outflow record), the snapshots so
far and the time loop's counters (next output time, rest detection, status). It is pickled after a
step into one file (:class:`granudep.checkpoint.CheckpointFile`: atomic, with the resolved config and
the granudep version), at most every ``every_s`` wall seconds and at the output time where
SIGTERM/SIGINT asked for a stop. A restart unpickles it and steps on: the numba kernels see exactly
the arrays they would have seen, so the result is bit-identical to an uninterrupted run.
"""
from __future__ import annotations

from pathlib import Path

from ..checkpoint import CheckpointFile
from ..progress import LOG
from ..signals import STOP

FORMAT = "granudep-isph-checkpoint-1"


class IsphCheckpointer(CheckpointFile):
    def __init__(self, identity: str, path: str | Path | None = None, every_s: float = 600.0,
                 restart: str | Path | None = None):
        super().__init__(identity, path, every_s, fmt=FORMAT, what="ISPH")
        self.state = None
        self.written: Path | None = None
        if restart is not None:
            self.load(restart)

    def load(self, path: str | Path) -> None:
        self.state = self.read(path)["state"]
        s = self.state.solver
        LOG.info("restart from %s: continuing from t = %.4f s (step %d)", path, s.t, s.step_no)

    # --- hooks of solver.run ------------------------------------------------------------------------
    def resume(self):
        state, self.state = self.state, None
        return state

    def after_step(self, state, at_output: bool) -> None:
        if self.due() or (at_output and STOP.requested):
            self.written = self.write(state=state) or self.written
