"""Writers of small rectangular-plate Nastran decks for the plate and MYSTRAN tests.

Plain fixed-format text (8-character fields), so that both pyNastran and MYSTRAN read it.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from structures.bulk_text import card


def plate_deck(path: Path, *, a: float = 1.0, b: float = 0.6, t: float = 0.005, nx: int = 20,
               ny: int = 12, e: float = 7.0e10, nu: float = 0.3, rho: float = 2700.0,
               boundary: str = "ss", element: str = "CQUAD4", mid3: bool = True,
               rotation: np.ndarray | None = None, nmodes: int = 6,
               params: dict[str, object] | None = None) -> Path:
    """Write a SOL 103 deck of an a x b plate (x along a, y along b) meshed nx x ny.

    boundary "ss": T1, T2, T3 fixed on all edges (simply supported: rotations free);
    "cantilever": all six components fixed along the edge x = 0. element "CTRIA3" splits each
    quad along its G1-G3 diagonal. ``rotation`` (3, 3) maps the plate into a different orientation
    in the basic frame (grids are written at R @ [x, y, 0]). Case control asks DISP(PLOT)=ALL so
    that MYSTRAN writes an OP2.
    """
    R = np.eye(3) if rotation is None else np.asarray(rotation, float)
    x = np.linspace(0.0, a, nx + 1)
    y = np.linspace(0.0, b, ny + 1)
    X, Y = np.meshgrid(x, y, indexing="ij")
    xyz = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)]) @ R.T
    gid = np.arange(1, X.size + 1).reshape(X.shape)
    lines = ["SOL 103", "CEND", "TITLE = PLATE", "METHOD = 1", "SPC = 1", "DISP(PLOT) = ALL",
             "BEGIN BULK"]
    for (name, value) in (params or {}).items():
        lines.append(card("PARAM", name, value))
    lines.append(card("EIGRL", 1, None, None, nmodes))
    lines.append(card("MAT1", 1, e, None, nu, rho))
    lines.append(card("PSHELL", 1, 1, t, 1, None, 1 if mid3 else None))
    for g, p in zip(gid.ravel(), xyz):
        lines.append(card("GRID", int(g), None, *(float(f"{c:.12g}") for c in p)))
    eid = 1
    for i in range(nx):
        for j in range(ny):
            g1, g2, g3, g4 = gid[i, j], gid[i + 1, j], gid[i + 1, j + 1], gid[i, j + 1]
            if element == "CQUAD4":
                lines.append(card("CQUAD4", eid, 1, g1, g2, g3, g4))
                eid += 1
            else:
                lines.append(card("CTRIA3", eid, 1, g1, g2, g3))
                lines.append(card("CTRIA3", eid + 1, 1, g1, g3, g4))
                eid += 2
    if boundary == "ss":
        edge = np.unique(np.concatenate([gid[0], gid[-1], gid[:, 0], gid[:, -1]]))
        comps = 123
    elif boundary == "cantilever":
        edge = gid[0]
        comps = 123456
    else:
        raise ValueError(f"boundary must be 'ss' or 'cantilever', not {boundary!r}")
    for start in range(0, len(edge), 6):
        lines.append(card("SPC1", 1, comps, *(int(g) for g in edge[start:start + 6])))
    lines.append("ENDDATA")
    path = Path(path)
    path.write_text("\n".join(lines) + "\n")
    return path
