"""CLI: ``granudep isph CASE|CONFIG.yaml`` and ``granudep isph-vtk RUN.nc -o DIR``."""
from __future__ import annotations

from pathlib import Path

from ..cliutil import add_checkpoint_args, add_run_args, apply_threads, checkpoint_path, parse_sets, restart_file


def _cmd_isph(args) -> int:
    from ..io import check_output
    from ..progress import LOG
    from ..signals import graceful_stop
    from .api import IsphInterrupted, run_config
    from .config import load_config
    from .errors import IsphBlowUp
    cfg = load_config(args.case, dx=args.dx, t_end=args.t_end, **parse_sets(args.set))
    out = Path(args.output) if args.output else Path("results/isph") / f"{cfg.case}.nc"
    apply_threads(args.threads)
    check_output(out)  # before any work: a read-only folder or a non-.nc name costs nothing
    from ..checkpoint import identity
    from .checkpoint import IsphCheckpointer
    ckpt = checkpoint_path(args, out)
    restart = restart_file(args, ckpt, lambda f: IsphCheckpointer(identity(cfg), restart=f))
    try:
        with graceful_stop():
            run_config(cfg, output=out, progress=args.progress, checkpoint=ckpt,
                       checkpoint_every=args.checkpoint_every, restart=restart)
    except IsphInterrupted as exc:
        LOG.error("%s at t = %.4f s; partial output in %s, checkpoint %s (continue with --restart %s)", exc,
                  exc.solver.t, getattr(exc, "output", "-"), exc.checkpoint, exc.checkpoint)
        return 128 + int(exc.signum)
    except IsphBlowUp as exc:
        LOG.error("%s", exc)
        return 1
    print(out)
    return 0


def _cmd_vtk(args) -> int:
    from ..io import check_output_dir
    from .vtk import export_vtk
    check_output_dir(args.output)
    pvd = export_vtk(args.run, args.output, encoding=args.encoding)
    print(pvd)
    return 0


def register(sub) -> None:
    p = sub.add_parser("isph", help="run a 2D ISPH mu(I) column collapse (Table 1 case, T22-A30/A45/A124 or YAML)")
    p.add_argument("case", help="case name (e.g. T22-A70) or CONFIG.yaml")
    p.add_argument("--dx", type=float, default=None, help="initial particle spacing [m] (default 0.004)")
    p.add_argument("--t-end", type=float, default=None, help="end time [s] (default 30 t_c; stops earlier at rest)")
    p.add_argument("-o", "--output", default=None, help="output NetCDF (.nc; default results/isph/{case}.nc)")
    p.add_argument("--progress", choices=["auto", "log", "bar", "off"], default="log",
                   help="progress: plain log lines (default), a tqdm bar, auto (bar in a terminal) or off")
    add_checkpoint_args(p)
    add_run_args(p, "numerics.cfl=0.1")
    p.set_defaults(func=_cmd_isph)
    p = sub.add_parser("isph-vtk", help="export a 2D ISPH run to ParaView (.vtp per snapshot + .pvd)")
    p.add_argument("run", help="ISPH NetCDF file")
    p.add_argument("-o", "--output", required=True, help="output folder")
    p.add_argument("--encoding", choices=["binary", "ascii"], default="binary",
                   help="VTK data arrays: base64 binary (default; ~6x smaller) or ASCII")
    p.set_defaults(func=_cmd_vtk)
