"""Shared figure helpers: the CLI registry, input loading, layout, notes."""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
import pandas as pd
import xarray as xr
from matplotlib.figure import Figure

from .. import cases
from ..config import ConfigError
from ..io import open_dataset

#: critical speed separating flowing from deposited particles (Section 2.2, m/s)
CRITICAL_SPEED = 0.1


@dataclass(frozen=True)
class FigureSpec:
    name: str
    help: str
    add_arguments: Callable  # (argparse parser) -> None
    from_args: Callable      # (args) -> Figure


REGISTRY: dict[str, FigureSpec] = {}


def register(name: str, help: str, add_arguments: Callable):
    """Decorator: register ``fn(args) -> Figure`` as ``granudep figure NAME``."""
    def deco(fn):
        REGISTRY[name] = FigureSpec(name, help, add_arguments, fn)
        return fn
    return deco


def load(obj) -> xr.Dataset:
    """Dataset from a Dataset or a path (NetCDF); missing file → ConfigError naming it."""
    if isinstance(obj, xr.Dataset):
        return obj
    path = Path(obj)
    if not path.exists():
        raise ConfigError(f"input: file {str(path)!r} does not exist")
    ds = open_dataset(path)
    ds.attrs.setdefault("source_file", path.name)
    return ds


def load_table(obj, required: tuple[str, ...] = (), name: str = "table") -> pd.DataFrame:
    if isinstance(obj, pd.DataFrame):
        df = obj
    else:
        path = Path(obj)
        if path.is_dir():
            raise ConfigError(f"{name}: expected a CSV file, got folder {str(path)!r}")
        if not path.exists():
            raise ConfigError(f"{name}: file {str(path)!r} does not exist")
        df = pd.read_csv(path)
    missing = [c for c in required if c not in df.columns]
    if missing:
        raise ConfigError(f"{name}: missing column(s) {', '.join(missing)}")
    return df


def need(ds: xr.Dataset, names, what: str) -> None:
    """Refuse a dataset lacking variables/attributes the figure needs, naming them."""
    missing = [n for n in names if n not in ds.variables and n not in ds.attrs]
    if missing:
        src = ds.attrs.get("source_file", ds.attrs.get("case", "dataset"))
        raise ConfigError(f"{what}: {src} lacks {', '.join(missing)} (data contract)")


def case_of(ds: xr.Dataset) -> str:
    return str(ds.attrs.get("case", ds.attrs.get("source_file", "?")))


def scales(ds: xr.Dataset) -> dict:
    """t_c, p0, characteristic velocity sqrt(g H0 cos θ) of a run/sections file."""
    H0, th = float(ds.attrs["H0"]), math.radians(float(ds.attrs["theta_deg"]))
    return {"H0": H0, "L0": float(ds.attrs["L0"]), "theta": th, "theta_deg": float(ds.attrs["theta_deg"]),
            "tc": cases.characteristic_time(H0, th), "p0": cases.momentum_scale(H0, th),
            "U": math.sqrt(cases.G * H0 * math.cos(th))}


def new_figure(nrows: int = 1, ncols: int = 1, panel=(5.0, 3.6), **kw):
    fig = Figure(figsize=(panel[0] * ncols, panel[1] * nrows), layout="constrained")
    axes = fig.subplots(nrows, ncols, squeeze=False, **kw)
    return fig, axes


def hide_unused(axes, used: int) -> None:
    for ax in axes.ravel()[used:]:
        ax.set_visible(False)


def panel_label(ax, k: int, text: str = "") -> None:
    ax.set_title(f"({chr(ord('a') + k)}) {text}".strip(), loc="left", fontsize=10)


def note(fig: Figure, text: str) -> None:
    """A footnote under the panels (front definitions, missing data, provenance)."""
    fig.text(0.5, -0.01, text, ha="center", va="top", fontsize=8, color="0.25", wrap=True)


def front_note(threshold) -> str:
    if threshold is None or not np.isfinite(float(threshold)):
        return "front definition not recorded in the file"
    return f"front: first point where depth < {1e3 * float(threshold):.2f} mm, walking down-slope from the main mass"


def colours(n: int, cmap: str = "viridis"):
    from matplotlib import colormaps
    cm = colormaps[cmap]
    return [cm(v) for v in (np.linspace(0.0, 0.9, n) if n > 1 else [0.0])]


def pick_sections(x_norm: np.ndarray, wanted) -> list[int]:
    """Indices of the sections nearest to the requested [x] values (unique, in order)."""
    x_norm = np.asarray(x_norm, float)
    if wanted is None:
        return list(range(x_norm.size))
    out = []
    for w in wanted:
        i = int(np.nanargmin(np.abs(x_norm - w)))
        if i not in out:
            out.append(i)
    return out


def pick_times(time: np.ndarray, wanted) -> list[int]:
    time = np.asarray(time, float)
    return [int(np.argmin(np.abs(time - w))) for w in wanted]


def critical_for(table: pd.DataFrame | None, case: str) -> pd.DataFrame:
    if table is None:
        return pd.DataFrame()
    return table[table["case"].astype(str) == case]


def nearest_row(df: pd.DataFrame, x_norm: float, tol: float = 1e-3):
    if df.empty:
        return None
    d = np.abs(df["x_norm"].to_numpy(float) - x_norm)
    i = int(np.argmin(d))
    return df.iloc[i] if d[i] <= tol else None


# ---- input classification: the workflow passes every input positionally ----------------------------

def kind_of(path) -> str:
    """What a contract file is: isph, da, sections, wm (NetCDF); critical, coefficients, compare,
    reference, sensitivity (CSV). Decided from the content (dims, columns), not the name."""
    p = Path(path)
    if not p.exists():
        raise ConfigError(f"input: file {str(p)!r} does not exist")
    if p.suffix.lower() == ".csv":
        cols = set(pd.read_csv(p, nrows=0).columns)
        if {"t_s_critical", "x_norm"} <= cols:
            return "critical"
        if "runout_rel_error" in cols:  # before A, B: compare tables carry the DA run's A, B
            return "compare"
        if {"A", "B"} <= cols:
            return "coefficients"
        if {"parameter", "value"} <= cols:
            return "sensitivity"
        if {"final_runout_norm", "provenance"} <= cols:
            return "reference"
        return "csv"
    with xr.open_dataset(p, decode_times=False) as ds:
        dims = set(ds.dims)
        if "width_factor" in dims:
            return "wm"
        if "section" in dims:
            return "sections"
        if "x_grid" in dims:
            return "da"
        if "particle" in dims and "y" in ds.variables:
            return "isph"
    return "unknown"


def classify(paths, allowed: tuple[str, ...], what: str) -> dict[str, list[str]]:
    """Group input paths by :func:`kind_of`; refuse kinds the figure cannot use."""
    out: dict[str, list[str]] = {k: [] for k in allowed}
    for p in paths:
        k = kind_of(p)
        if k not in allowed:
            raise ConfigError(f"{what}: input {str(p)!r} is a {k!r} file; this figure reads {', '.join(allowed)}")
        out[k].append(str(p))
    return out


def add_inputs(p, help_text: str) -> None:
    p.add_argument("inputs", nargs="+", metavar="INPUT", help=help_text + " (kind detected from the content)")
