"""``granudep monitor`` and ``granudep monitor-wm``: section time series of a 2D ISPH run."""
from __future__ import annotations

import argparse
from pathlib import Path

from ..cliutil import add_run_args, apply_threads, parse_sets
from ..config import ConfigError
from ..io import write_netcdf
from ..progress import LOG


def _common(p) -> None:
    p.add_argument("run", help="2D ISPH run file (results/isph/{case}.nc)")
    p.add_argument("--critical-speed", type=float, default=None, metavar="V",
                   help="|v| below which a particle is deposited, m/s (default 0.1)")
    p.add_argument("--divergence-threshold", type=float, default=None, metavar="T",
                   help="eq 16 threshold on div r over deposited neighbours (default 1.6)")
    p.add_argument("--interface-threshold", type=float, default=None, help=argparse.SUPPRESS)  # old name: refused
    p.add_argument("--x-inf", type=float, default=None, metavar="X",
                   help="final runout x_inf in m from the back wall (default: the run's front named by x_inf_front)")
    p.add_argument("--n-sections", type=int, default=None, metavar="N", help="number of sections (default 11)")
    add_run_args(p, "bed_mirror=false")


def _overrides(args) -> dict:
    if args.interface_threshold is not None:
        raise ConfigError("--interface-threshold: renamed to --divergence-threshold (monitor.divergence_threshold; "
                          "one name per quantity across stages)")
    return {"critical_speed": args.critical_speed, "divergence_threshold": args.divergence_threshold,
            "x_inf": args.x_inf, "n_sections": args.n_sections, **parse_sets(args.set)}


def _prepare(args, default_dir: str, overrides: dict):
    """Config, input and output checked before any work; returns (run dataset, output path)."""
    from ..io import check_output, open_dataset
    from .api import _config
    _config(overrides)  # bad keys and ranges first
    run = open_dataset(args.run, what="run")
    out = Path(args.output or f"{default_dir}/{run.attrs.get('case', Path(args.run).stem)}.nc")
    check_output(out)
    apply_threads(args.threads)
    return run, out


def _cmd_monitor(args) -> int:
    from .api import monitor
    over = {"width_factor": args.width_factor, **_overrides(args)}
    run, out = _prepare(args, "results/sections", over)
    ds = monitor(run, **over)
    write_netcdf(ds, out)
    src = ds.interface_source.values
    LOG.info("monitor %s: %d sections x %d times, W_M = %g dx, x_inf = %.4f m; interface from eq 16 in %d, "
             "fallback in %d, empty %d section-times -> %s", ds.attrs["case"], ds.sizes["section"],
             ds.sizes["time"], ds.attrs["width_factor"], ds.attrs["x_inf"], (src == 1).sum(), (src == 2).sum(),
             (src == -1).sum(), out)
    return 0


def _cmd_monitor_wm(args) -> int:
    from .api import monitor_wm
    over = _overrides(args)
    if args.widths:
        over["wm_factors"] = args.widths
    run, out = _prepare(args, "results/wm", over)
    ds = monitor_wm(run, **over)
    write_netcdf(ds, out)
    table = ds.rms_deviation.to_pandas()
    table.columns = [f"{v:.2f}" for v in ds.x_norm.values]
    table.index = [f"W_M={w:g}dx" for w in ds.width_factor.values]
    print(f"RMS deviation of hu/p0 from W_M = {ds.attrs['wm_reference']:g} dx over the deceleration window "
          f"(columns: [x]) -- {ds.attrs['case']}")
    print(table.to_string(float_format=lambda v: f"{v:.4f}"))
    LOG.info("monitor-wm %s -> %s", ds.attrs["case"], out)
    return 0


def register(sub) -> None:
    p = sub.add_parser("monitor", help="monitoring-section time series of a 2D run (eqs 15-17)")
    _common(p)
    p.add_argument("-o", "--output", help="sections NetCDF (default results/sections/{case}.nc)")
    p.add_argument("--width-factor", type=float, default=None, metavar="W",
                   help="section width W_M in units of dx (default 2)")
    p.set_defaults(func=_cmd_monitor)
    p = sub.add_parser("monitor-wm", help="Appendix: hu/p0 for W_M = 1..4 dx and RMS deviation vs 2 dx (Figs A1-A2)")
    _common(p)
    p.add_argument("-o", "--output", help="NetCDF (default results/wm/{case}.nc)")
    p.add_argument("--widths", type=float, nargs="+", default=None, metavar="W",
                   help="section widths in units of dx (default 1 2 3 4; must include 2)")
    p.set_defaults(func=_cmd_monitor_wm)
