"""Interruption: SIGTERM/SIGINT stop a run cleanly; no signal lands inside a file write.

* :func:`deferred_signals` — around a file write (``io.atomic_path``): SIGINT/SIGTERM are held
  until the write and the rename are done, then delivered. A KeyboardInterrupt raised inside
  netCDF4/HDF5 while xarray holds its file lock hung the process; now the
  write completes (or fails on its own) and the signal acts after it.
* :func:`graceful_stop` — around a run (the ``granudep isph``/``da`` commands): the first
  SIGTERM/SIGINT sets :data:`STOP`; the run's progress hook sees it at the next output time and
  raises :class:`RunInterrupted` (after writing a checkpoint, where there is one); the command then
  writes the partial output and exits with 128 + the signal number and one line. A second signal
  stops at once (KeyboardInterrupt).
"""
from __future__ import annotations

import contextlib
import logging
import os
import signal
import threading

HANDLED = (signal.SIGINT, signal.SIGTERM)


class RunInterrupted(RuntimeError):
    """A run stopped by SIGTERM/SIGINT at an output time; ``signum`` says which."""

    def __init__(self, message: str, signum: int = signal.SIGTERM):
        super().__init__(message)
        self.signum = signum


class _Stop:
    def __init__(self):
        self.signum: int | None = None

    @property
    def requested(self) -> bool:
        return self.signum is not None

    def clear(self) -> None:
        self.signum = None

    def name(self) -> str:
        return signal.Signals(self.signum).name if self.signum else ""


STOP = _Stop()


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@contextlib.contextmanager
def deferred_signals(signals=HANDLED):
    """Hold SIGINT/SIGTERM while the block runs; deliver the first one afterwards."""
    if not _main_thread():
        yield
        return
    pending: list[int] = []
    old = {s: signal.getsignal(s) for s in signals}

    def hold(signum, frame):
        pending.append(signum)

    for s in signals:
        signal.signal(s, hold)
    try:
        yield
    finally:
        for s in signals:
            signal.signal(s, old[s])
        if pending:
            signum = pending[0]
            handler = old[signum]
            if callable(handler):
                handler(signum, None)
            elif handler == signal.SIG_DFL:
                os.kill(os.getpid(), signum)


@contextlib.contextmanager
def graceful_stop(signals=HANDLED):
    """While the block runs, the first SIGTERM/SIGINT requests a stop (STOP); a second interrupts."""
    if not _main_thread():
        yield STOP
        return
    old = {s: signal.getsignal(s) for s in signals}

    def request(signum, frame):
        if STOP.requested:
            raise KeyboardInterrupt
        STOP.signum = signum
        logging.getLogger("granudep").warning("%s received: stopping at the next output time (send it again to stop at once)",
                    signal.Signals(signum).name)

    STOP.clear()
    for s in signals:
        signal.signal(s, request)
    try:
        yield STOP
    finally:
        for s in signals:
            signal.signal(s, old[s])
