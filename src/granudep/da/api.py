"""Python API of the DA model: ``run_da`` (→ xarray.Dataset) and ``warmup``."""
from __future__ import annotations

import math

import xarray as xr

from ..checkpoint import identity as checkpoint_identity
from ..progress import LOG, make_progress
from .checkpoint import Checkpointer, DAInterrupted
from .config import DAConfig, resolve
from .deposition import coefficients, find_x_inf
from .errors import DARunError
from .output import to_dataset
from .physics import earth_pressure_coefficients
from .solver import Physics
from .step import AT_REST, RUNNING
from .solver import simulate as _simulate


def _k(cfg: DAConfig) -> tuple[float, float]:
    m = cfg.material
    return earth_pressure_coefficients(cfg.numerics.earth_pressure, math.radians(m.phi_internal_deg),
                                       math.radians(m.phi_basal_deg), cfg.theta)


def _check(rec, cfg, ds_fn):
    if rec.status not in (RUNNING, AT_REST):
        raise DARunError(rec.message, ds_fn(rec))
    if rec.status == RUNNING:
        LOG.warning("DA %s: %s — flow time undefined; raise numerics.t_end", cfg.case, rec.message)


def run_da(case_or_config, deposition: bool | dict = True, progress=None, checkpoint=None,
           checkpoint_every: float = 600.0, restart=None, **overrides) -> xr.Dataset:
    """Run a DA case: a Table 5 name (``"1D-A70"``), a YAML path, a mapping or a ``DAConfig``.

    ``deposition`` switches the deposition source term (it overrides ``deposition.enabled``), or is
    the ``deposition`` section itself (``deposition={"ab_source": "user", "A": -0.03, "B": 0.04}``:
    deposition on, unless the mapping says ``enabled: false``);
    ``overrides`` are config sections (``numerics={"cfl": 0.1}``) or unique keys
    (``n_particles=500``, ``x_inf_mode="user"``, ``x_inf=0.9``). Bad input raises ConfigError before
    any work; a run that blows up raises :class:`DARunError` carrying the partial dataset.

    ``progress``: None/"auto" (tqdm bar in a terminal or notebook, log lines otherwise), "log",
    "bar" or False. ``checkpoint``: a file the run state is written to every ``checkpoint_every``
    wall seconds and on SIGTERM/SIGINT (inside :func:`granudep.signals.graceful_stop`);
    ``restart``: such a file to continue from (bit-identical to an uninterrupted run). A stop
    raises :class:`granudep.da.checkpoint.DAInterrupted` with the partial dataset as ``dataset``.
    """
    cfg = resolve(case_or_config, deposition=deposition, **overrides)
    deposition = cfg.deposition.enabled
    if cfg.geometry.path is not None:  # a slope profile: granudep.da.path_run
        from .path_run import run_path
        return run_path(cfg, deposition)
    ka, kp = _k(cfg)
    ckpt = Checkpointer(checkpoint_identity(cfg), checkpoint, checkpoint_every, restart)
    progress = make_progress(progress, cfg.output.progress_every_s, total=cfg.numerics.t_end, desc=f"DA {cfg.case}")
    ckpt.progress = progress
    label = f"{cfg.case} ({'deposition' if deposition else 'no deposition'})"

    def simulate(cfg, phys, label, progress):
        def run(hook):
            try:
                return _simulate(cfg, phys, label, progress, checkpoint=hook)
            except DAInterrupted as exc:
                exc.dataset = to_dataset(cfg, exc.record, deposition=phys.deposition, physics=phys,
                                         A=phys.A if phys.deposition else float("nan"),
                                         B=phys.B if phys.deposition else float("nan"))
                exc.dataset.attrs["status"] = f"interrupted: {exc}"
                raise
        return ckpt.simulate(f"{label}|{phys!r}", run)

    try:
        ds = _run(cfg, deposition, ka, kp, label, progress, simulate)
    finally:
        progress.close()
    ckpt.remove()
    return ds


def _run(cfg, deposition, ka, kp, label, progress, simulate) -> xr.Dataset:
    if not deposition:
        phys = Physics(ka, kp, False)
        rec = simulate(cfg, phys, label, progress)
        _check(rec, cfg, lambda r: to_dataset(cfg, r, deposition=False, physics=phys))
        return to_dataset(cfg, rec, deposition=False, physics=phys)

    A, B, source = coefficients(cfg)   # ConfigError before any work
    dep = cfg.deposition
    LOG.info("DA %s: A = %.5g, B = %.5g from %s (%s), x_inf mode %s", cfg.case, A, B, source,
             dep.coefficient_units, dep.x_inf_mode)

    def run_with(x_inf: float):
        phys = Physics(ka, kp, True, A, B, x_inf)
        rec = simulate(cfg, phys, f"{label}, x_inf = {x_inf:.4f} m", progress)
        _check(rec, cfg, lambda r: to_dataset(cfg, r, deposition=True, physics=phys, A=A, B=B, ab_source=source))
        return rec

    def run_without():
        phys0 = Physics(ka, kp, False)
        rec0 = simulate(cfg, phys0, f"{cfg.case} (no deposition, for x_inf)", progress)
        _check(rec0, cfg, lambda r: to_dataset(cfg, r, deposition=False, physics=phys0))
        return rec0

    xinf = find_x_inf(dep, run_with, run_without, cfg.geometry.L0, cfg.case)
    phys = Physics(ka, kp, True, A, B, xinf.x_inf)
    return to_dataset(cfg, xinf.record, deposition=True, physics=phys, A=A, B=B, ab_source=source, xinf=xinf)


def warmup() -> None:
    """Compile every numba kernel with a tiny run (with deposition, wall and friction)."""
    run_da({"case": "warmup", "geometry": {"L0": 0.05, "H0": 0.02, "theta_deg": 10.0},
            "numerics": {"n_particles": 40, "t_end": 0.05},
            "deposition": {"ab_source": "user", "A": -0.03, "B": 0.04, "x_inf_mode": "user", "x_inf": 0.1},
            "output": {"dt_output": 0.025}}, deposition=True)
