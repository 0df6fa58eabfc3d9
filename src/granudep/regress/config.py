"""Regression settings: onset rule, growth-phase fit, which sections enter the A/B fit (eq 36)."""
from __future__ import annotations

from dataclasses import dataclass

from ..config import ConfigError, param


@dataclass(frozen=True)
class RegressConfig:
    onset_depth_factor: float = param(0.5, gt=0.0, le=10.0, unit="1",
                                      doc="onset (t_s)_C: the last upward crossing of h_D = this x dx "
                                          "(after it h_D stays above until the end of the record)")
    onset_max_gap: float = param(0.5, ge=0.0, unit="1",
                                 doc="dips of h_D below the onset depth whose surrounding samples above it lie at "
                                     "most this far apart (in t_s) are bridged (a momentary "
                                     "re-mobilisation does not reset the onset); 0 = never")
    growth_end_fraction: float = param(0.95, gt=0.0, le=1.0, unit="1",
                                       doc="the growth phase fitted for (S_D)_s and the Fig-9 intercept ends at "
                                           "the first sample with h_D >= this x final h_D")
    min_fit_points: int = param(3, ge=2, doc="fewest samples in a growth-phase fit (else NaN rate)")
    fit_x_min: float = param(0.0, ge=0.0, le=1.0, unit="1", doc="lowest [x] entering the A/B fit (eq 36)")
    fit_x_max: float = param(1.0, ge=0.0, le=1.0, unit="1", doc="highest [x] entering the A/B fit (eq 36)")
    min_sections: int = param(3, ge=2, doc="fewest sections with an onset for an A/B fit (else NaN A, B)")

    def validate(self, prefix: str = "") -> None:
        if self.fit_x_min >= self.fit_x_max:
            p = f"{prefix}." if prefix else ""
            raise ConfigError(f"{p}fit_x_max: must be > fit_x_min = {self.fit_x_min} (got {self.fit_x_max})")
