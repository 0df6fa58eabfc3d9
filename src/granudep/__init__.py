"""granudep: deposition-aware depth-averaged modelling of granular flows.

Public entry points (the few names users need; internals stay in the subpackages):

* :func:`run_da` — run a 1D depth-averaged SPH case (with or without deposition) → ``xarray.Dataset``
* :func:`run_isph` — run a 2D ISPH column-collapse case → ``xarray.Dataset``
* :func:`monitor` — monitoring-section time series from a 2D run → ``xarray.Dataset``
* :func:`load` — open any granudep NetCDF output
"""
from ._version import __version__
from .config import ConfigError
from .io import open_dataset as load


def run_da(case_or_config, deposition: bool = True, **overrides):
    """Run a DA case by name (``"1D-A70"``), YAML path or dict; returns an ``xarray.Dataset``."""
    from .da.api import run_da as _run
    return _run(case_or_config, deposition=deposition, **overrides)


def run_isph(case_or_config, **overrides):
    """Run a 2D ISPH case by name (``"T22-A70"``), YAML path or dict; returns an ``xarray.Dataset``."""
    from .isph.api import run_isph as _run
    return _run(case_or_config, **overrides)


def monitor(run, **overrides):
    """Monitoring-section time series (eqs 15–17) from a 2D run (Dataset or path)."""
    from .monitor.api import monitor as _run
    return _run(run, **overrides)


__all__ = ["__version__", "ConfigError", "load", "run_da", "run_isph", "monitor"]
