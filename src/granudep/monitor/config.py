"""Monitoring-section settings (Section 2.2, Section 3, Appendix of Nikooei & Choi 2022).

Defaults are the paper's: 11 sections from the gate x = L0 to the final front x∞, width
W_M = 2Δx, critical speed 0.1 m/s separating flowing from deposited particles, ∇·r threshold 1.6
for F/D interface particles (eq 16).
"""
from __future__ import annotations

from dataclasses import dataclass

from ..config import ConfigError, param


@dataclass(frozen=True)
class MonitorConfig:
    n_sections: int = param(11, ge=2, le=1001,
                            doc="number of equally spaced sections from x = L0 to x = x_inf (paper: 11)")
    width_factor: float = param(2.0, gt=0.0, le=50.0, unit="1",
                                doc="section width W_M in units of the run's particle spacing dx (paper: 2)")
    critical_speed: float = param(0.1, gt=0.0, unit="m/s",
                                  doc="|v| below which a particle counts as deposited (paper: 0.1 m/s)")
    divergence_threshold: float = param(1.6, gt=0.0, lt=2.0, unit="1", was="interface_threshold",
                                        doc="eq 16: a deposited particle with (div r) over deposited "
                                            "neighbours below this is an F/D interface particle (paper: 1.6)")
    bed_mirror: bool = param(True, doc="count mirror images of deposited particles below the bed y = 0 "
                                       "in eq 16 (the rigid bed is at rest; the run holds no wall particles)")
    x_inf: float | None = param(None, gt=0.0, unit="m",
                                doc="final runout x_inf (m from the back wall); null = the run's front named by "
                                    "x_inf_front")
    x_inf_front: str = param("v99", choices=("v99", "5mm", "2d", "tail", "position"),
                             doc="which final front of the 2D run is x_inf (eq 35): v99 = the point beyond which "
                                 "1 % of the deposit lies (default: resolved at every dx), 5mm / 2d = the attached "
                                 "front at that thickness, tail = the attached mass at any thickness, position = "
                                 "the run's final_front_position (its default front, 2 d)")
    wm_factors: tuple[float, ...] = param((1.0, 2.0, 3.0, 4.0), unit="1",
                                          doc="monitor-wm: section widths in units of dx (Appendix: 1..4)")
    wm_reference: float = param(2.0, gt=0.0, unit="1",
                                doc="monitor-wm: the width (units of dx) the RMS deviation is taken against")
    wm_stop_fraction: float = param(0.01, ge=0.0, lt=1.0, unit="1",
                                    doc="monitor-wm: the deceleration window of a section runs from the peak "
                                        "of the reference hu to the first time hu < this fraction of the peak")

    def validate(self, prefix: str = "") -> None:
        p = f"{prefix}." if prefix else ""
        if not self.wm_factors:
            raise ConfigError(f"{p}wm_factors: must list at least one width factor > 0 (got empty)")
        for i, w in enumerate(self.wm_factors):
            if not w > 0:
                raise ConfigError(f"{p}wm_factors[{i}]: must be > 0 (got {w!r})")
        if self.wm_reference not in self.wm_factors:
            raise ConfigError(f"{p}wm_reference: must be one of wm_factors {list(self.wm_factors)} "
                              f"(got {self.wm_reference!r})")
