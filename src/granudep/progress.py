"""Progress lines for long runs: plain ``logging`` lines every N seconds (read well in a TTY and
in a Snakemake log alike; no carriage returns)."""
from __future__ import annotations

import logging
import sys
import time

LOG = logging.getLogger("granudep")


def setup_logging(verbose: bool = False) -> None:
    """Configure the ``granudep`` logger once (CLI entry point)."""
    if LOG.handlers:
        return
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(message)s", "%H:%M:%S"))
    LOG.addHandler(handler)
    LOG.setLevel(logging.DEBUG if verbose else logging.INFO)


class Progress:
    """Emit ``message()`` at most every ``every_s`` wall seconds (and on ``final``)."""

    def __init__(self, every_s: float = 5.0, logger: logging.Logger = LOG):
        self.every_s = every_s
        self.logger = logger
        self.t0 = time.perf_counter()
        self._last = -1e30

    def elapsed(self) -> float:
        return time.perf_counter() - self.t0

    def __call__(self, message_fn, final: bool = False) -> None:
        now = time.perf_counter()
        if final or now - self._last >= self.every_s:
            self._last = now
            self.logger.info(message_fn() if callable(message_fn) else message_fn)
