"""``granudep da``: run a DA case (Table 5 name or YAML) with or without deposition → NetCDF."""
from __future__ import annotations

import sys
from pathlib import Path

from ..cliutil import (add_checkpoint_args, add_run_args, apply_threads, checkpoint_path, failed_path,
                       interrupted_path, parse_sets, restart_file)
from ..io import write_netcdf
from ..progress import LOG


def _run(args) -> int:
    from ..io import check_output
    from ..signals import graceful_stop
    from .api import DARunError, checkpoint_identity, run_da
    from .checkpoint import DAInterrupted
    from .config import resolve
    from .output import default_path, summary_line

    x_inf_mode = args.x_inf_mode
    if args.x_inf is not None and x_inf_mode is None:
        x_inf_mode = "user"  # --x-inf alone means: use this x_inf
    overrides = {"n_particles": args.n_particles, "ab_source": args.ab_source, "coefficients": args.coefficients,
                 "x_inf_mode": x_inf_mode, "x_inf": args.x_inf, "coefficient_units": args.coefficient_units,
                 **parse_sets(args.set)}
    deposition = not args.no_deposition
    cfg = resolve(args.case, deposition=deposition, **overrides)  # ConfigError before any work
    apply_threads(args.threads)
    if args.convergence:
        return _convergence(args, cfg, deposition)
    out = Path(args.output or default_path(cfg, deposition))
    check_output(out)  # a read-only folder or a non-.nc name costs nothing
    ckpt = checkpoint_path(args, out)
    from .checkpoint import Checkpointer
    restart = restart_file(args, ckpt, lambda f: Checkpointer(checkpoint_identity(cfg), restart=f))
    LOG.info("DA %s (%s deposition) -> %s", cfg.case, "with" if deposition else "without", out)
    try:
        with graceful_stop():
            ds = run_da(cfg, deposition=deposition, progress=args.progress, checkpoint=ckpt,
                        checkpoint_every=args.checkpoint_every, restart=restart)
    except DAInterrupted as exc:
        part = interrupted_path(out)
        if getattr(exc, "dataset", None) is not None:
            write_netcdf(exc.dataset, part)
        LOG.error("%s; partial output %s, checkpoint %s (continue with --restart %s)", exc, part, exc.checkpoint,
                  exc.checkpoint)
        return 128 + int(exc.signum)
    except DARunError as exc:
        LOG.error("%s", exc)
        if exc.dataset is not None:
            failed = failed_path(out)
            write_netcdf(exc.dataset, failed)
            LOG.error("outputs written until the failure: %s", failed)
        return 1
    except RuntimeError as exc:  # x_inf iteration did not converge
        LOG.error("%s", exc)
        return 1
    write_netcdf(ds, out)
    if not ds.attrs["at_rest"]:
        LOG.warning("%s", ds.attrs["status"])
    if deposition:
        print(f"x_inf = {ds.attrs['x_inf']:.4f} m ({ds.attrs['x_inf_mode']}, {ds.attrs['x_inf_iterations']} runs, "
              f"residual {ds.attrs['x_inf_residual']:.2e}); A = {ds.attrs['A']:.5g}, B = {ds.attrs['B']:.5g} "
              f"({ds.attrs['ab_source']}, {ds.attrs['coefficient_units']})")
        if ds.attrs.get("x_inf_warning"):
            LOG.warning("%s", ds.attrs["x_inf_warning"])
            print(f"WARNING: {ds.attrs['x_inf_warning']}")
    print(summary_line(ds))
    if "travel_angle" in ds:  # a path run (geometry.path)
        from .path_run import path_summary_line
        print(path_summary_line(ds))
    print(f"written {out}")
    sys.stdout.flush()
    return 0


def _convergence(args, cfg, deposition) -> int:
    """--convergence: the doubling study N_MIN, 2 N_MIN, … N_MAX of this case; a table on stdout and a CSV."""
    from .convergence import doubling_study, format_table
    out = Path(args.output or f"results/da/{cfg.case}_{'deposition' if deposition else 'nodeposition'}"
                              f"_convergence.csv")
    if out.suffix != ".csv":
        out = out.with_suffix(".csv")
    df = doubling_study(cfg, deposition, args.n_min, args.n_max or max(args.n_min, 4 * cfg.numerics.n_particles))
    print(f"{cfg.case} ({'with' if deposition else 'without'} deposition), earth pressure "
          f"{cfg.numerics.earth_pressure} / switch {cfg.numerics.earth_pressure_switch}: doubling study")
    print(format_table(df))
    out.parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(out, index=False)
    print(f"written {out}")
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "da", help="run the 1D depth-averaged SPH model (Table 5 case or YAML), with or without deposition",
        description="Run the 1D DA SPH model of Sections 2.3-2.4; prints progress and, at the end, the final "
                    "runout dL/L0 (from the gate) with the particle number N it was computed with and the flow "
                    "time with the front definition. A runout is an answer only at an N where it has converged: "
                    "--convergence runs the doubling study that shows from which N it changes < 1 %% per doubling.")
    p.add_argument("case", metavar="CASE|CONFIG.yaml", help="1D-A30, 1D-A45, 1D-A70, 1D-A124 or a YAML config "
                   "(with geometry.path: a run along a slope profile, e.g. config/da/example_path.yaml)")
    p.add_argument("--no-deposition", action="store_true", help="switch the deposition source term off")
    p.add_argument("-o", "--output", metavar="OUT.nc",
                   help="NetCDF output (default results/da/{case}_{deposition|nodeposition}.nc)")
    p.add_argument("--n-particles", type=int, metavar="N", help="particles in the initial column")
    p.add_argument("--ab-source", choices=["paper", "computed", "user"], help="where A and B of eq 36 come from")
    p.add_argument("--coefficients", metavar="COEFFS.csv", help="coefficients.csv of `granudep regress` (computed)")
    p.add_argument("--coefficient-units", choices=["normalised", "dimensional"],
                   help="read A, B as normalised ((hu)_C = p0 (A[x] + B), eq 36) or dimensional (m2/s)")
    p.add_argument("--x-inf-mode", choices=["self-consistent", "no-deposition", "user"], help="how x_inf in [x] is set")
    p.add_argument("--x-inf", type=float, metavar="X",
                   help="x_inf in m from the back wall (implies --x-inf-mode user)")
    p.add_argument("--convergence", action="store_true",
                   help="run the doubling study instead of one run: N = --n-min, 2 N, ... up to --n-max (default 4x "
                        "numerics.n_particles), print runout, change per doubling (converged: < 1 %% from some N "
                        "on), flow time, CPU s and the energy checks (W_min/dE <= 1, rises of E) per N, and write "
                        "them to a CSV (-o, default results/da/{case}_{deposition|nodeposition}_convergence.csv)")
    p.add_argument("--n-min", type=int, default=250, metavar="N", help="first N of --convergence (default 250)")
    p.add_argument("--n-max", type=int, metavar="N", help="last N of --convergence")
    add_checkpoint_args(p)
    p.add_argument("--progress", choices=["auto", "log", "bar", "off"], default="log",
                   help="progress: plain log lines (default), a tqdm bar, auto (bar in a terminal) or off")
    add_run_args(p, "numerics.cfl=0.3")
    p.set_defaults(func=_run)
