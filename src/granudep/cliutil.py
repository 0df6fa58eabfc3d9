"""Options every run command shares: ``--set KEY=VALUE``, ``--threads N``."""
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


def failed_path(out) -> "os.PathLike":
    """Where a run that failed (an ISPH blow-up, a DA particle leaving the domain) writes the outputs it
    has until the failure: NAME.failed.nc, never the final name (a workflow would take it for a result;
    Snakemake deletes a failed job's declared outputs anyway)."""
    from pathlib import Path
    out = Path(out)
    return out.with_name(out.stem + ".failed.nc")


def add_checkpoint_args(p) -> None:
    """``--checkpoint FILE``, ``--checkpoint-every S``, ``--restart CHECKPOINT|auto`` (the DA and ISPH runs)."""
    p.add_argument("--checkpoint", metavar="FILE", help="checkpoint file (default OUT folder/.{OUT stem}.ckpt)")
    p.add_argument("--checkpoint-every", type=float, default=600.0, metavar="S",
                   help="wall seconds between checkpoints (default 600; SIGTERM/SIGINT always write one)")
    p.add_argument("--restart", metavar="CHECKPOINT|auto",
                   help="continue an interrupted run from its checkpoint (bit-identical); 'auto': the default "
                        "checkpoint if it exists and matches the inputs")


def checkpoint_path(args, out) -> "os.PathLike":
    """--checkpoint, or the default next to the output: OUT folder/.{OUT stem}.ckpt."""
    from pathlib import Path
    out = Path(out)
    return Path(args.checkpoint) if args.checkpoint else out.with_name(f".{out.stem}.ckpt")


def restart_file(args, ckpt, check) -> "os.PathLike | None":
    """--restart FILE, or --restart auto: the default checkpoint when it exists and ``check(ckpt)``
    (which raises ConfigError for a checkpoint of another run) accepts it."""
    from pathlib import Path
    from .progress import LOG
    if args.restart is None:
        return None
    if args.restart != "auto":
        return Path(args.restart)
    ckpt = Path(ckpt)
    if not ckpt.is_file():
        return None
    try:
        check(ckpt)
    except ConfigError as exc:
        LOG.warning("not restarting: %s; starting afresh", exc)
        return None
    return ckpt
