"""Markdown pieces of the report: number formatting, tables, "not available" lines, CSV and NetCDF readers."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
from ..io import open_dataset


def fmt(v, spec: str = ".3g") -> str:
    if v is None:
        return "–"
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    try:
        f = float(v)
    except (TypeError, ValueError):
        s = str(v)
        return s.replace("|", "\\|").replace("\n", " ") if s and s != "nan" else "–"
    return "–" if not math.isfinite(f) else format(f, spec)


def md_table(df: pd.DataFrame, columns: dict[str, tuple[str, str]]) -> str:
    """Markdown table of ``df``: columns = {column: (header, format spec)}; absent columns skipped."""
    cols = [(c, h, f) for c, (h, f) in columns.items() if c in df.columns]
    lines = ["| " + " | ".join(h for _, h, _ in cols) + " |", "|" + "|".join("---" for _ in cols) + "|"]
    for _, row in df.iterrows():
        lines.append("| " + " | ".join(fmt(row[c], f) for c, _, f in cols) + " |")
    return "\n".join(lines)


def not_available(what: str, path) -> str:
    return f"_Not available: {what} ({'not given' if path is None else f'{path} not found'})._\n"


def read_csv(path) -> pd.DataFrame | None:
    if path is None or not Path(path).is_file():
        return None
    return pd.read_csv(path)


def pct_mean(s: pd.Series) -> str:
    s = pd.to_numeric(s, errors="coerce").abs()
    s = s[np.isfinite(s)]
    return f"{s.mean():.1f} %" if len(s) else "–"


def open_lazily(path):
    """A run or sections file, lazily, in the stages' dimension order and with times in seconds."""
    return open_dataset(path, load=False)
