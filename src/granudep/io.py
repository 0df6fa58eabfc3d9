"""NetCDF output shared by every stage: CF attributes, provenance, atomic writes.

Contract (``docs/data-contract.md``): every file has ``Conventions = "CF-1.10"``, ``units`` and
``long_name`` on every variable, and global attributes ``case``, ``granudep_version``, ``config``
(the full resolved config as YAML text) and ``history``. Files are written to a temporary name in
the destination folder and renamed into place, so nothing half-written ever carries a final name.
"""
from __future__ import annotations

import datetime as _dt
import os
import sys
import tempfile
from pathlib import Path
from typing import Callable

import numpy as np
import xarray as xr

from ._version import __version__, commit
from .signals import deferred_signals
from .config import ConfigError
import time


class ContractError(ValueError):
    """A dataset about to be written misses a CF attribute required by the data contract."""


def provenance(ds: xr.Dataset, *, case: str, config_yaml: str, command: str | None = None,
               title: str | None = None) -> xr.Dataset:
    """Set the global attributes the data contract requires (in place; returns ``ds``)."""
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    cmd = command if command is not None else " ".join(Path(sys.argv[0]).name.split() + sys.argv[1:])
    ds.attrs["Conventions"] = "CF-1.10"
    if title is not None or "title" not in ds.attrs:
        ds.attrs["title"] = title or f"granudep output, case {case}"
    ds.attrs["case"] = case
    ds.attrs["granudep_version"] = __version__
    ds.attrs["granudep_commit"] = commit() or "unknown"
    ds.attrs["config"] = config_yaml
    prev = ds.attrs.get("history", "")
    ds.attrs["history"] = (f"{prev}\n" if prev else "") + f"{now}: granudep {__version__}: {cmd}"
    return ds


def check_contract(ds: xr.Dataset) -> None:
    """Raise ContractError if a variable lacks ``units``/``long_name`` or a global attr is missing."""
    missing = [a for a in ("Conventions", "case", "granudep_version", "config", "history") if a not in ds.attrs]
    if missing:
        raise ContractError(f"dataset lacks global attribute(s) {missing}")
    for name, var in {**ds.coords, **ds.data_vars}.items():
        for att in ("units", "long_name"):
            if att not in var.attrs:
                raise ContractError(f"variable {name!r} lacks the {att!r} attribute")


#: CF-1.10 needs "<unit> since <epoch>" on a time coordinate (sections 4.4, 3.1). Our times are
#: seconds since release, so the epoch is arbitrary; readers open the files with
#: :func:`open_dataset` (``granudep.load``), which keeps them as plain seconds (decode_times=False).
CF_TIME_UNITS = "seconds since 1970-01-01 00:00:00"


#: the per-particle and per-cell records the stages build as (time, particle) and (time, x_grid);
#: the files store them as (particle, time) and (x_grid, time) (CF 2.4) and open_dataset turns them back
TIME_MAJOR = ("particle", "x_grid")


def _time_major(ds: xr.Dataset) -> xr.Dataset:
    for name in list(ds.data_vars):
        v = ds[name]
        if v.ndim == 2 and v.dims[1] == "time" and v.dims[0] in TIME_MAJOR:
            ds[name] = v.transpose("time", v.dims[0])
    return ds


def _cf_dataset(ds: xr.Dataset) -> xr.Dataset:
    """The dataset as written: CF time units on ``time`` (from ``s``), in a copy; ``ds`` is unchanged."""
    out = ds.copy(deep=False)
    for name in list(out.variables):
        v = out.variables[name]
        if name == "time" and v.attrs.get("units") == "s":
            attrs = {**v.attrs, "units": CF_TIME_UNITS, "standard_name": "time", "calendar": "standard",
                     "axis": "T", "comment": "model time: t = 0 s at release; the epoch of the units is arbitrary "
                                            "(open with granudep.load or xarray decode_times=False)"}
            new = xr.Variable(v.dims, v.data, attrs=attrs)
            out = out.assign_coords({name: new}) if name in out.coords else out.assign({name: new})
    for name in list(out.data_vars):  # CF 2.4: other dimensions to the left of T
        v = out[name]
        if v.ndim == 2 and v.dims[0] == "time" and v.dims[1] in TIME_MAJOR:
            out[name] = v.transpose(v.dims[1], "time")
    lower: dict[str, str] = {}
    for name in out.variables:
        other = lower.setdefault(str(name).lower(), str(name))
        if other != name:
            raise ContractError(f"variables {other!r} and {name!r} differ only by case (CF 2.3: names are "
                                f"not case sensitive)")
    return out


def _encoding(ds: xr.Dataset) -> dict:
    enc = {}
    for name in ds.coords:
        enc[name] = {"_FillValue": None}
    for name, v in ds.variables.items():
        if v.dtype.kind in "UO" and v.ndim >= 1:  # strings as CF character arrays, not NC_STRING
            enc.setdefault(name, {})["dtype"] = "S1"
    for name, var in ds.data_vars.items():
        if var.dtype.kind in "fiu" and var.ndim >= 1:
            enc[name] = {"zlib": True, "complevel": 4}
        if var.dtype.kind == "f":
            enc.setdefault(name, {})["_FillValue"] = None if var.ndim == 0 else np.nan
    return enc


def atomic_path(path: str | Path, write: Callable[[Path], None]) -> Path:
    """Call ``write(tmp)`` on a temporary file next to ``path``, then rename it into place.

    The temporary file is removed if ``write`` raises, so a failure never leaves a file under the
    final name (nor stray temporaries).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    clean_stale_temporaries(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    tmp = Path(tmp)
    try:
        with deferred_signals():  # no KeyboardInterrupt inside netCDF4/HDF5 (it hung on xarray's lock)
            write(tmp)
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; give the usual permissions
            os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def check_output(path: str | Path, suffixes: tuple[str, ...] | None = (".nc",), what: str = "output") -> Path:
    """Refuse an output path before any work: wrong suffix, or a folder that cannot be written.

    Creates the folder (as the write would) and a temporary file in it, removed at once. Raises a
    one-line ConfigError such as ``output: cannot write to results/isph (Read-only file system)``.
    """
    path = Path(path)
    if suffixes and path.suffix.lower() not in suffixes:
        raise ConfigError(f"{what}: {path} must end in {' or '.join(suffixes)} (the file is "
                          f"{'NetCDF' if suffixes == ('.nc',) else suffixes[0]}; got {path.suffix or 'no suffix'!r})")
    if path.is_dir():
        raise ConfigError(f"{what}: {path} is a folder; give a file name")
    folder = path.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".probe", dir=folder)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise ConfigError(f"{what}: cannot write to {folder}/ ({exc.strerror or exc})") from None
    return path


def check_output_dir(folder: str | Path, what: str = "output") -> Path:
    """Like :func:`check_output` for an output folder."""
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        from .config import ConfigError
        raise ConfigError(f"{what}: {folder} exists and is not a folder")
    check_output(folder / "probe", suffixes=None, what=what)
    return folder


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def clean_stale_temporaries(path: str | Path, min_age_s: float = 3600.0) -> list[Path]:
    """Remove the ``.NAME.PID.XXXX.tmp`` files that killed writers (SIGKILL, power loss) left next
    to ``path``: those whose writer process PID is gone (and, without a PID, older than
    ``min_age_s``). A writer running now keeps its file. Returns the removed paths.
    """
    path = Path(path)
    removed: list[Path] = []
    if not path.parent.is_dir():
        return removed
    now = time.time()
    for tmp in path.parent.glob(f".{path.name}.*.tmp"):
        token = tmp.name[len(path.name) + 2:].split(".", 1)[0]
        try:
            stale = (not _pid_alive(int(token))) if token.isdigit() and "." in tmp.name[len(path.name) + 2:-4] \
                else now - tmp.stat().st_mtime >= min_age_s
            if stale:
                tmp.unlink()
                removed.append(tmp)
        except OSError:
            pass
    return removed


def write_netcdf(ds: xr.Dataset, path: str | Path) -> Path:
    """Write ``ds`` to NetCDF atomically after checking the CF/provenance contract."""
    check_contract(ds)
    ds = _cf_dataset(ds)
    enc = _encoding(ds)
    return atomic_path(path, lambda tmp: ds.to_netcdf(tmp, engine="netcdf4", encoding=enc))


def write_text(text: str, path: str | Path) -> Path:
    """Write a text file (CSV, Markdown, YAML) atomically."""
    return atomic_path(path, lambda tmp: tmp.write_text(text))


def save_figure(fig, path: str | Path, **kwargs) -> Path:
    """Save a matplotlib figure atomically (PNG by default)."""
    path = Path(path)
    fmt = path.suffix.lstrip(".") or "png"
    kwargs.setdefault("dpi", 150)
    kwargs.setdefault("bbox_inches", "tight")
    return atomic_path(path, lambda tmp: fig.savefig(tmp, format=fmt, **kwargs))


def open_dataset(path: str | Path, what: str = "input", load: bool = True) -> xr.Dataset:
    """Open a granudep NetCDF file fully into memory (the file is closed on return).

    Times stay seconds since release (``decode_times=False``; the files carry CF time units) and
    the particle and grid records are (time, particle) and (time, x_grid), as the stages build
    them (the files store time last, as CF 2.4 recommends). ``load=False``: lazily, for attributes and a few variables
    (use it as a context manager). A missing, empty, truncated or non-NetCDF file raises a
    one-line ConfigError naming it.
    """
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"{what}: file not found: {path}")
    size = path.stat().st_size
    if size == 0:
        raise ConfigError(f"{what}: {path} is empty (0 bytes; an interrupted copy or write?)")
    with open(path, "rb") as fh:
        magic = fh.read(8)
    if not (magic.startswith(b"CDF") or magic.startswith(b"\x89HDF\r\n\x1a\n")):
        raise ConfigError(f"{what}: {path} is not a NetCDF file (starts with {magic[:8]!r})")
    try:
        if not load:
            return _time_major(xr.open_dataset(path, decode_times=False))
        with xr.open_dataset(path, decode_times=False) as ds:
            return _time_major(ds.load())
    except (OSError, ValueError, RuntimeError, KeyError, IndexError) as exc:
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise ConfigError(f"{what}: cannot read {path} as NetCDF ({size} bytes; truncated or damaged? "
                          f"{reason[:200]})") from None


def var(data, dims, units: str, long_name: str, **attrs) -> xr.Variable:
    """Shorthand for an xarray variable carrying the attributes the contract requires."""
    return xr.Variable(dims, np.asarray(data), attrs={"units": units, "long_name": long_name, **attrs})
