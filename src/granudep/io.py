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

from ._version import __version__


class ContractError(ValueError):
    """A dataset about to be written misses a CF attribute required by the data contract."""


def provenance(ds: xr.Dataset, *, case: str, config_yaml: str, command: str | None = None) -> xr.Dataset:
    """Set the global attributes the data contract requires (in place; returns ``ds``)."""
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    cmd = command if command is not None else " ".join(Path(sys.argv[0]).name.split() + sys.argv[1:])
    ds.attrs["Conventions"] = "CF-1.10"
    ds.attrs["case"] = case
    ds.attrs["granudep_version"] = __version__
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


def _encoding(ds: xr.Dataset) -> dict:
    enc = {}
    for name in ds.coords:
        enc[name] = {"_FillValue": None}
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
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    tmp = Path(tmp)
    try:
        write(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; give the usual permissions
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def write_netcdf(ds: xr.Dataset, path: str | Path) -> Path:
    """Write ``ds`` to NetCDF atomically after checking the CF/provenance contract."""
    check_contract(ds)
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


def open_dataset(path: str | Path) -> xr.Dataset:
    """Open a granudep NetCDF file fully into memory (the file is closed on return)."""
    with xr.open_dataset(path) as ds:
        return ds.load()


def var(data, dims, units: str, long_name: str, **attrs) -> xr.Variable:
    """Shorthand for an xarray variable carrying the attributes the contract requires."""
    return xr.Variable(dims, np.asarray(data), attrs={"units": units, "long_name": long_name, **attrs})
