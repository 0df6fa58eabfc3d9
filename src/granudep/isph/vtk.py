"""ParaView export: one PolyData (.vtp, ASCII, points as vertices) per snapshot and a .pvd index."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..io import open_dataset, write_text

_FIELDS = ("u", "v", "pressure", "viscosity", "free_surface")


def _vtp(x, y, fields: dict) -> str:
    n = x.size
    pts = np.column_stack([x, y, np.zeros(n)])
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">', "<PolyData>",
             f'<Piece NumberOfPoints="{n}" NumberOfVerts="{n}" NumberOfLines="0" NumberOfStrips="0" NumberOfPolys="0">',
             "<PointData>"]
    for name, val in fields.items():
        typ = "Int8" if val.dtype == np.int8 else "Float32"
        lines.append(f'<DataArray type="{typ}" Name="{name}" format="ascii">')
        lines.append(" ".join(map(str, val.tolist())))
        lines.append("</DataArray>")
    lines += ["</PointData>", "<Points>", '<DataArray type="Float32" NumberOfComponents="3" format="ascii">',
              " ".join(f"{a:.6g}" for a in pts.ravel()), "</DataArray>", "</Points>", "<Verts>",
              '<DataArray type="Int64" Name="connectivity" format="ascii">', " ".join(map(str, range(n))),
              "</DataArray>", '<DataArray type="Int64" Name="offsets" format="ascii">',
              " ".join(map(str, range(1, n + 1))), "</DataArray>", "</Verts>", "</Piece>", "</PolyData>",
              "</VTKFile>"]
    return "\n".join(lines) + "\n"


def export_vtk(run_path: str | Path, out_dir: str | Path) -> Path:
    """Write OUT/{case}_{k:05d}.vtp for each snapshot and OUT/{case}.pvd; returns the .pvd path."""
    ds = open_dataset(run_path)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    case = ds.attrs.get("case", Path(run_path).stem)
    entries = []
    for k, t in enumerate(ds.time.values):
        snap = ds.isel(time=k)
        fields = {name: np.asarray(snap[name].values) for name in _FIELDS if name in snap}
        name = f"{case}_{k:05d}.vtp"
        write_text(_vtp(np.asarray(snap.x.values, float), np.asarray(snap.y.values, float), fields), out / name)
        entries.append(f'<DataSet timestep="{float(t):.6g}" group="" part="0" file="{name}"/>')
    pvd = ('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
           "<Collection>\n" + "\n".join(entries) + "\n</Collection>\n</VTKFile>\n")
    return write_text(pvd, out / f"{case}.pvd")
