"""Options every run command shares: ``--set KEY=VALUE``, ``--threads N`` (issue 14, users' habits)."""
from __future__ import annotations

import os
from typing import Iterable

from .config import ConfigError, yaml_load


def add_run_args(p, example: str) -> None:
    p.add_argument("--set", dest="set", action="append", default=[], metavar="KEY=VALUE",
                   help=f"override one config key, dotted or unique (repeatable; YAML values), e.g. {example}")
    p.add_argument("--threads", type=int, default=None, metavar="N",
                   help="numba threads (default: NUMBA_NUM_THREADS or every core)")


def parse_sets(items: Iterable[str]) -> dict:
    """``["numerics.dx=0.01", "stop_at_rest=false"]`` -> ``{"numerics.dx": 0.01, "stop_at_rest": False}``."""
    out = {}
    for item in items or ():
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ConfigError(f"--set: expected KEY=VALUE (got {item!r})")
        try:
            value = yaml_load(text) if text.strip() else None
        except Exception:  # noqa: BLE001 -- any YAML error: one line
            raise ConfigError(f"--set {key}: value {text!r} is not valid YAML") from None
        if value is None:
            raise ConfigError(f"--set {key}: give a value (got {text!r})")
        out[key] = value
    return out


def apply_threads(n: int | None) -> None:
    """Set the numba thread count (before any kernel runs); refuses more than numba was started with."""
    if n is None:
        return
    import numba
    limit = numba.config.NUMBA_NUM_THREADS
    if not 1 <= n <= limit:
        raise ConfigError(f"--threads: must be >= 1 and <= {limit} (the NUMBA_NUM_THREADS this process "
                          f"started with; set NUMBA_NUM_THREADS={n} in the environment for more; got {n})")
    numba.set_num_threads(n)
    os.environ["GRANUDEP_THREADS"] = str(n)


def interrupted_path(out) -> "os.PathLike":
    """Where a run stopped by SIGTERM/SIGINT writes its partial output: NAME.interrupted.nc."""
    from pathlib import Path
    out = Path(out)
    return out.with_name(out.stem + ".interrupted.nc")
