"""The paper's case tables (shipped as package data) and the scales every stage shares.

Table 1: 2D ISPH cases ``T{theta}-A{100a}``; Table 5: DA cases ``1D-A{100a}``; Table 3: critical
times; Table 2: materials. Scales (conventions.md): t_c = sqrt(H0/(g cos θ)), p0 = H0 sqrt(g H0 cos θ),
[x] = (x − L0)/(x∞ − L0).
"""
from __future__ import annotations

import math
import re
from functools import lru_cache
from importlib import resources

import pandas as pd

from .config import ConfigError

G = 9.81  # m/s², the paper's value (Section 2.1)
CASE_NAME = re.compile(r"^[A-Za-z0-9_-]+$")


def _table(name: str) -> pd.DataFrame:
    with resources.files("granudep.data").joinpath(name).open() as fh:
        return pd.read_csv(fh)


@lru_cache(maxsize=None)
def table1() -> pd.DataFrame:
    """Table 1: 2D ISPH cases (case_id, theta_deg, H0_m, L0_m, a)."""
    return _table("table1_isph_cases.csv")


@lru_cache(maxsize=None)
def table2() -> pd.DataFrame:
    """Table 2: materials (glass beads, quartz sand)."""
    return _table("table2_materials.csv")


@lru_cache(maxsize=None)
def table3() -> pd.DataFrame:
    """Table 3: the paper's normalised critical times (t_s)_C at [x_M] = 0.2 … 0.8."""
    return _table("table3_critical_times.csv")


@lru_cache(maxsize=None)
def table5() -> pd.DataFrame:
    """Table 5: DA cases at θ = 22° with the paper's A and B."""
    return _table("table5_da_cases.csv")


def material(name: str = "glass_beads") -> dict:
    """One row of Table 2 as a dict in SI units (d in m; the friction angle under the configs' name)."""
    t = table2()
    row = t[t.material == name]
    if row.empty:
        raise ConfigError(f"material: unknown material {name!r} (allowed: {', '.join(t.material)})")
    r = row.iloc[0]
    return {"d": float(r.d_mm) * 1e-3, "rho_s": float(r.rho_s_kg_m3), "solid_fraction": float(r.solid_fraction),
            "rho": float(r.rho_bulk_kg_m3), "phi_internal_deg": float(r.phi_deg)}


def check_case_name(name: str) -> str:
    """Case names become file names: only letters, digits, '_' and '-'."""
    if not CASE_NAME.match(name or ""):
        raise ConfigError(f"case: {name!r} is not a valid case name (allowed characters: A-Z a-z 0-9 _ -)")
    return name


def characteristic_time(H0: float, theta: float, g: float = G) -> float:
    """t_c = sqrt(H0 / (g cos θ)) (Section 4.2.1); θ in radians."""
    return math.sqrt(H0 / (g * math.cos(theta)))


def momentum_scale(H0: float, theta: float, g: float = G) -> float:
    """p0 = H0 sqrt(g H0 cos θ) (Section 4.2.2); θ in radians."""
    return H0 * math.sqrt(g * H0 * math.cos(theta))


def normalised_position(x, L0: float, x_inf: float):
    """[x] = (x − L0)/(x∞ − L0) (eq 35)."""
    return (x - L0) / (x_inf - L0)


def list_cases() -> pd.DataFrame:
    """All named cases: Table 1 (2D ISPH) and Table 5 (DA), one row each."""
    t1 = table1().assign(stage="isph", A=float("nan"), B=float("nan"))
    t5 = table5().assign(stage="da")
    cols = ["case_id", "stage", "theta_deg", "a", "L0_m", "H0_m", "A", "B"]
    return pd.concat([t1[cols], t5[cols]], ignore_index=True)
