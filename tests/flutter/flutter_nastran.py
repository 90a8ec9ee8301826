"""Readers of Nastran validation output used by the flutter tests (F06 tables, OP4 QHH)."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import xarray as xr

DATA = Path(__file__).resolve().parents[1] / "data"

_NUM = r"[-+]?\d*\.?\d+(?:[Ee][-+]?\d+)?"


def f06_modes_used(f06: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Generalized mass, stiffness and cycles of the 'ACTUAL MODES USED' real-eigenvalue table."""
    text = f06.read_text(errors="replace")
    start = text.index("(ACTUAL MODES USED")
    rows = []
    for line in text[start:].splitlines()[1:]:
        parts = line.split()
        if len(parts) == 7 and parts[0].isdigit():
            rows.append([float(x) for x in parts])
        elif rows:
            break
    a = np.array(rows)
    return a[:, 5], a[:, 6], a[:, 4]


def f06_flutter_summaries(f06: Path) -> list[dict]:
    """Every FLUTTER SUMMARY table of an F06.

    Returns dicts with ``point``, ``mach`` and ``density_ratio`` (PK/KE headers; None for PKNL) and
    ``rows``: columns (k, 1/k, V, g, f, Re, Im) for PK/K/KE, or (k, 1/k, density, Mach, V, g, f, Re,
    Im) for PKNL; ``columns`` names them.
    """
    text = f06.read_text(errors="replace")
    out = []
    for block in text.split("FLUTTER  SUMMARY")[1:]:
        point = int(re.search(r"POINT =\s*(\d+)", block).group(1))
        head = re.search(r"MACH NUMBER =\s*(" + _NUM + r")\s+DENSITY RATIO =\s*(" + _NUM + ")", block)
        rows = []
        for line in block.splitlines()[5:]:
            parts = line.split()
            if len(parts) in (7, 9):
                try:
                    rows.append([float(x) for x in parts])
                    continue
                except ValueError:
                    pass
            if rows:
                break
        rows = np.array(rows)
        names = (("k", "inv_k", "velocity", "damping", "frequency", "re", "im") if rows.shape[1] == 7
                 else ("k", "inv_k", "density", "mach", "velocity", "damping", "frequency", "re", "im"))
        out.append({"point": point, "mach": float(head.group(1)) if head else None,
                    "density_ratio": float(head.group(2)) if head else None, "rows": rows,
                    "columns": names})
    return out


def column(summary: dict, name: str) -> np.ndarray:
    """One named column of a parsed FLUTTER SUMMARY table."""
    return summary["rows"][:, summary["columns"].index(name)]


def first_crossing(summary: dict, along: str = "velocity", g_tol: float = 1e-6) -> dict | None:
    """Linear interpolation of a table's first g crossing from below 0 to above ``g_tol`` along
    increasing velocity (PK, KE) or density (PKNL); returns the interpolated velocity, frequency
    (and density for PKNL)."""
    key = "density" if "density" in summary["columns"] else along
    order = np.argsort(column(summary, key), kind="stable")
    g = column(summary, "damping")[order]
    for i in range(len(g) - 1):
        if g[i] < 0 and g[i + 1] > g_tol:
            t = g[i] / (g[i] - g[i + 1])
            return {name: column(summary, name)[order][i] + t * (column(summary, name)[order][i + 1]
                                                                 - column(summary, name)[order][i])
                    for name in ("velocity", "frequency", "density") if name in summary["columns"]}
    return None


def bah_qhh_dataset() -> xr.Dataset:
    """Nastran's QHH of bah_plane_qhh as a GAF Dataset Q(mach, k, mode_i, mode_j).

    OUTPUT4 QHH stacks one n x n matrix per (Mach, k) in MKAERO1 order: for each MKAERO1 card, for
    each of its Mach numbers, for each of its k values (checked in the tests: at the smallest k the
    imaginary parts vanish like k, and the two Mach blocks differ only slightly).
    """
    from pyNastran.bdf.bdf import read_bdf
    from pyNastran.op4.op4 import read_op4

    folder = DATA / "bah_plane"
    mats = read_op4(str(folder / "bah_plane_qhh.op4"), debug=False)["QHH"].data
    bdf = read_bdf(str(folder / "bah_plane_qhh.bdf"), debug=None)
    table = {}
    i = 0
    for mk in bdf.mkaeros:
        for m in mk.machs:
            for k in mk.reduced_freqs:
                table[(float(m), float(k))] = np.asarray(mats[i], dtype=complex)
                i += 1
    assert i == len(mats)
    machs = sorted({m for m, _ in table})
    ks = sorted({k for _, k in table})
    arr = np.array([[table[(m, k)] for k in ks] for m in machs])
    n = arr.shape[-1]
    return xr.Dataset({"Q": (("mach", "k", "mode_i", "mode_j"), arr)},
                      coords={"mach": machs, "k": ks, "mode_i": np.arange(1, n + 1),
                              "mode_j": np.arange(1, n + 1)},
                      attrs={"refc": float(bdf.aero.cref), "rhoref": float(bdf.aero.rho_ref)})


def bah_flutter_502() -> dict:
    """Nastran's bah_plane FLUTTER 502 as our solvers take it: ``gaf`` (the QHH), ``gm``, ``gk``
    (generalized mass and stiffness of the F06), ``rho``, ``mach``, ``V`` (the FLFACT lists),
    ``sdamp`` (the deck's TABDMP1 2001) and ``summaries`` (the F06's FLUTTER SUMMARY tables at
    that Mach number)."""
    from pyNastran.bdf.bdf import read_bdf

    f06 = DATA / "bah_plane" / "bah_plane.f06"
    gm, gk, _ = f06_modes_used(f06)
    bdf = read_bdf(str(DATA / "bah_plane" / "bah_plane.bdf"), debug=None)
    fl = bdf.flutters[502]
    mach = bdf.flfacts[fl.mach].factors[0]
    return dict(gaf=bah_qhh_dataset(), gm=gm, gk=gk,
                rho=bdf.flfacts[fl.density].factors[0] * bdf.aero.rho_ref, mach=mach,
                V=np.asarray(bdf.flfacts[fl.reduced_freq_velocity].factors, dtype=float),
                sdamp=bdf.tables_sdamping[2001],
                summaries=[s for s in f06_flutter_summaries(f06) if np.isclose(s["mach"], mach)])
