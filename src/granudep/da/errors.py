"""The error a DA run raises when it blows up or leaves the domain (below the drivers that raise it)."""
from __future__ import annotations

import xarray as xr


class DARunError(RuntimeError):
    """A run that blew up or left the domain; ``dataset`` holds everything written until then."""

    def __init__(self, message: str, dataset: xr.Dataset | None = None):
        super().__init__(message)
        self.dataset = dataset
