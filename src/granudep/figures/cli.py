"""CLI of the figures stage: ``figure NAME`` (one paper figure from the stage outputs) and ``path-figure``
(the profile figure of DA runs on a slope profile)."""
from __future__ import annotations

import argparse

from ..config import ConfigError
from ..progress import LOG


def _cmd_figure(args) -> int:
    from . import FIGURES
    from ..io import save_figure
    spec = FIGURES[args.name]
    args.output = args.output or getattr(args, "output_parent", None)
    if not args.output:
        raise ConfigError(f"figure {args.name}: -o/--output OUT.png is required")
    fig = spec.from_args(args)
    save_figure(fig, args.output)
    LOG.info("figure %s written to %s", args.name, args.output)
    return 0


def _cmd_path_figure(args) -> int:
    from ..io import save_figure
    from .path import path_figure
    if len(args.runs) > 2:
        raise ConfigError("path-figure: give one or two DA path runs (NetCDF)")
    save_figure(path_figure(args.runs, args.exaggeration), args.output)
    LOG.info("path figure written to %s", args.output)
    return 0


def register(sub) -> None:
    try:
        from . import FIGURES
    except ImportError:  # figure modules not importable (matplotlib missing): keep the other commands usable
        FIGURES = {}
    p = sub.add_parser("figure", help="draw one of the paper's figures from the stage outputs")
    p.add_argument("-o", "--output", dest="output_parent", metavar="OUT.png", help=argparse.SUPPRESS)
    fsub = p.add_subparsers(dest="name", metavar="NAME", required=True)
    for name, spec in FIGURES.items():
        fp = fsub.add_parser(name, help=spec.help, description=spec.help)
        fp.add_argument("-o", "--output", metavar="OUT.png", help="figure file (.png, .pdf, .svg)")
        spec.add_arguments(fp)
        fp.set_defaults(func=_cmd_figure)
    q = sub.add_parser(
        "path-figure", help="figure of DA runs on a path profile: bed, release, final deposit, travel angle, envelopes",
        description="Profile figure of one or two `granudep da` runs with geometry.path (with/without deposition).")
    q.add_argument("runs", nargs="+", metavar="RUN.nc", help="DA path runs of the same case")
    q.add_argument("-o", "--output", required=True, metavar="OUT.png")
    q.add_argument("--exaggeration", type=float, metavar="X", help="vertical exaggeration of the depths (default: auto)")
    q.set_defaults(func=_cmd_path_figure)


__all__ = ["register", "ConfigError"]
