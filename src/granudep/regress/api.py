"""Critical-momentum regression (Section 4.2): section files → critical.csv, coefficients.csv/.nc,
Table 3 and Table 5 comparisons."""
from __future__ import annotations

from pathlib import Path

import pandas as pd
import xarray as xr
import yaml

from ..config import ConfigError, flat_config, to_dict
from ..io import open_dataset, provenance, write_netcdf, write_text
from .coefficients import coefficient_table, coefficients_dataset
from .paper_tables import table3_comparison, table5_comparison
from .config import RegressConfig
from .critical import critical_table

CRITICAL_COLUMNS = ["case", "theta_deg", "a", "x_norm", "t_s_critical", "t_s_critical_fit", "deposition_rate",
                    "r2", "momentum_critical_norm"]


def _load(item) -> tuple[xr.Dataset, str]:
    if isinstance(item, xr.Dataset):
        return item, str(item.attrs.get("case", "dataset"))
    path = Path(item)
    if not path.is_file():
        raise ConfigError(f"sections: file not found: {path}")
    return open_dataset(path, what="sections"), str(path)


def regress(sections, **overrides) -> dict:
    """Run the regression over section datasets (or paths). Returns a dict with DataFrames
    ``critical``, ``coefficients``, ``table3``, ``table5``, the Dataset ``coefficients_nc`` and
    ``config``."""
    cfg = flat_config(RegressConfig, overrides=overrides, prefix="regress")
    if isinstance(sections, (str, Path, xr.Dataset)):
        sections = [sections]
    if not sections:
        raise ConfigError("sections: give at least one sections file")
    loaded = [_load(s) for s in sections]  # check every input before any work
    names = [str(ds.attrs.get("case", "run")) for ds, _ in loaded]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ConfigError(f"sections: case {dup[0]!r} given more than once (one sections file per case)")
    critical = pd.concat([critical_table(ds, cfg) for ds, _ in loaded], ignore_index=True)
    critical = critical[CRITICAL_COLUMNS + [c for c in critical.columns if c not in CRITICAL_COLUMNS]]
    coeffs = coefficient_table(critical, cfg)
    nc = coefficients_dataset(coeffs)
    cfg_text = yaml.safe_dump({"regress": to_dict(cfg), "inputs": [src for _, src in loaded]}, sort_keys=False)
    provenance(nc, case="regression", config_yaml=cfg_text,
               title="granudep critical depth-averaged momentum coefficients A, B (eq 36)")
    return {"critical": critical, "coefficients": coeffs, "coefficients_nc": nc,
            "table3": table3_comparison(critical), "table5": table5_comparison(coeffs), "config": cfg}


def write_outputs(result: dict, outdir) -> list[Path]:
    """DIR/critical.csv, coefficients.csv, coefficients.nc, table3_comparison.csv, table5_comparison.csv."""
    outdir = Path(outdir)
    paths = [
        write_text(result["critical"].to_csv(index=False), outdir / "critical.csv"),
        write_text(result["coefficients"].to_csv(index=False), outdir / "coefficients.csv"),
        write_netcdf(result["coefficients_nc"], outdir / "coefficients.nc"),
        write_text(result["table3"].to_csv(index=False), outdir / "table3_comparison.csv"),
        write_text(result["table5"].to_csv(index=False), outdir / "table5_comparison.csv"),
    ]
    return paths
