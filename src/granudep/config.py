"""Configuration as data: typed dataclasses loaded from YAML, validated once at the edge.

Every stage defines its own (frozen) dataclasses and builds them with :func:`build`, which

* refuses unknown keys (naming the full dotted key and the allowed ones),
* checks types (``int`` accepted where ``float`` is declared, nothing else coerced),
* checks ranges declared in field metadata with :func:`param`,
* recurses into nested dataclasses.

Any violation raises :class:`ConfigError` with a one-line message such as::

    geometry.H0: must be > 0 (got -0.1)

so the CLI can print it and exit before any work starts.
"""
from __future__ import annotations

import dataclasses
import math
import re
import types
import typing
from pathlib import Path
from typing import Any, Callable, Mapping

import yaml


class ConfigLoader(yaml.SafeLoader):
    """PyYAML's safe loader reading numbers as YAML 1.2 (core schema) does.

    PyYAML follows YAML 1.1, where a float needs a dot and a signed exponent: ``5.0e4`` and ``1e-3``
    stay strings there and the config was refused ("must be a number (got str '5.0e4')"). This
    loader adds YAML 1.2's float pattern (digits, an optional dot, an exponent with or without sign)
    as an implicit resolver; everything else (safe tags only) is unchanged. A resolver on a private
    subclass needs no new dependency (ruamel.yaml) and never changes PyYAML for other code.
    """


_YAML12_FLOAT = re.compile(r"""^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)
                            |[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$""", re.X)
ConfigLoader.yaml_implicit_resolvers = {k: list(v) for k, v in yaml.SafeLoader.yaml_implicit_resolvers.items()}
ConfigLoader.add_implicit_resolver("tag:yaml.org,2002:float", _YAML12_FLOAT, list("-+0123456789."))


def yaml_load(text: str):
    """Parse YAML text with :class:`ConfigLoader` (safe tags, YAML 1.2 numbers)."""
    return yaml.load(text, Loader=ConfigLoader)  # noqa: S506 -- ConfigLoader is a SafeLoader


def yaml12_numbers(obj: Any) -> Any:
    """Strings a YAML 1.1 parser left unconverted that YAML 1.2 reads as numbers -> floats.

    For configs parsed by someone else's loader (Snakemake's ``configfile``): ``"5.0e4"`` -> 5.0e4.
    """
    if isinstance(obj, dict):
        return {k: yaml12_numbers(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [yaml12_numbers(v) for v in obj]
    if isinstance(obj, str) and _YAML12_FLOAT.match(obj) and re.search(r"[eE]", obj):
        return float(obj)
    return obj


class ConfigError(ValueError):
    """Bad user input: the message names the key and the allowed range."""


def param(default: Any = dataclasses.MISSING, *, ge=None, gt=None, le=None, lt=None,
          choices=None, unit: str | None = None, doc: str = "", was: str | None = None,
          default_factory=dataclasses.MISSING):
    """A dataclass field with validation metadata (range, choices, unit, doc).

    ``was``: the key's old name (one name per quantity across stages); a config that
    still gives it is refused with one line naming the new key (:func:`build`, :func:`overrides_mapping`).
    """
    meta = {"ge": ge, "gt": gt, "le": le, "lt": lt, "choices": choices, "unit": unit, "doc": doc, "was": was}
    if default_factory is not dataclasses.MISSING:
        return dataclasses.field(default_factory=default_factory, metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


def _range_text(meta: Mapping[str, Any]) -> str:
    parts = []
    if meta.get("gt") is not None:
        parts.append(f"> {meta['gt']}")
    if meta.get("ge") is not None:
        parts.append(f">= {meta['ge']}")
    if meta.get("lt") is not None:
        parts.append(f"< {meta['lt']}")
    if meta.get("le") is not None:
        parts.append(f"<= {meta['le']}")
    return " and ".join(parts)


def _check_range(key: str, value: Any, meta: Mapping[str, Any]) -> None:
    if meta.get("choices") is not None and value not in meta["choices"]:
        raise ConfigError(f"{key}: must be one of {list(meta['choices'])} (got {value!r})")
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        if isinstance(value, float) and not math.isfinite(value):
            raise ConfigError(f"{key}: must be a finite number (got {value!r})")
        bad = ((meta.get("gt") is not None and not value > meta["gt"])
               or (meta.get("ge") is not None and not value >= meta["ge"])
               or (meta.get("lt") is not None and not value < meta["lt"])
               or (meta.get("le") is not None and not value <= meta["le"]))
        if bad:
            raise ConfigError(f"{key}: must be {_range_text(meta)} (got {value!r})")


def _type_name(tp: Any) -> str:
    return getattr(tp, "__name__", str(tp))


def _coerce(key: str, value: Any, tp: Any) -> Any:
    """Check ``value`` against annotation ``tp``; return the (possibly converted) value."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = typing.get_args(tp)
        if value is None and type(None) in args:
            return None
        errors = []
        for arg in args:
            if arg is type(None):
                continue
            try:
                return _coerce(key, value, arg)
            except ConfigError as exc:  # try the next alternative
                errors.append(str(exc))
        raise ConfigError(errors[0] if errors else f"{key}: invalid value {value!r}")
    if origin is typing.Literal:
        allowed = typing.get_args(tp)
        if value not in allowed:
            raise ConfigError(f"{key}: must be one of {list(allowed)} (got {value!r})")
        return value
    if origin in (list, tuple):
        if not isinstance(value, (list, tuple)):
            raise ConfigError(f"{key}: must be a list (got {type(value).__name__} {value!r})")
        args = typing.get_args(tp)
        item_tp = args[0] if args else Any
        items = [_coerce(f"{key}[{i}]", v, item_tp) for i, v in enumerate(value)]
        return tuple(items) if origin is tuple else items
    if origin is dict:
        if not isinstance(value, Mapping):
            raise ConfigError(f"{key}: must be a mapping (got {type(value).__name__})")
        return dict(value)
    if dataclasses.is_dataclass(tp):
        if isinstance(value, tp):
            return value
        if not isinstance(value, Mapping):
            raise ConfigError(f"{key}: must be a mapping of {_type_name(tp)} fields (got {value!r})")
        return build(tp, value, prefix=key)
    if tp is Any:
        return value
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigError(f"{key}: must be a number (got {type(value).__name__} {value!r})")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            if isinstance(value, float) and value.is_integer():
                return int(value)
            raise ConfigError(f"{key}: must be an integer (got {type(value).__name__} {value!r})")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{key}: must be true or false (got {value!r})")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(f"{key}: must be a string (got {type(value).__name__} {value!r})")
        return value
    if isinstance(tp, type) and not isinstance(value, tp):
        raise ConfigError(f"{key}: must be of type {_type_name(tp)} (got {value!r})")
    return value


def build(cls: type, data: Mapping[str, Any] | None, prefix: str = ""):
    """Build dataclass ``cls`` from a mapping, validating keys, types and ranges."""
    data = {} if data is None else data
    if not isinstance(data, Mapping):
        raise ConfigError(f"{prefix or 'config'}: must be a mapping (got {data!r})")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    where = f"{prefix}." if prefix else ""
    data = _renamed_keys(cls, data, where)
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise ConfigError(f"{where}{unknown[0]}: unknown key (allowed: {', '.join(sorted(fields))})")
    kwargs = {}
    for name, f in fields.items():
        key = f"{prefix}.{name}" if prefix else name
        if name in data:
            value = _coerce(key, data[name], hints[name])
        elif f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING:
            continue
        else:
            raise ConfigError(f"{key}: required key is missing")
        _check_range(key, value, f.metadata)
        kwargs[name] = value
    obj = cls(**kwargs)
    # validate defaults too (cheap; catches inconsistent defaults early)
    for name, f in fields.items():
        if name not in kwargs:
            _check_range(f"{prefix}.{name}" if prefix else name, getattr(obj, name), f.metadata)
    validate = getattr(obj, "validate", None)
    if callable(validate):
        validate(prefix)
    return obj


def to_dict(obj: Any) -> Any:
    """Dataclass -> plain dict (tuples become lists) suitable for YAML."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: to_dict(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, (list, tuple)):
        return [to_dict(v) for v in obj]
    if isinstance(obj, dict):
        return {k: to_dict(v) for k, v in obj.items()}
    return obj


def to_yaml(obj: Any) -> str:
    """The full resolved config as YAML text (stored in every output's ``config`` attribute)."""
    return yaml.safe_dump(to_dict(obj), sort_keys=False)


def load_yaml(path: str | Path) -> dict:
    """Read a YAML mapping; a clear ConfigError if the file is missing or not a mapping."""
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"{path}: config file not found")
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: not a UTF-8 text file (byte {exc.start}: {exc.reason}); "
                          f"save the YAML as UTF-8") from None
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read ({exc.strerror})") from None
    try:
        data = yaml_load(text)
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: not valid YAML ({' '.join(str(exc).split())})") from None
    if data is None:
        raise ConfigError(f"{path}: the config file is empty (give at least `case:`; "
                          f"see `granudep config template STAGE`)")
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: top level must be a mapping of keys")
    return data


def merge(base: Mapping[str, Any], override: Mapping[str, Any]) -> dict:
    """Recursive dict merge (override wins); used to overlay a user YAML on case defaults."""
    out = dict(base)
    for k, v in override.items():
        if isinstance(v, Mapping) and isinstance(out.get(k), Mapping):
            out[k] = merge(out[k], v)
        else:
            out[k] = v
    return out


# --- one loader and one override rule for every stage -----------------------------------

def renamed(cls: type) -> dict[str, str]:
    """Old key -> new key of ``cls``'s fields (``param(was=...)``)."""
    return {f.metadata["was"]: f.name for f in dataclasses.fields(cls) if f.metadata.get("was")}


def _renamed_keys(cls: type, data: Mapping[str, Any], where: str) -> Mapping[str, Any]:
    old = [k for k in data if k in renamed(cls)]
    if not old:
        return data
    new = renamed(cls)
    raise ConfigError(f"{where}{old[0]}: renamed to {where}{new[old[0]]} (one name per quantity across stages)")


def sections(cls: type) -> dict[str, type]:
    """The fields of a stage config that are sections (nested dataclasses): name -> class."""
    hints = typing.get_type_hints(cls)
    return {f.name: hints[f.name] for f in dataclasses.fields(cls)
            if isinstance(hints[f.name], type) and dataclasses.is_dataclass(hints[f.name])}


def field_index(cls: type) -> dict[str, list[str]]:
    """Bare key -> its dotted keys in a stage config: every section's fields and the top-level keys."""
    idx: dict[str, list[str]] = {}
    secs = sections(cls)
    for f in dataclasses.fields(cls):
        if f.name in secs:
            for g in dataclasses.fields(secs[f.name]):
                idx.setdefault(g.name, []).append(f"{f.name}.{g.name}")
        else:
            idx.setdefault(f.name, []).append(f.name)
    return idx


def dotted_key(cls: type, name: str) -> str | None:
    """The dotted key of a bare key that is unique in ``cls`` (``phi_basal_deg`` -> ``wall.phi_basal_deg``
    in the ISPH config, ``material.phi_basal_deg`` in the DA config); None when it is not a key there."""
    where = field_index(cls).get(name, [])
    return where[0] if len(where) == 1 else None


def _old_names(cls: type) -> dict[str, str]:
    """Old bare and dotted keys of ``cls`` -> the new dotted key."""
    out = {}
    secs = sections(cls)
    for old, new in renamed(cls).items():
        out[old] = new
    for sec, tp in secs.items():
        for old, new in renamed(tp).items():
            out[old] = out[f"{sec}.{old}"] = f"{sec}.{new}"
    return out


def overrides_mapping(cls: type, overrides: Mapping[str, Any], example: str = "") -> dict:
    """Keyword or ``--set`` overrides -> a nested mapping to merge on a stage config, by one rule.

    A key is a section given as a mapping (``numerics={"dx": 0.01}``, merged), a dotted key of any
    depth (``numerics.dx``), or a bare key that is unique in the config (``dx``). ``None`` values are
    skipped (an option not given). An ambiguous, unknown or renamed key is refused in one line.
    """
    idx = field_index(cls)
    secs = sections(cls)
    old = _old_names(cls)
    out: dict = {}
    for key, value in overrides.items():
        if value is None:
            continue
        if key in secs:
            if not isinstance(value, Mapping):
                raise ConfigError(f"{key}: must be a mapping of {key} keys (got {type(value).__name__} {value!r})")
            out = merge(out, {key: dict(value)})
            continue
        if "." in key:
            dotted = key
            if dotted in old:
                raise ConfigError(f"{key}: renamed to {old[key]} (one name per quantity across stages)")
        else:
            where = idx.get(key) or []
            if not where and key in old:
                raise ConfigError(f"{key}: renamed to {old[key].rsplit('.', 1)[-1]} ({old[key]}; one name per "
                                  f"quantity across stages)")
            if not where:
                raise ConfigError(f"{key}: unknown override (allowed: a section {sorted(secs)}, section.key or a "
                                  f"unique key such as {example or ', '.join(sorted(idx)[:3])})")
            if len(where) > 1:
                raise ConfigError(f"{key}: ambiguous override (use one of {', '.join(where)})")
            dotted = where[0]
        node: Any = value
        for part in reversed(dotted.split(".")):
            node = {part: node}
        out = merge(out, node)
    return out


def config_data(cls: type, source: Any, overrides: Mapping[str, Any] | None = None, *,
                paper_case: Callable[[str], Mapping | None], case_mapping: Callable[[str], Mapping],
                on_file: Callable[[dict, Path], dict] | None = None, example: str = "") -> dict:
    """The one loader of a stage config (ISPH, DA): its mapping before :func:`build`.

    ``source`` is a ``cls`` instance, a mapping, a YAML path or a case name. A mapping or YAML naming
    a paper case (``paper_case(name)`` gives its defaults, None when it is not one) inherits the
    case's defaults under its own keys; a bare case name is ``case_mapping(name)`` (which refuses an
    unknown name); a YAML file without ``case`` is named after its stem; ``on_file`` may rewrite a
    file's mapping (the DA anchors a path CSV next to its YAML). Then :func:`overrides_mapping` is
    merged on top: one override rule for every stage (``example``: keys its refusal suggests).
    """
    if isinstance(source, cls):
        data = to_dict(source)
    elif isinstance(source, Mapping):
        data = dict(source)
    elif isinstance(source, (str, Path)) and (str(source).endswith((".yaml", ".yml")) or Path(str(source)).is_file()):
        data = load_yaml(source)
        if on_file is not None:
            data = on_file(data, Path(str(source)))
        data.setdefault("case", Path(str(source)).stem)
    elif isinstance(source, str):
        data = dict(case_mapping(source))
    else:
        raise ConfigError(f"case: must be a case name, YAML path or mapping (got {type(source).__name__} {source!r})")
    if not isinstance(source, cls) and isinstance(data.get("case"), str):
        defaults = paper_case(data["case"])
        if defaults is not None:
            data = merge(defaults, data)
    return merge(data, overrides_mapping(cls, overrides or {}, example))


def flat_config(cls: type, data: Mapping[str, Any] | None = None, overrides: Mapping[str, Any] | None = None, *,
                prefix: str):
    """A stage config without sections (monitor, regress) by the same rule: a YAML mapping plus
    overrides, each key the config's own, bare or dotted with the stage's name (``monitor.width_factor``);
    ``None`` values skipped (an option not given)."""
    over = {k.removeprefix(f"{prefix}."): v for k, v in (overrides or {}).items() if v is not None}
    return build(cls, merge(dict(data or {}), over), prefix=prefix)
