"""Progress lines for long runs: plain ``logging`` lines every N seconds (read well in a TTY and
in a Snakemake log alike; no carriage returns)."""
from __future__ import annotations

import logging
import sys
import time

from .signals import STOP

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
    """Emit ``message()`` at most every ``every_s`` wall seconds (and on ``final``).

    The stages call it at every output time; when SIGTERM/SIGINT asked for a stop
    (``signals.STOP``) it calls ``on_stop()`` there, which raises the stage's interruption.
    """

    def __init__(self, every_s: float = 5.0, logger: logging.Logger = LOG, on_stop=None):
        self.every_s = every_s
        self.logger = logger
        self.on_stop = on_stop
        self.t0 = time.perf_counter()
        self._last = -1e30

    def elapsed(self) -> float:
        return time.perf_counter() - self.t0

    def __call__(self, message_fn, final: bool = False) -> None:
        if STOP.requested and self.on_stop is not None and not final:
            self.on_stop()
        now = time.perf_counter()
        if final or now - self._last >= self.every_s:
            self._last = now
            self.logger.info(message_fn() if callable(message_fn) else message_fn)

    def update(self, t: float) -> None:
        """Simulated time reached (a bar moves; plain lines need nothing)."""

    def reset(self, desc: str = "") -> None:
        """A new simulation of the same run starts (a bar starts again)."""

    def close(self) -> None:
        """End of the run."""


def _interactive() -> bool:
    """A terminal on stderr, or a Jupyter kernel."""
    try:
        if sys.stderr.isatty():
            return True
    except (AttributeError, ValueError):
        pass
    ip = sys.modules.get("IPython")
    if ip is not None:
        try:
            shell = ip.get_ipython()
            return shell is not None and shell.__class__.__name__ == "ZMQInteractiveShell"
        except Exception:  # noqa: BLE001
            return False
    return False


class BarProgress(Progress):
    """A tqdm bar over simulated time (terminal/notebook): the periodic lines go to DEBUG."""

    def __init__(self, every_s: float, total: float, on_stop=None, desc: str = ""):
        super().__init__(every_s, on_stop=on_stop)
        from tqdm.auto import tqdm
        self.bar = tqdm(total=float(total), unit="s", unit_scale=False, desc=desc, dynamic_ncols=True,
                        bar_format="{desc} {percentage:3.0f}%|{bar}| t = {n:.3f}/{total:.3f} s [{elapsed}<{remaining}]")

    def __call__(self, message_fn, final: bool = False) -> None:
        if STOP.requested and self.on_stop is not None and not final:
            self.on_stop()
        if final:
            self.logger.info(message_fn() if callable(message_fn) else message_fn)

    def update(self, t: float) -> None:
        t = min(float(t), self.bar.total)
        if t > self.bar.n:
            self.bar.update(t - self.bar.n)

    def reset(self, desc: str = "") -> None:
        self.bar.reset(total=self.bar.total)
        if desc:
            self.bar.set_description_str(desc)

    def close(self) -> None:
        self.bar.close()


class _Silent(Progress):
    def __call__(self, message_fn, final: bool = False) -> None:
        if STOP.requested and self.on_stop is not None and not final:
            self.on_stop()


def make_progress(mode, every_s: float, total: float = 1.0, on_stop=None, desc: str = "") -> Progress:
    """The progress reporter of the Python API's ``progress=`` argument.

    ``None``/``"auto"``: a tqdm bar in a terminal or notebook (when tqdm is installed), plain log
    lines otherwise (Snakemake logs, batch jobs); ``"log"``: plain lines every ``every_s`` wall
    seconds; ``"bar"``: the bar; ``False``/``"off"``: nothing. Log lines go to the ``granudep``
    logger, which gets a stderr handler here if nothing else configured logging.
    """
    if mode in (False, "off", "none"):
        return _Silent(every_s, on_stop=on_stop)
    if mode in (None, True, "auto"):
        mode = "bar" if _interactive() else "log"
    if mode == "bar":
        try:
            return BarProgress(every_s, total, on_stop=on_stop, desc=desc)
        except ImportError:
            mode = "log"
    if mode != "log":
        from .config import ConfigError
        raise ConfigError(f"progress: must be one of 'auto', 'log', 'bar', False (got {mode!r})")
    if not LOG.handlers and not logging.getLogger().handlers:
        setup_logging()
    return Progress(every_s, on_stop=on_stop)
