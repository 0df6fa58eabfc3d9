"""The error a 2D run raises when it blows up (below the solver and the linear systems that raise it)."""
from __future__ import annotations


class IsphBlowUp(RuntimeError):
    """A run that produced NaN or lost a particle; ``dataset`` holds the snapshots so far."""

    def __init__(self, message: str, dataset=None):
        super().__init__(message)
        self.dataset = dataset
