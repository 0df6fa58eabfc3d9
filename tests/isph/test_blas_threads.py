"""The ISPH solver pins the BLAS its numba kernels call to one thread (linsolve.pin_blas_to_one_thread)."""
import threadpoolctl

from granudep.isph.config import load_config
from granudep.isph.stepper import IsphSolver


def test_solver_runs_blas_on_one_thread():
    IsphSolver(load_config("T22-A70", **{"numerics.dx": 0.02}))
    blas = [d for d in threadpoolctl.threadpool_info() if d["user_api"] == "blas"]
    assert blas, "no BLAS library loaded"
    assert all(d["num_threads"] == 1 for d in blas), blas


def test_a_run_resumed_from_a_state_pins_blas_too(monkeypatch):
    """A checkpointed solver is unpickled, not constructed: run() pins the BLAS itself."""
    import granudep.isph.linsolve as ls
    from granudep.isph.run import RunState, Snapshots, run
    cfg = load_config("T22-A70", **{"numerics.dx": 0.02, "numerics.t_end": 0.005})
    s = IsphSolver(cfg)
    threadpoolctl.threadpool_limits(limits=2, user_api="blas")
    monkeypatch.setattr(ls, "_BLAS_PINNED", False)

    class Resume:
        def resume(self):
            return RunState(s, Snapshots(), cfg.output.dt_output)

        def after_step(self, state, at_output):
            pass
    run(cfg, checkpoint=Resume())
    assert all(d["num_threads"] == 1 for d in threadpoolctl.threadpool_info() if d["user_api"] == "blas")
