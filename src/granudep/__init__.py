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
# The subpackage ``granudep.monitor`` shares its name with the function below. Importing a
# subpackage for the first time binds it as an attribute of its parent, which replaced the
# function by the module after the first call ("'module' object is not callable"). Import it
# here, before the function is defined, so the later imports find it loaded and bind nothing.
from . import monitor as _monitor_package  # noqa: F401  (light: the subpackage __init__ only)


def run_da(case_or_config, deposition=True, **overrides):
    """Run a DA case by name (``"1D-A70"``), YAML path or dict; returns an ``xarray.Dataset``.

    ``deposition``: true/false, or the ``deposition`` section as a dict; other sections as dicts
    (``numerics={"n_particles": 500}``) or unique keys (``n_particles=500``)."""
    from .da.api import run_da as _run
    return _run(case_or_config, deposition=deposition, **overrides)


def run_isph(case_or_config, **overrides):
    """Run a 2D ISPH case by name (``"T22-A70"``), YAML path or dict; returns an ``xarray.Dataset``.

    Overrides: sections as dicts (``numerics={"dx": 0.01}``), ``section.key`` or unique keys (``dx=0.01``)."""
    from .isph.api import run_isph as _run
    return _run(case_or_config, **overrides)


def monitor(run, **overrides):
    """Monitoring-section time series (eqs 15–17) from a 2D run (Dataset or path)."""
    from .monitor.api import monitor as _run
    return _run(run, **overrides)


__all__ = ["__version__", "ConfigError", "load", "run_da", "run_isph", "monitor"]
