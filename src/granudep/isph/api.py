"""Public API of the 2D ISPH stage: run a case, warm the numba cache."""
from __future__ import annotations

from pathlib import Path
from typing import Any

import xarray as xr

from ..io import write_netcdf
from ..progress import LOG, Progress
from .config import IsphConfig, load_config
from .output import build_dataset
from .solver import IsphBlowUp, run


def run_isph(case_or_config: Any, output: str | Path | None = None, **overrides) -> xr.Dataset:
    """Run a 2D ISPH case (Table 1 name, T22-A30/A45/A124, YAML path, mapping or IsphConfig).

    ``overrides`` name config fields (``dx=0.008``, ``t_end=1.0``, ``wall.slip="no_slip"``). With
    ``output`` the dataset is written there (atomically), also when the run blows up: then the
    snapshots so far are written with ``status = "failed: ..."`` and IsphBlowUp is re-raised.
    Bad input raises ConfigError before any work.
    """
    cfg = load_config(case_or_config, **overrides)
    return run_config(cfg, output=output)


def run_config(cfg: IsphConfig, output: str | Path | None = None) -> xr.Dataset:
    LOG.info("isph %s: theta=%.1f deg, L0=%.3f m, H0=%.3f m, dx=%.4f m, t_end=%.3f s (%.1f t_c), slip=%s",
             cfg.case, cfg.geometry.theta_deg, cfg.geometry.L0, cfg.geometry.H0, cfg.numerics.dx, cfg.t_end,
             cfg.t_end / cfg.t_c, cfg.wall.slip)
    try:
        solver, snaps, status, ttr = run(cfg, progress=Progress(cfg.output.progress_s))
    except IsphBlowUp as exc:
        ds = build_dataset(cfg, exc.solver, exc.snapshots, f"failed: {exc}", float("nan"))
        exc.dataset = ds
        if output is not None:
            write_netcdf(ds, output)
            LOG.error("isph %s failed; partial output (%d snapshots) kept in %s", cfg.case, ds.sizes["time"], output)
        raise
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
    return ds


def warmup() -> None:
    """Compile (and cache) every numba kernel with a few steps of a tiny collapse."""
    cfg = load_config({"case": "warmup", "geometry": {"L0": 0.04, "H0": 0.04, "domain_length": 0.2},
                       "numerics": {"dx": 0.01, "t_end": 0.01}, "output": {"progress_s": 1e9}})
    run(cfg, progress=Progress(1e9))
    for slip in ("no_slip",):
        run(load_config(cfg, **{"wall.slip": slip}), progress=Progress(1e9))
