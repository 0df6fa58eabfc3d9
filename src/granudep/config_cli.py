"""``granudep config show CASE|YAML``, ``granudep config template STAGE``, ``granudep config write``.

``show`` prints the resolved config of a run (what the stage would use, after the case's geometry,
the YAML and any ``--set``) with each key's unit, allowed range and meaning; ``template`` prints
a complete, commented YAML of a stage's defaults to start a config from; ``write`` writes a config
file from dotted keys (the workflow's per-run configs: user cases, sensitivity runs).
"""
from __future__ import annotations

import dataclasses
import typing
from pathlib import Path

from .config import ConfigError, _range_text, load_yaml, renamed, to_dict

STAGES = ("isph", "da", "monitor", "regress")


def _root(stage: str):
    if stage == "isph":
        from .isph.config import IsphConfig
        return IsphConfig
    if stage == "da":
        from .da.config import DAConfig
        return DAConfig
    if stage == "monitor":
        from .monitor.config import MonitorConfig
        return MonitorConfig
    from .regress.config import RegressConfig
    return RegressConfig


def _resolve(stage: str, source: str | None, overrides: dict):
    from .config import flat_config
    if stage == "isph":
        from .isph.config import load_config
        return load_config(source if source is not None else {"case": "my-run"}, **overrides)
    if stage == "da":
        from .da.config import resolve
        return resolve(source if source is not None else {"case": "my-run", "deposition": {"ab_source": "user",
                                                                                           "A": -0.03, "B": 0.05}},
                       **overrides)
    data = load_yaml(source) if source is not None else {}
    return flat_config(_root(stage), data, overrides, prefix=stage if stage == "monitor" else "regress")


def guess_stage(source: str) -> str:
    """The stage a case name or YAML belongs to."""
    from .cases import table5
    from .isph.config import case_names
    if source in case_names():
        return "isph"
    if source in set(table5().case_id):
        return "da"
    if source.endswith((".yaml", ".yml")) or Path(source).is_file():
        data = load_yaml(source)
        keys = set(data)
        if keys & {"rheology", "wall"}:
            return "isph"
        if keys & {"deposition"} or "n_particles" in (data.get("numerics") or {}):
            return "da"
        for stage in ("monitor", "regress"):  # an old key name counts: the stage's build then names the new one
            cls = _root(stage)
            if keys & ({f.name for f in dataclasses.fields(cls)} | set(renamed(cls))):
                return stage
        raise ConfigError(f"{source}: cannot tell the stage from its keys; give --stage isph|da|monitor|regress")
    raise ConfigError(f"case: unknown case {source!r} (a Table 1/5 case name or a YAML file; `granudep cases`)")


def _lines(obj, cls, prefix: str = "", indent: int = 0, commented: bool = False) -> list[str]:
    out = []
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        value = getattr(obj, f.name)
        pad = "  " * indent
        tp = hints[f.name]
        if dataclasses.is_dataclass(tp) or dataclasses.is_dataclass(value):
            out.append(f"{pad}{f.name}:")
            out += _lines(value, type(value), f"{prefix}{f.name}.", indent + 1, commented)
            continue
        meta = f.metadata or {}
        bits = []
        if meta.get("unit"):
            bits.append(f"[{meta['unit']}]")
        rng = _range_text(meta)
        if rng:
            bits.append(rng)
        choices = meta.get("choices") or (typing.get_args(tp) if typing.get_origin(tp) is typing.Literal else None)
        if choices:
            bits.append("one of " + ", ".join(map(str, choices)))
        if meta.get("doc"):
            bits.append(str(meta["doc"]))
        if meta.get("was"):
            bits.append(f"formerly {meta['was']}")
        import yaml
        text = yaml.safe_dump({f.name: to_dict(value)}, default_flow_style=True, width=10_000).strip()[1:-1]
        out.append(f"{pad}{text}" + (f"    # {'; '.join(bits)}" if bits else ""))
    return out


def _cmd_show(args) -> int:
    from .cliutil import parse_sets
    stage = args.stage or guess_stage(args.source)
    cfg = _resolve(stage, args.source, parse_sets(args.set))
    print(f"# granudep {stage} config, resolved from {args.source} (keys, values, [unit], allowed range, meaning)")
    print("\n".join(_lines(cfg, type(cfg))))
    return 0


def _cmd_template(args) -> int:
    cfg = _resolve(args.stage, None, {})
    head = {"isph": "# granudep isph CONFIG.yaml  (delete what you keep at its default; units in [..])",
            "da": "# granudep da CONFIG.yaml  (deposition: ab_source user needs A and B; 'computed' a coefficients.csv)",
            "monitor": "# monitoring settings (granudep monitor RUN.nc --set KEY=VALUE, or the keys of this file)",
            "regress": "# regression settings (granudep regress ... --set KEY=VALUE)"}[args.stage]
    print(head)
    print("\n".join(_lines(cfg, type(cfg))))
    return 0


def _cmd_write(args) -> int:
    from .cliutil import parse_sets
    from .config import merge
    from .io import check_output, write_text
    import yaml
    check_output(args.output, suffixes=(".yaml", ".yml"))
    data: dict = {}
    for key, value in parse_sets(args.set).items():
        for part in reversed(key.split(".")):
            value = {part: value}
        data = merge(data, value)
    if not data:
        raise ConfigError("config write: give at least one --set KEY=VALUE")
    write_text(yaml.safe_dump(data, sort_keys=False), args.output)
    print(args.output)
    return 0


def register(sub) -> None:
    p = sub.add_parser("config", help="show a resolved config with units and ranges, or print a template")
    csub = p.add_subparsers(dest="config_command", metavar="show|template|write", required=True)
    s = csub.add_parser("show", help="the resolved config of a case or YAML, with units, ranges and meanings")
    s.add_argument("source", metavar="CASE|CONFIG.yaml")
    s.add_argument("--stage", choices=STAGES, help="the stage (default: from the case name or the YAML's keys)")
    s.add_argument("--set", dest="set", action="append", default=[], metavar="KEY=VALUE",
                   help="override one key as the run commands do (repeatable)")
    s.set_defaults(func=_cmd_show)
    t = csub.add_parser("template", help="a complete commented YAML of a stage's defaults")
    t.add_argument("stage", choices=STAGES)
    t.set_defaults(func=_cmd_template)
    w = csub.add_parser("write", help="write a config YAML from dotted keys (checked by the stage when it runs)")
    w.add_argument("-o", "--output", required=True, metavar="CONFIG.yaml")
    w.add_argument("--set", dest="set", action="append", default=[], metavar="KEY=VALUE",
                   help="one key, dotted for a section (geometry.L0=0.2), YAML value (repeatable; in order)")
    w.set_defaults(func=_cmd_write)
