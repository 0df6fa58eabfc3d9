"""``granudep`` command line: one sub-command per stage, each registered by its own subpackage.

Each stage module ``granudep.<stage>.cli`` exposes ``register(subparsers)`` which adds its
sub-parser and sets ``func`` (a callable taking the parsed args and returning an exit code).
Bad input (``ConfigError``) is printed as one clear line and exits with status 2 before any work.
"""
from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

from ._version import __version__
from .config import ConfigError
from .progress import LOG, setup_logging

#: stage modules providing sub-commands, in the paper's order
STAGES = ("granudep.da.cli", "granudep.isph.cli", "granudep.monitor.cli", "granudep.regress.cli",
          "granudep.report.cli", "granudep.figures.cli", "granudep.config_cli", "granudep.calibration")


def _cmd_cases(args) -> int:
    from .cases import list_cases
    import pandas as pd
    with pd.option_context("display.width", 120, "display.max_rows", 100):
        print(list_cases().to_string(index=False))
    return 0


def _cmd_warmup(args) -> int:
    """Compile (and cache) every stage's numba kernels once, before parallel jobs start."""
    import time
    for stage in args.stages or ["da", "isph", "monitor"]:
        t0 = time.perf_counter()
        importlib.import_module(f"granudep.{stage}.api").warmup()
        LOG.info("warm-up %s: %.1f s", stage, time.perf_counter() - t0)
    if args.touch:
        from .io import write_text
        write_text("numba kernels compiled\n", args.touch)
    return 0


def _cmd_verify(args) -> int:
    """Run a stage's analytic verification suite and write the table (CSV) the report reads."""
    from .io import check_output, write_text
    import pandas as pd
    check_output(args.output, suffixes=(".csv",))  # before the suite runs
    module = importlib.import_module(f"granudep.{args.stage}.verification")
    known = list(getattr(module, "CHECKS", {}))
    if args.checks is not None:
        if not known:
            raise ConfigError(f"--checks: the {args.stage} suite runs as a whole (no --checks)")
        bad = [c for c in args.checks.split(",") if c not in known]
        if bad or not args.checks:
            raise ConfigError(f"--checks: must be comma-separated names of {', '.join(known)} (got {args.checks!r})")
    if args.merge:
        missing = [f for f in args.merge if not Path(f).is_file()]
        if missing:
            raise ConfigError(f"--merge: file not found: {missing[0]}")
        table = pd.concat([pd.read_csv(f) for f in args.merge], ignore_index=True)  # in the order given
    else:
        table = module.run_all(quick=args.quick, **({"checks": args.checks.split(",")} if args.checks else {}))
    if hasattr(module, "annotate_table"):  # isph: the chain-dx error beside each checked row
        table = module.annotate_table(table)
    print(table.to_string(index=False))
    write_text(table.to_csv(index=False), args.output)
    from .verification_gate import count, exit_code
    counts = count(table)
    LOG.info("%s: %s", args.output, counts.sentence())
    if counts.failed:
        LOG.warning("%d checked row(s) outside tolerance (%s): see %s%s", counts.failed, ", ".join(counts.failing),
                    args.output, "; --report-only: exit status 0" if args.report_only else "")
    return exit_code(table, report_only=args.report_only)


class _Version(argparse.Action):
    """``--version``: one unwrapped line with the release and the git commit."""

    def __call__(self, parser, namespace, values, option_string=None):
        from ._version import commit
        print(f"granudep {__version__} (commit {commit() or 'unknown: not a git checkout'})")
        parser.exit(0)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="granudep", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action=_Version, nargs=0, help="print the version and the commit, then exit")
    parser.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    p = sub.add_parser("cases", help="list the paper's named cases (Tables 1 and 5)")
    p.set_defaults(func=_cmd_cases)
    p = sub.add_parser("warmup", help="compile and cache the numba kernels (run once before parallel jobs)")
    # no stage named: all three (argparse checks a list default against choices, so the default is
    # filled in by the command)
    p.add_argument("stages", nargs="*", choices=["da", "isph", "monitor"], help="stages (default: all)")
    p.add_argument("--touch", metavar="FILE", help="write this flag file when done (Snakemake target)")
    p.set_defaults(func=_cmd_warmup)
    p = sub.add_parser("verify", help="run a stage's analytic verification suite and write a CSV table")
    p.add_argument("stage", choices=["da", "isph"])
    p.add_argument("-o", "--output", required=True, help="CSV: check, quantity, value, reference, error, tolerance, passed, note")
    p.add_argument("--quick", action="store_true", help="coarser resolutions (CI smoke)")
    p.add_argument("--checks", default=None, metavar="NAME[,NAME]", help="run only these checks (isph: "
                   "hydrostatic, film_flow, navier_film, sliding_block, bagnold, navier_bagnold, decelerating_layer, "
                   "dam_break, dam_break_approximate, collapse_t22a70; the fine-resolution rows: bagnold_fine, "
                   "navier_bagnold_fine, decelerating_layer_fine, dam_break_fine, run only when named)")
    p.add_argument("--merge", nargs="+", default=None, metavar="CSV",
                   help="write the table of these partial tables (--checks runs, concatenated in this order) "
                        "instead of running checks")
    p.add_argument("--report-only", action="store_true",
                   help="write the table and exit 0 even when a checked row fails (default: exit 1 then; "
                        "rows without a finite tolerance are reported and never decide the exit status)")
    p.set_defaults(func=_cmd_verify)
    for name in STAGES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name == name:  # stage not built yet
                continue
            raise
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    setup_logging(args.verbose)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except ConfigError as exc:
        print(f"granudep: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        LOG.error("interrupted")
        return 130
    except BrokenPipeError:  # `granudep config show X | head`: the reader left; nothing to say
        import os
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except OSError as exc:  # a disk or permission problem while writing: one line, not a traceback
        where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
        print(f"granudep: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
