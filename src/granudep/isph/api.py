"""Public API of the 2D ISPH stage: run a case, warm the numba cache."""
from __future__ import annotations

from pathlib import Path
from typing import Any

import xarray as xr

from ..checkpoint import identity as checkpoint_identity
from ..io import check_output, write_netcdf
from ..progress import LOG, Progress, make_progress
from ..signals import STOP, RunInterrupted
from .checkpoint import IsphCheckpointer
from .config import IsphConfig, load_config
from .output import build_dataset
from .errors import IsphBlowUp
from .run import run


class IsphInterrupted(IsphBlowUp, RunInterrupted):
    """A run stopped by SIGTERM/SIGINT at an output time (the solver attaches its snapshots)."""

    def __init__(self, message: str, signum: int):
        IsphBlowUp.__init__(self, message)
        self.signum = signum
        self.checkpoint = None  # the checkpoint written at the stop (run_config sets it)


def _stop(cfg: IsphConfig):
    def on_stop():
        raise IsphInterrupted(f"isph {cfg.case}: stopped by {STOP.name()}", STOP.signum)
    return on_stop


def run_isph(case_or_config: Any, output: str | Path | None = None, progress: Any = None, checkpoint=None,
             checkpoint_every: float = 600.0, restart=None, **overrides) -> xr.Dataset:
    """Run a 2D ISPH case (Table 1 name, T22-A30/A45/A124, YAML path, mapping or IsphConfig).

    ``overrides`` name config fields (``dx=0.008``, ``t_end=1.0``, ``wall.slip="no_slip"``) or
    whole sections (``numerics={"dx": 0.008}``). With ``output`` the dataset is written there
    (atomically; the path is checked before the run); when the run blows up, the snapshots so far
    go to ``NAME.failed.nc`` beside it (as a failed DA run's do), with ``status = "failed: ..."``,
    and IsphBlowUp is re-raised.
    ``progress``: None/"auto" (a tqdm bar in a terminal or notebook, plain log lines otherwise),
    "log", "bar", False (silent). Bad input raises ConfigError before any work.

    ``checkpoint``: a file the run state is written to every ``checkpoint_every`` wall seconds and
    on SIGTERM/SIGINT (inside :func:`granudep.signals.graceful_stop`); ``restart``: such a file to
    continue from (bit-identical to an uninterrupted run; refused for another config). A stop raises
    :class:`IsphInterrupted` with the partial dataset as ``dataset`` and the file as ``checkpoint``;
    a finished run removes its checkpoint.
    """
    cfg = load_config(case_or_config, **overrides)
    if output is not None:
        check_output(output)
    return run_config(cfg, output=output, progress=progress, checkpoint=checkpoint,
                      checkpoint_every=checkpoint_every, restart=restart)


def run_config(cfg: IsphConfig, output: str | Path | None = None, progress: Any = "log", checkpoint=None,
               checkpoint_every: float = 600.0, restart=None) -> xr.Dataset:
    ckpt = IsphCheckpointer(checkpoint_identity(cfg), checkpoint, checkpoint_every, restart)  # errors before work
    LOG.info("isph %s: theta=%.1f deg, L0=%.3f m, H0=%.3f m, dx=%.4f m, t_end=%.3f s (%.1f t_c), slip=%s",
             cfg.case, cfg.geometry.theta_deg, cfg.geometry.L0, cfg.geometry.H0, cfg.numerics.dx, cfg.t_end,
             cfg.t_end / cfg.t_c, cfg.wall.slip)
    prog = make_progress(progress, cfg.output.progress_every_s, total=cfg.t_end, on_stop=_stop(cfg), desc=f"isph {cfg.case}")
    try:
        solver, snaps, status, ttr = run(cfg, on_snapshot=lambda s, snaps: prog.update(s.t), progress=prog,
                                         checkpoint=ckpt)
    except IsphBlowUp as exc:
        prog.close()
        interrupted = isinstance(exc, IsphInterrupted)
        if interrupted:
            exc.checkpoint = ckpt.written
        ds = build_dataset(cfg, exc.solver, exc.snapshots, f"{'interrupted' if interrupted else 'failed'}: {exc}",
                           float("nan"))
        exc.dataset = ds
        if output is not None:
            from ..cliutil import failed_path, interrupted_path
            path = interrupted_path(output) if interrupted else failed_path(output)  # as the DA: never the final name
            write_netcdf(ds, path)
            exc.output = path
            (LOG.info if interrupted else LOG.error)(  # the CLI's one error line says it for a stop
                "isph %s %s; partial output (%d snapshots) kept in %s", cfg.case,
                "interrupted" if interrupted else "failed", ds.sizes["time"], path)
        raise
    prog.close()
    ds = build_dataset(cfg, solver, snaps, status, ttr)
    if ds.attrs["n_outflow"]:
        LOG.warning("isph %s: %d particle(s) left through the downstream outflow at x = %.3f m between t=%.3f and "
                    "%.3f s (frozen there in the snapshots; see outflow_time)", cfg.case, ds.attrs["n_outflow"],
                    cfg.domain_length, ds.attrs["first_outflow_time"], ds.attrs["last_outflow_time"])
    LOG.info("isph %s: %s at t=%.3f s; time_to_rest=%.3f s (%.2f t_c), front=%.4f m, %d particles, %d steps, "
             "%.2f ms/step", cfg.case, status, solver.t, ttr, ttr / cfg.t_c, float(ds.final_front_position),
             solver.n0, solver.stats.steps, ds.attrs["ms_per_step"])
    if output is not None:
        write_netcdf(ds, output)
    ckpt.remove()  # a finished run (its output written) needs no checkpoint
    return ds


def warmup() -> None:
    """Compile (and cache) every numba kernel with a few steps of a tiny collapse."""
    cfg = load_config({"case": "warmup", "geometry": {"L0": 0.04, "H0": 0.04, "domain_length": 0.2},
                       "numerics": {"dx": 0.01, "t_end": 0.01}, "output": {"progress_every_s": 1e9}})
    run(cfg, progress=Progress(1e9))
    for slip in ("no_slip",):
        run(load_config(cfg, **{"wall.slip": slip}), progress=Progress(1e9))
