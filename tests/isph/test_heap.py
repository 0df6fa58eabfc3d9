"""granudep.isph.heap: freed blocks stay in the heap (no page faults on the next step's arrays)."""
import os
import subprocess
import sys

import pytest

PROBE = """
import resource, numpy as np
from granudep.isph.heap import keep_freed_memory
ok = keep_freed_memory()
faults = 0
for step in range(6):                   # a step's arrays, their sizes moving a little every step
    f0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    a = np.ones(2_000_000 + 1000 * step)   # 16 MB, above glibc's default 128 kB mmap threshold
    b = np.ones(1_000_000 + 500 * step)
    del a, b
    if step:
        faults += resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f0
print(ok, faults)
"""


def _probe(keep: str):
    env = dict(os.environ, GRANUDEP_KEEP_HEAP=keep)
    out = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, env=env, check=True)
    ok, faults = out.stdout.split()
    return ok == "True", int(faults)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc mallopt")
def test_freed_memory_is_reused_without_page_faults():
    ok, faults = _probe("1")
    off, faults_off = _probe("0")
    assert ok and not off
    # 24 MB per step: glibc's defaults hand (part of) it back and fault it in again, the kept heap reuses it
    assert faults_off > 1000
    assert faults < 50
