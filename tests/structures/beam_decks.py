"""Writers of small beam decks (free-field bulk data) for the structures tests."""
from __future__ import annotations

from pathlib import Path

import numpy as np

E, NU, RHO = 7.0e10, 0.3, 2700.0
LENGTH, AREA, INERTIA = 10.0, 0.01, 1.0e-5


def beam_deck(path: Path, *, nel: int = 40, support: str = "cantilever", plane_only: bool = False,
              cd: int = 0, cp: int = 0, coords: str = "", extra: str = "", nmodes: int = 10,
              i2: float = INERTIA, rotation=None, element: str = "CBAR",
              vector_in_basic: bool = False) -> Path:
    """A uniform CBAR (or CBEAM) beam along x (or along ``rotation @ x``), COUPMASS consistent mass.

    CBEAM (PBEAM with K1 = K2 = 0: no shear flexibility) carries the section's torsional inertia,
    which Nastran's CBAR omits; a free-free CBAR beam has a massless axial rotation.

    support: 'cantilever' (grid 1 clamped) or 'free'. ``plane_only`` keeps only the x-z bending
    DOFs (PS=1246). ``cd``/``cp`` name coordinate systems defined in ``coords``.
    ``vector_in_basic`` writes OFFT = BGG (orientation vector in basic, not in GA's CD frame).
    """
    rot = np.eye(3) if rotation is None else np.asarray(rotation, float)
    lines = ["SOL 103", "CEND", "METHOD = 1"]
    if support == "cantilever":
        lines.append("SPC = 1")
    lines += ["BEGIN BULK", f"EIGRL,1,,,{nmodes}", "PARAM,COUPMASS,1", f"MAT1,1,{E},,{NU},{RHO}",
              f"PBAR,1,1,{AREA},{INERTIA},{i2},{2 * INERTIA}" if element == "CBAR" else
              f"PBEAM,1,1,{AREA},{INERTIA},{i2},0.,{2 * INERTIA}\n"
              ",,,,,,,,\n,0.,0."]
    ps = "1246" if plane_only else ""
    for i in range(nel + 1):
        x = rot @ np.array([LENGTH * i / nel, 0.0, 0.0])
        if cp:
            x = _to_frame(x, coords, cp)
        lines.append(f"GRID,{i + 1},{cp or ''},{x[0]!r},{x[1]!r},{x[2]!r},{cd or ''},{ps}")
    v = rot @ np.array([0.0, 1.0, 0.0])
    if cd and not vector_in_basic:
        v = _frame(coords, cd)[0] @ v  # CBAR X1-X3 are in GA's displacement frame (QRG)
    offt = ",BGG" if vector_in_basic else ""
    for i in range(nel):
        lines.append(f"{element},{i + 1},1,{i + 1},{i + 2},{v[0]!r},{v[1]!r},{v[2]!r}{offt}")
    if support == "cantilever":
        lines.append("SPC1,1,123456,1")
    lines += [coords, extra, "ENDDATA"]
    path.write_text("\n".join(line for line in lines if line) + "\n")
    return path


def _frame(coords, cid):
    """(rows i, j, k in basic; origin) of rectangular frame ``cid`` in ``coords`` (CORD2R only)."""
    for line in coords.replace("\n,", ",").splitlines():
        f = line.split(",")
        if f[0] == "CORD2R" and int(f[1]) == cid:
            a, b, c = (np.array(list(map(float, f[i:i + 3]))) for i in (3, 6, 9))
            k = (b - a) / np.linalg.norm(b - a)
            i_ = (c - a) - np.dot(c - a, k) * k
            i_ /= np.linalg.norm(i_)
            return np.array([i_, np.cross(k, i_), k]), a
    raise KeyError(cid)


def _to_frame(x, coords, cid):
    """Coordinates of basic point x in rectangular frame ``cid`` of ``coords``."""
    rows, origin = _frame(coords, cid)
    return rows @ (x - origin)


def cord2r(cid: int, origin, z_point, xz_point, kind: str = "R") -> str:
    """A CORD2R (or CORD2C/CORD2S with ``kind``) card in free field with one continuation."""
    first = ",".join(repr(float(v)) for v in [*origin, *z_point])
    return f"CORD2{kind},{cid},,{first}\n," + ",".join(repr(float(v)) for v in xz_point)


def bending_frequencies(beta_l, i_val=INERTIA):
    """Euler-Bernoulli f_n = (beta_n L)^2 / (2 pi L^2) sqrt(E I / (rho A)) [Hz]."""
    return np.asarray(beta_l) ** 2 / (2 * np.pi * LENGTH ** 2) * np.sqrt(E * i_val / (RHO * AREA))


# Roots of cos(bL) cosh(bL) = -1 (clamped-free) and = +1 (free-free), Blevins, *Formulas for
# Natural Frequency and Mode Shape*, table 8-1.
CANTILEVER_BETA_L = (1.87510407, 4.69409113, 7.85475744, 10.99554073)
FREE_FREE_BETA_L = (4.73004074, 7.85320462, 10.99560784, 14.13716549)
