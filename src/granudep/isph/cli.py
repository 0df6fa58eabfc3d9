"""CLI: ``granudep isph CASE|CONFIG.yaml`` and ``granudep isph-vtk RUN.nc -o DIR``."""
from __future__ import annotations

from pathlib import Path


def _cmd_isph(args) -> int:
    from .api import run_isph
    from .config import load_config
    from .solver import IsphBlowUp
    cfg = load_config(args.case, dx=args.dx, t_end=args.t_end)
    out = Path(args.output) if args.output else Path("results/isph") / f"{cfg.case}.nc"
    from .api import run_config
    try:
        run_config(cfg, output=out)
    except IsphBlowUp as exc:
        from ..progress import LOG
        LOG.error("%s", exc)
        return 1
    print(out)
    return 0


def _cmd_vtk(args) -> int:
    from .vtk import export_vtk
    pvd = export_vtk(args.run, args.output)
    print(pvd)
    return 0


def register(sub) -> None:
    p = sub.add_parser("isph", help="run a 2D ISPH mu(I) column collapse (Table 1 case, T22-A30/A45/A124 or YAML)")
    p.add_argument("case", help="case name (e.g. T22-A70) or CONFIG.yaml")
    p.add_argument("--dx", type=float, default=None, help="initial particle spacing [m] (default 0.004)")
    p.add_argument("--t-end", type=float, default=None, help="end time [s] (default 30 t_c; stops earlier at rest)")
    p.add_argument("-o", "--output", default=None, help="output NetCDF (default results/isph/{case}.nc)")
    p.set_defaults(func=_cmd_isph)
    p = sub.add_parser("isph-vtk", help="export a 2D ISPH run to ParaView (.vtp per snapshot + .pvd)")
    p.add_argument("run", help="ISPH NetCDF file")
    p.add_argument("-o", "--output", required=True, help="output folder")
    p.set_defaults(func=_cmd_vtk)
