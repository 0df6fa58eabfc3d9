"""Are the outputs of this checkout bit for bit those of another revision? (structure and
numerics go in separate commits, the ISPH and DA outputs unchanged by each structural step)

    python benchmarks/results_unchanged.py [--base main] [--dx 0.008] [--keep DIR] [--threads 1] [--da-only]
        [--isph-only] [--set numerics.projection=approximate ...] [--t-end S]

Runs T22-A70 (2D ISPH at --dx, to rest; not with --da-only), 1D-A70 (DA, with and without
deposition, N = 1000; with deposition also at N = 4000, where the deposit grid follows the release
smoothing length) and the example path (config/da/example_path.yaml at N = 1000, x∞ fixed, with and
without deposition) twice, with this working tree and with --base's src/ (``git archive`` into a temporary folder), each in its own
process on one numba thread (``--threads``) with its own numba cache, and compares every data variable and
coordinate value for value (NaN equal to NaN). Prints the differing arrays and exits 1 when any
differs, 0 when all agree. ``--set KEY=VALUE`` (repeated) runs T22-A70 with those ISPH keys (a
solver or scheme variant the defaults do not reach), ``--t-end`` stops it early, ``--isph-only`` skips
the DA runs. Both runs are made on this machine: OpenBLAS's kernels (np.dot in the
ISPH CG) depend on the CPU, so stored digests would not be comparable across machines.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

RUNNER = """
import sys
import numpy as np
import granudep
import json
dx, out, path_yaml, da_only = float(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4] == "1"
isph_only, isph_keys = sys.argv[5] == "1", json.loads(sys.argv[6])
arrays = {}


def keep(name, ds):
    for k, v in {**ds.coords, **ds.data_vars}.items():
        arrays[f"{name}/{k}"] = np.asarray(v.values)


for dep in (() if isph_only else (True, False)):
    keep(f"1D-A70_{'deposition' if dep else 'nodeposition'}", granudep.run_da("1D-A70", deposition=dep, progress=False))
    keep(f"path_{'deposition' if dep else 'nodeposition'}", granudep.run_da(
        path_yaml, deposition={"x_inf_mode": "user", "x_inf": 730.0} if dep else False, progress=False,
        numerics={"n_particles": 1000}))
if not isph_only:
    keep("1D-A70_deposition_N4000", granudep.run_da("1D-A70", deposition=True, progress=False, n_particles=4000))
status = "no 2D run"
if not da_only:
    ds = granudep.run_isph("T22-A70", dx=dx, progress=False, **isph_keys)
    keep("T22-A70", ds)
    status = ds.attrs["status"]
np.savez(out, **arrays)
print(granudep.__file__, len(arrays), "arrays;", "T22-A70", status)
"""


def _run(src: Path, dx: float, out: Path, cache: Path, threads: int = 1, da_only: bool = False,
         isph_only: bool = False, isph_keys: dict | None = None) -> None:
    env = {**os.environ, "PYTHONPATH": str(src), "NUMBA_NUM_THREADS": str(threads), "NUMBA_CACHE_DIR": str(cache),
           "PYTHONDONTWRITEBYTECODE": "1"}
    subprocess.run([sys.executable, "-c", RUNNER, str(dx), str(out), str(ROOT / "config" / "da" / "example_path.yaml"),
                    "1" if da_only else "0", "1" if isph_only else "0", json.dumps(isph_keys or {})],
                   env=env, check=True, cwd=src.parent)


def _differences(a: Path, b: Path) -> list[str]:
    x, y = np.load(a), np.load(b)
    out = [f"{k}: only in {'the base' if k in x.files else 'this tree'}" for k in sorted(set(x.files) ^ set(y.files))]
    for k in sorted(set(x.files) & set(y.files)):
        u, v = x[k], y[k]
        same = u.shape == v.shape and np.array_equal(u, v, equal_nan=u.dtype.kind in "fc")
        if not same:
            out.append(f"{k}: shape {u.shape} vs {v.shape}" if u.shape != v.shape else
                       f"{k}: {int(np.sum(u != v))} of {u.size} values differ")
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", default="main", help="revision to compare with (default main)")
    ap.add_argument("--dx", type=float, default=0.008, help="2D particle spacing, m (default 0.008)")
    ap.add_argument("--keep", metavar="DIR", help="keep the two .npz files in DIR")
    ap.add_argument("--threads", type=int, default=1,
                    help="NUMBA_NUM_THREADS of both runs (default 1; 2 exercises the parallel builds)")
    ap.add_argument("--da-only", action="store_true", help="the DA runs only (no T22-A70)")
    ap.add_argument("--isph-only", action="store_true", help="T22-A70 only (no DA runs)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="an ISPH config key of the T22-A70 runs, e.g. numerics.projection=approximate")
    ap.add_argument("--t-end", type=float, default=None, help="stop T22-A70 at this time (s; default: at rest)")
    args = ap.parse_args()
    import yaml
    keys = {k: yaml.safe_load(v) for k, v in (a.split("=", 1) for a in args.set)}
    if args.t_end is not None:
        keys["t_end"] = args.t_end
    with tempfile.TemporaryDirectory(prefix="granudep-unchanged-") as tmp:
        tmp = Path(tmp)
        base = tmp / "base"
        base.mkdir()
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", "--format=tar", args.base, "src"],
                                 check=True, capture_output=True).stdout  # the base's package, no checkout
        subprocess.run(["tar", "-x", "-C", str(base)], input=archive, check=True)
        keep = Path(args.keep) if args.keep else tmp
        keep.mkdir(parents=True, exist_ok=True)
        files = {"base": keep / "base.npz", "tree": keep / "tree.npz"}
        for name, src in (("base", base / "src"), ("tree", ROOT / "src")):
            _run(src, args.dx, files[name], tmp / f"cache_{name}", args.threads, args.da_only, args.isph_only, keys)
        diff = _differences(files["base"], files["tree"])
    if diff:
        print(f"outputs differ from {args.base}:\n  " + "\n  ".join(diff))
        return 1
    what = [] if args.da_only else [f"T22-A70 (dx = {args.dx} m{''.join(f', {k} = {v}' for k, v in keys.items())})"]
    if not args.isph_only:
        what.append("1D-A70 (with and without deposition, and N = 4000 with) and the example path (with and without)")
    print(f"every array of {' and '.join(what)} is identical to {args.base}'s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
