"""Signals never land inside a write, stale temporaries go, DA runs restart bit-identically."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import granudep
from granudep.da import checkpoint as C
from granudep.io import atomic_path, write_netcdf
from granudep.signals import STOP

DA_ARGS = dict(deposition={"ab_source": "user", "A": -0.03, "B": 0.05}, n_particles=60, progress=False)


def _small_dataset():
    from granudep.io import provenance, var
    ds = xr.Dataset({"a": var(np.arange(5.0), ("time",), "m", "a")},
                    coords={"time": var(np.arange(5.0), ("time",), "s", "time")})
    return provenance(ds, case="x", config_yaml="{}\n")


def test_sigint_during_a_write_is_delivered_after_it(tmp_path):
    out = tmp_path / "f.txt"
    # a process started in the background of a non-interactive shell inherits SIGINT ignored
    # (POSIX), and Python then leaves it so: give the test Python's own Ctrl-C handler
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        _sigint_during_a_write(out, tmp_path)
    finally:
        signal.signal(signal.SIGINT, before)


def _sigint_during_a_write(out, tmp_path):

    def write(tmp: Path):
        with open(tmp, "w") as fh:
            fh.write("first half\n")
            os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C in the middle of the write
            fh.write("second half\n")

    with pytest.raises(KeyboardInterrupt):
        atomic_path(out, write)
    assert out.read_text() == "first half\nsecond half\n"  # the write completed, then the signal acted
    assert not list(tmp_path.glob(".*.tmp"))
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_stale_temporaries_of_dead_writers_are_removed(tmp_path):
    out = tmp_path / "run.nc"
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale = tmp_path / f".run.nc.{dead.pid}.abcd1234.tmp"
    live = tmp_path / f".run.nc.{os.getpid()}.efgh5678.tmp"
    other = tmp_path / f".other.nc.{dead.pid}.abcd1234.tmp"
    for p in (stale, live, other):
        p.write_bytes(b"half a file")
    write_netcdf(_small_dataset(), out)
    assert not stale.exists() and live.exists() and other.exists()
    assert granudep.load(out).sizes["time"] == 5


def test_da_restart_continues_bit_identically(tmp_path, monkeypatch):
    ref = granudep.run_da("1D-A70", **DA_ARGS)
    assert ref.attrs["x_inf_iterations"] >= 2
    ck = tmp_path / "run.ckpt"
    orig = C.Checkpointer.at_output
    calls = {"n": 0}

    def at_output(self, key, fn):  # a SIGTERM arrives in the third simulation (an x_inf iterate)
        calls["n"] += 1
        if len(self.completed) == 2 and STOP.signum is None:
            STOP.signum = signal.SIGTERM
        return orig(self, key, fn)

    monkeypatch.setattr(C.Checkpointer, "at_output", at_output)
    try:
        with pytest.raises(C.DAInterrupted, match="stopped by SIGTERM at t = ") as exc:
            granudep.run_da("1D-A70", checkpoint=ck, checkpoint_every=1e9, **DA_ARGS)
    finally:
        STOP.clear()
    assert exc.value.checkpoint == ck and ck.is_file()
    assert exc.value.dataset.attrs["status"].startswith("interrupted")
    monkeypatch.setattr(C.Checkpointer, "at_output", orig)
    again = granudep.run_da("1D-A70", checkpoint=ck, restart=ck, **DA_ARGS)
    for name in ref.variables:
        assert np.array_equal(ref[name].values, again[name].values, equal_nan=True), name
    assert {k: v for k, v in ref.attrs.items() if k != "history"} == \
        {k: v for k, v in again.attrs.items() if k != "history"}
    assert not ck.exists()  # a finished run removes its checkpoint


def test_restart_refuses_another_runs_checkpoint(tmp_path):
    ck = tmp_path / "run.ckpt"
    C.Checkpointer("identity A", ck).save()
    with pytest.raises(granudep.ConfigError, match="--restart: .* was written by another run"):
        granudep.run_da("1D-A70", restart=ck, **DA_ARGS)
    (tmp_path / "junk.ckpt").write_text("not a pickle")
    with pytest.raises(granudep.ConfigError, match="is not a readable granudep checkpoint"):
        granudep.run_da("1D-A70", restart=tmp_path / "junk.ckpt", **DA_ARGS)


def test_isph_stop_request_writes_the_partial_output(tmp_path):
    from granudep.isph.api import IsphInterrupted, run_isph
    out = tmp_path / "T22-A70.nc"
    STOP.signum = signal.SIGTERM
    try:
        with pytest.raises(IsphInterrupted, match="stopped by SIGTERM"):
            run_isph("T22-A70", output=out, dx=0.02, t_end=0.05, progress=False)
    finally:
        STOP.clear()
    assert not out.exists()  # never a partial run under the final name
    part = granudep.load(tmp_path / "T22-A70.interrupted.nc")
    assert part.attrs["status"].startswith("interrupted") and part.sizes["time"] >= 1


@pytest.mark.slow
def test_da_cli_sigterm_then_restart_auto(tmp_path):
    """The real thing: SIGTERM to `granudep da` -> exit 143, one line, checkpoint; rerun continues."""
    out = tmp_path / "run.nc"
    cmd = [sys.executable, "-m", "granudep", "da", "1D-A70", "--ab-source", "user", "--set", "deposition.A=-0.03",
           "--set", "deposition.B=0.05", "--n-particles", "60", "--set", "output.progress_every_s=1e-9",
           "-o", str(out)]
    env = {**os.environ, "PYTHONPATH": str(Path(granudep.__file__).parents[1])}
    proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
    lines = []
    for line in proc.stderr:  # wait until the run is stepping
        lines.append(line)
        if "x_inf iteration 1" in line:
            proc.send_signal(signal.SIGTERM)
            break
    rest = proc.stderr.read()
    rc = proc.wait()
    errors = [ln for ln in (lines + rest.splitlines()) if " ERROR " in ln]
    assert rc == 128 + signal.SIGTERM, "".join(lines) + rest
    assert len(errors) == 1 and "stopped by SIGTERM" in errors[0] and "--restart" in errors[0], errors
    ck = tmp_path / ".run.ckpt"
    assert ck.is_file() and not out.exists() and (tmp_path / "run.interrupted.nc").is_file()
    assert not list(tmp_path.glob(".*.tmp"))
    done = subprocess.run(cmd + ["--restart", "auto"], capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    assert "continuing" in done.stderr or "restored" in done.stderr, done.stderr
    ref = granudep.run_da("1D-A70", **DA_ARGS)
    got = granudep.load(out)
    for name in ("front_position", "x", "u", "deposit_depth", "x_inf_history"):
        assert np.array_equal(ref[name].values, got[name].values, equal_nan=True), name


WRITER = r"""
import os, signal, sys, threading, time
import numpy as np, xarray as xr
from granudep.io import provenance, var, write_netcdf
ds = xr.Dataset({"x": var(np.random.default_rng(0).random((400, 20000), dtype=np.float32), ("time", "particle"),
                          "m", "x")}, coords={"time": var(np.arange(400.0), ("time",), "s", "time")})
provenance(ds, case="big", config_yaml="{}")
delay = float(sys.argv[2])
threading.Timer(delay, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
try:
    write_netcdf(ds, sys.argv[1])
    time.sleep(1.0)  # the signal, if it came after the write, lands here
except KeyboardInterrupt:
    print("interrupted", flush=True)
    sys.exit(130)
"""


@pytest.mark.parametrize("delay", [0.1, 0.5])  # inside the write (without the fix: a hang in 2 of 2)
def test_ctrl_c_during_a_netcdf_write_does_not_hang(tmp_path, delay):
    out = tmp_path / "big.nc"
    env = {**os.environ, "PYTHONPATH": str(Path(granudep.__file__).parents[1])}
    proc = subprocess.run([sys.executable, "-c", WRITER, str(out), str(delay)], capture_output=True, text=True,
                          timeout=120, env=env)  # a hang fails here
    assert proc.returncode in (0, 130), proc.stderr
    assert "Traceback" not in proc.stderr, proc.stderr
    assert not list(tmp_path.glob(".*.tmp"))
    if out.exists():  # complete, never truncated
        assert granudep.load(out).x.shape == (400, 20000)


@pytest.mark.slow
def test_isph_cli_sigterm_one_line_and_partial_output(tmp_path):
    out = tmp_path / "T22-A70.nc"
    env = {**os.environ, "PYTHONPATH": str(Path(granudep.__file__).parents[1])}
    proc = subprocess.Popen([sys.executable, "-m", "granudep", "isph", "T22-A70", "--dx", "0.01", "--set",
                             "output.progress_every_s=1e-9", "-o", str(out)], stderr=subprocess.PIPE, text=True, env=env)
    lines = []
    for line in proc.stderr:
        lines.append(line)
        if "steps=" in line and len(lines) > 3:
            proc.send_signal(signal.SIGTERM)
            break
    lines += proc.stderr.read().splitlines(True)
    assert proc.wait() == 128 + signal.SIGTERM
    errors = [ln for ln in lines if " ERROR " in ln or "Traceback" in ln]
    assert len(errors) == 1 and "stopped by SIGTERM" in errors[0] and "--restart" in errors[0], errors
    assert not out.exists() and not list(tmp_path.glob(".*.tmp"))
    assert granudep.load(tmp_path / "T22-A70.interrupted.nc").attrs["status"].startswith("interrupted")
    assert (tmp_path / ".T22-A70.ckpt").is_file()  # what --restart auto continues (tests/isph/test_checkpoint.py)
