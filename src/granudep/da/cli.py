"""``granudep da``: run a DA case (Table 5 name or YAML) with or without deposition → NetCDF."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..io import write_netcdf
from ..progress import LOG


def _run(args) -> int:
    from .api import DARunError, run_da
    from .config import resolve
    from .output import default_path, summary_line

    overrides = {"n_particles": args.n_particles, "ab_source": args.ab_source, "coefficients": args.coefficients,
                 "x_inf_mode": args.x_inf_mode, "x_inf": args.x_inf,
                 "coefficient_units": args.coefficient_units}
    deposition = not args.no_deposition
    cfg = resolve(args.case, deposition=deposition, **overrides)  # ConfigError before any work
    out = Path(args.output or default_path(cfg, deposition))
    LOG.info("DA %s (%s deposition) -> %s", cfg.case, "with" if deposition else "without", out)
    try:
        ds = run_da(cfg, deposition=deposition)
    except DARunError as exc:
        LOG.error("%s", exc)
        if exc.dataset is not None:
            failed = out.with_name(out.stem + ".failed.nc")
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
    print(f"written {out}")
    sys.stdout.flush()
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "da", help="run the 1D depth-averaged SPH model (Table 5 case or YAML), with or without deposition",
        description="Run the 1D DA SPH model of Sections 2.3-2.4; prints progress and, at the end, the final "
                    "runout dL/L0 (from the gate) and the flow time with the front definition.")
    p.add_argument("case", metavar="CASE|CONFIG.yaml", help="1D-A30, 1D-A45, 1D-A70, 1D-A124 or a YAML config")
    p.add_argument("--no-deposition", action="store_true", help="switch the deposition source term off")
    p.add_argument("-o", "--output", metavar="OUT.nc",
                   help="NetCDF output (default results/da/{case}_{deposition|nodeposition}.nc)")
    p.add_argument("--n-particles", type=int, metavar="N", help="particles in the initial column")
    p.add_argument("--ab-source", choices=["paper", "computed", "user"], help="where A and B of eq 36 come from")
    p.add_argument("--coefficients", metavar="COEFFS.csv", help="coefficients.csv of `granudep regress` (computed)")
    p.add_argument("--coefficient-units", choices=["normalised", "dimensional"],
                   help="read A, B as normalised ((hu)_C = p0 (A[x] + B), eq 36) or dimensional (m2/s)")
    p.add_argument("--x-inf-mode", choices=["self-consistent", "no-deposition", "user"], help="how x_inf in [x] is set")
    p.add_argument("--x-inf", type=float, metavar="X", help="x_inf in m from the back wall (x-inf-mode user)")
    p.set_defaults(func=_run)
