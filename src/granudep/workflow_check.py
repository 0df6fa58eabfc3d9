"""One validation for the command line and the workflow.

The Snakefile calls :func:`check_structure` on the merged config before it reads anything from it,
then, once every rule is defined, :func:`check_jobs` with one :class:`Job` per stage run it would
schedule. Each job builds its stage config with the stage's own builder (``isph.config.load_config``,
``da.config.resolve``, ``flat_config(MonitorConfig, ...)``) from the same arguments its shell command
passes to ``granudep``, so ``snakemake -n`` refuses exactly what the jobs would, before any job
runs. The JSON schema (``workflow/schemas/config.schema.yaml``) only checks the workflow's own
structure (sections, lists, names, types); every number with a physical meaning is checked by the
stage validators. Every refusal is one :class:`ConfigError` line naming the config file that sets
the key, the key and the allowed range::

    config/ci.yaml: user_cases[0].theta_deg: isph run 'steep': geometry.theta_deg: must be < material.phi_internal_deg = 25.5 ... (got 30.0)
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence

from .config import ConfigError, flat_config, load_yaml, yaml12_numbers
from .isph.config import load_config
from .da.config import resolve
from .monitor.config import MonitorConfig

Key = tuple  # a path into the config: ("isph", "dx") or ("user_cases", 0, "H0")


def key_text(key: Sequence) -> str:
    """("user_cases", 0, "H0") -> "user_cases[0].H0"."""
    out = ""
    for k in key:
        out += f"[{k}]" if isinstance(k, int) else (f".{k}" if out else str(k))
    return out or "config"


def _show(path) -> str:
    """A path as the user would type it: relative when inside the working folder."""
    p = str(path)
    if os.path.isabs(p):
        rel = os.path.relpath(p)
        return rel if not rel.startswith("..") else p
    return p


class ConfigSources:
    """Which file (or ``--config``) sets a key: the last file, in Snakemake's order, that has it."""

    def __init__(self, files: Iterable[str | Path] = (), cli: Mapping | None = None):
        self.files: list[tuple[str, dict]] = []
        for f in files:
            try:
                self.files.append((_show(f), load_yaml(f)))
            except ConfigError:
                self.files.append((_show(f), {}))
        self.cli = dict(cli or {})

    @staticmethod
    def _has(data: Any, key: Sequence) -> bool:
        for k in key:
            if isinstance(k, int):
                if not isinstance(data, list) or k >= len(data):
                    return False
            elif not isinstance(data, Mapping) or k not in data:
                return False
            data = data[k]
        return True

    def where(self, key: Sequence) -> str:
        key = tuple(key)
        while key:
            if self._has(self.cli, key):
                return "--config"
            for name, data in reversed(self.files):
                if self._has(data, key):
                    return name
            key = key[:-1]
        return self.files[-1][0] if self.files else "config"


def snakemake_sources(workflow) -> ConfigSources:
    """The config files of a running Snakemake workflow, lowest priority first."""
    over = [str(p) for p in (getattr(workflow, "overwrite_configfiles", None) or [])]
    every = [str(p) for p in (getattr(workflow, "configfiles", None) or [])]
    base = [p for p in every if p not in over]
    cli = getattr(getattr(workflow, "config_settings", None), "config", None) or {}
    return ConfigSources(base + over, cli)


# --- structure (JSON schema) ---------------------------------------------------------------------
def _schema_message(err) -> tuple[Key, str]:
    key = tuple(err.absolute_path)
    v, inst, sch = err.validator, err.instance, err.schema
    if v == "additionalProperties" and isinstance(inst, Mapping):
        allowed = sorted(sch.get("properties", {}))
        extra = sorted(k for k in inst if k not in allowed)
        return key + (extra[0],), f"unknown key (allowed: {', '.join(allowed)})"
    if v == "required":
        missing = [k for k in err.validator_value if k not in inst]
        return key + (missing[0],), "required key is missing"
    if v == "type":
        want = err.validator_value
        want = " or ".join(want) if isinstance(want, list) else want
        return key, f"must be of type {want} (got {type(inst).__name__} {inst!r})"
    if v in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"):
        op = {"minimum": ">=", "maximum": "<=", "exclusiveMinimum": ">", "exclusiveMaximum": "<"}[v]
        return key, f"must be {op} {err.validator_value} (got {inst!r})"
    if v == "enum":
        return key, f"must be one of {list(err.validator_value)} (got {inst!r})"
    if v == "pattern":
        what = sch.get("description") or f"a string matching {err.validator_value}"
        return key, f"must be {what} (got {inst!r})"
    if v == "not" and key and key[-1] == "name":
        return key, f"{inst!r} is a paper case name; give your case its own name"
    if v == "uniqueItems":
        dup = next((x for i, x in enumerate(inst) if x in inst[:i]), None)
        return key, f"lists {dup!r} more than once"
    if v == "minItems":
        return key, f"must list at least {err.validator_value} item(s) (got {len(inst)})"
    msg = " ".join(str(err.message).split())
    return key, msg if len(msg) < 160 else msg[:157] + "..."


def _non_finite(data: Any, key: Key = ()) -> Key | None:
    if isinstance(data, float) and not math.isfinite(data):
        return key
    if isinstance(data, Mapping):
        items = data.items()
    elif isinstance(data, list):
        items = enumerate(data)
    else:
        return None
    for k, v in items:
        bad = _non_finite(v, key + (k,))
        if bad is not None:
            return bad
    return None


def _get(data: Any, key: Sequence) -> Any:
    for k in key:
        data = data[k]
    return data


def check_structure(config: dict, schema_path: str | Path, sources: ConfigSources) -> dict:
    """YAML 1.2 numbers, the workflow schema, finite numbers, unique user cases, reference tables.

    Converts (in place) the strings Snakemake's YAML 1.1 reader left for ``5.0e4``/``1e-3`` and
    returns ``config``; raises a one-line ConfigError on the first problem.
    """
    import jsonschema

    config.update(yaml12_numbers(dict(config)))
    schema = load_yaml(schema_path)
    validator = jsonschema.Draft202012Validator(schema)
    err = jsonschema.exceptions.best_match(validator.iter_errors(config))
    if err is not None:
        key, msg = _schema_message(err)
        raise ConfigError(f"{sources.where(key)}: {key_text(key)}: {msg}")
    bad = _non_finite(config)
    if bad is not None:
        raise ConfigError(f"{sources.where(bad)}: {key_text(bad)}: must be a finite number (got {_get(config, bad)!r})")
    names = [c["name"] for c in config.get("user_cases", [])]
    for i, n in enumerate(names):
        if n in names[:i]:
            raise ConfigError(f"{sources.where(('user_cases', i, 'name'))}: user_cases[{i}].name: {n!r} is "
                              f"already the name of user_cases[{names.index(n)}] (each case needs its own name)")
    paper = set(config.get("isph", {}).get("cases", [])) | set(config.get("isph", {}).get("table5_geometries", []))
    for i, n in enumerate(names):
        if n in paper:
            raise ConfigError(f"{sources.where(('user_cases', i, 'name'))}: user_cases[{i}].name: {n!r} is a "
                              f"paper case name; give your case its own name")
    for i, p in enumerate(config.get("reference_tables", [])):
        if not Path(p).is_file():
            raise ConfigError(f"{sources.where(('reference_tables', i))}: reference_tables[{i}]: file not found: "
                              f"{p} (paths are relative to the workflow folder {os.getcwd()})")
    da = config.get("da", {})
    missing = [c for c in da.get("cases", []) if c not in da.get("reference_2d", {})]
    if missing:
        raise ConfigError(f"{sources.where(('da', 'reference_2d'))}: da.reference_2d: no 2D reference run for "
                          f"{', '.join(missing)} (map each DA case to the ISPH case of the same geometry, "
                          f"e.g. 1D-A70: T22-A70)")
    return config


# --- every job's stage config -------------------------------------------------------------------------
@dataclass
class Job:
    """One stage run the workflow would schedule: ``build()`` makes its stage config (raising
    ConfigError); ``keys`` maps a stage key prefix (``numerics.dx``, ``geometry``) to the config key
    that sets it; ``key`` is the job's own entry (named when no prefix matches)."""
    label: str
    build: Callable[[], Any]
    key: Key
    keys: dict[str, Key] = field(default_factory=dict)


def _workflow_key(job: Job, message: str) -> Key:
    """The config key behind a stage message ``numerics.dx: ...``; a mapped key ending in ``"*"``
    takes the stage key's last part (``geometry.H0`` -> ``user_cases[0].H0``)."""
    stage_key = message.split(":", 1)[0].strip()
    best = None
    for prefix, wkey in job.keys.items():
        if stage_key == prefix or stage_key.startswith(prefix + "."):
            if best is None or len(prefix) > len(best[0]):
                best = (prefix, wkey)
    if best is None:
        return job.key
    wkey = tuple(best[1])
    if wkey and wkey[-1] == "*":
        wkey = wkey[:-1] + (stage_key.rsplit(".", 1)[-1],)
    return wkey


def check_jobs(jobs: Iterable[Job], sources: ConfigSources) -> int:
    """Build every job's stage config; the first refusal as one ConfigError line. Returns the count."""
    n = 0
    for job in jobs:
        try:
            job.build()
        except ConfigError as exc:
            msg = " ".join(str(exc).split())
            wkey = _workflow_key(job, msg)
            raise ConfigError(f"{sources.where(wkey)}: {key_text(wkey)}: {job.label}: {msg}") from None
        n += 1
    return n


# --- builders mirroring the rules' command lines ------------------------------------------------------
def isph_job(label: str, source: Any, key: Key, keys: dict[str, Key], **overrides) -> Job:
    return Job(label, lambda: load_config(source, **overrides), key, keys)


def da_job(label: str, source: Any, key: Key, keys: dict[str, Key], deposition: bool, **overrides) -> Job:
    return Job(label, lambda: resolve(source, deposition=deposition, **overrides), key, keys)


def monitor_job(label: str, key: Key, keys: dict[str, Key], **overrides) -> Job:
    over = {k: (list(v) if isinstance(v, tuple) else v) for k, v in overrides.items()}
    return Job(label, lambda: flat_config(MonitorConfig, overrides=over, prefix="monitor"), key, keys)


def user_case_mapping(entry: Mapping) -> dict:
    """The YAML the rule ``user_case_config`` writes for a user case (what isph/da read)."""
    return {"case": entry["name"], "geometry": {"theta_deg": entry["theta_deg"], "L0": entry["L0"], "H0": entry["H0"]}}
