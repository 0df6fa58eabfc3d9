"""ISPH checkpoint/restart. A run stopped mid-run (a checkpoint written after step N, then
the process lost; or SIGTERM at an output time) and restarted from its checkpoint gives every array
of the output bit for bit as the uninterrupted run: the renumbering every 10 steps, the warm-start
arrays, the statistics, the energy budget and the time loop's counters survive the file."""
from __future__ import annotations

import pickle
import signal

import numpy as np
import pytest

from granudep.cli import main
from granudep.config import ConfigError
from granudep.io import open_dataset
from granudep.isph.api import IsphInterrupted, run_isph
from granudep.isph.checkpoint import IsphCheckpointer
from granudep.signals import STOP

RUN = dict(dx=0.008, t_end=0.3, progress=False)
#: the adjoint-pair projection with the projection's wall reaction: p_wall, wall_dry, wall_an in play
PAIR = {"numerics.projection": "adjoint_pair", "wall.slip": "coulomb", "wall.coulomb_normal": "projection"}
TIMING = {"history", "wall_time_s", "ms_per_step"}  # wall-clock attributes differ between any two runs


class Lost(Exception):
    """The process died right after the checkpoint was written."""


def assert_identical(ref, got):
    assert set(ref.variables) == set(got.variables)
    for name in ref.variables:
        assert np.array_equal(ref[name].values, got[name].values, equal_nan=True), name
    keys = set(ref.attrs) - TIMING
    assert keys == set(got.attrs) - TIMING
    for k in keys:
        assert np.array_equal(ref.attrs[k], got.attrs[k], equal_nan=not isinstance(ref.attrs[k], str)), k


def test_restart_after_a_mid_run_checkpoint_is_bit_identical(tmp_path, monkeypatch):
    ref = run_isph("T22-A70", **RUN)
    assert ref.attrs["n_steps"] > 100 and ref.sizes["time"] > 20
    ck = tmp_path / "run.ckpt"
    orig = IsphCheckpointer.after_step

    def after_step(self, state, at_output):  # step 37: between output times, 7 steps after a renumbering
        if state.solver.step_no == 37:
            assert not at_output and state.solver.permuted
            self.write(state=state)
            raise Lost
        return orig(self, state, at_output)

    monkeypatch.setattr(IsphCheckpointer, "after_step", after_step)
    with pytest.raises(Lost):
        run_isph("T22-A70", checkpoint=ck, checkpoint_every=1e9, **RUN)
    monkeypatch.setattr(IsphCheckpointer, "after_step", orig)
    assert ck.is_file() and not list(tmp_path.glob(".*.tmp"))
    data = pickle.loads(ck.read_bytes())
    assert data["version"] and "case: T22-A70" in data["identity"] and data["state"].solver.step_no == 37
    out = tmp_path / "T22-A70.nc"
    got = run_isph("T22-A70", output=out, checkpoint=ck, restart=ck, **RUN)
    assert_identical(ref, got)
    assert_identical(ref, open_dataset(out))
    assert not ck.exists()  # a finished run removes its checkpoint


def test_sigterm_then_restart_is_bit_identical_with_the_adjoint_pair(tmp_path, monkeypatch):
    ref = run_isph("T22-A70", **RUN, **PAIR)
    ck = tmp_path / "run.ckpt"
    orig = IsphCheckpointer.after_step

    def after_step(self, state, at_output):  # SIGTERM during step 55: the stop comes at the next output
        if state.solver.step_no == 55 and STOP.signum is None:
            STOP.signum = signal.SIGTERM
        return orig(self, state, at_output)

    monkeypatch.setattr(IsphCheckpointer, "after_step", after_step)
    out = tmp_path / "T22-A70.nc"
    try:
        with pytest.raises(IsphInterrupted, match="stopped by SIGTERM") as exc:
            run_isph("T22-A70", output=out, checkpoint=ck, checkpoint_every=1e9, **RUN, **PAIR)
    finally:
        STOP.clear()
    monkeypatch.setattr(IsphCheckpointer, "after_step", orig)
    assert exc.value.checkpoint == ck and ck.is_file() and not out.exists()
    s = pickle.loads(ck.read_bytes())["state"].solver
    assert s.step_no > 55 and s.p_wall is not None and s.wall_dry is not None and s.wall_an is not None
    assert (tmp_path / "T22-A70.interrupted.nc").is_file()
    assert_identical(ref, run_isph("T22-A70", checkpoint=ck, restart=ck, **RUN, **PAIR))


def test_restart_refusals_are_one_line(tmp_path):
    ck = tmp_path / "run.ckpt"
    with pytest.raises(ConfigError, match=r"^--restart: checkpoint file not found: "):
        run_isph("T22-A70", restart=ck, **RUN)
    ck.write_bytes(b"not a pickle")
    with pytest.raises(ConfigError, match=r"^--restart: .* is not a readable granudep checkpoint \(") as exc:
        run_isph("T22-A70", restart=ck, **RUN)
    assert "\n" not in str(exc.value)
    ck.write_bytes(pickle.dumps({"format": "granudep-da-checkpoint-1"}))
    with pytest.raises(ConfigError, match=r"is not a granudep ISPH checkpoint$"):
        run_isph("T22-A70", restart=ck, **RUN)
    from granudep.checkpoint import identity
    from granudep.isph.config import load_config
    IsphCheckpointer(identity(load_config("T22-A70", dx=0.008, t_end=0.2)), ck).write(state=None)
    with pytest.raises(ConfigError, match=r"^--restart: .* was written by another run \(different config or "
                                          r"granudep version\); rerun without --restart or with the same inputs$"):
        run_isph("T22-A70", restart=ck, **RUN)
    with pytest.raises(ConfigError, match=r"^--checkpoint-every: must be >= 0 s"):
        run_isph("T22-A70", checkpoint=ck, checkpoint_every=-1.0, **RUN)


def test_cli_restart_flags(tmp_path, monkeypatch, capsys):
    out = tmp_path / "T22-A70.nc"
    args = ["isph", "T22-A70", "--dx", "0.008", "--t-end", "0.3", "--progress", "off", "-o", str(out)]
    assert main(args + ["--restart", str(tmp_path / "missing.ckpt")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--restart: checkpoint file not found" in err[0], err
    # --restart auto: the default checkpoint next to the output (.T22-A70.ckpt), written mid-run
    ck = tmp_path / ".T22-A70.ckpt"
    orig = IsphCheckpointer.after_step

    def after_step(self, state, at_output):
        if state.solver.step_no == 23:
            self.write(state=state)
            raise Lost
        return orig(self, state, at_output)

    monkeypatch.setattr(IsphCheckpointer, "after_step", after_step)
    with pytest.raises(Lost):
        main(args)
    monkeypatch.setattr(IsphCheckpointer, "after_step", orig)
    assert ck.is_file() and not out.exists()
    assert main(args + ["--restart", "auto"]) == 0
    assert not ck.exists()
    assert_identical(run_isph("T22-A70", **RUN), open_dataset(out))
    assert main(args + ["--restart", "auto"]) == 0  # no checkpoint: auto starts afresh
