"""Nastran-style FLUTTER SUMMARY text of sweep results, to compare line by line with an F06.

One table per case and root, in the layout MSC Nastran prints (tests/data/bah_plane/bah_plane.f06,
pt145.f06, two_mode_flutter/0012_flutter.f06): a header ``POINT = n  MACH NUMBER = ...  DENSITY
RATIO = ...  METHOD = PK`` (``POINT = n  METHOD = PKNL`` for a density sweep), then per flight
point the columns KFREQ, 1./KFREQ, VELOCITY, DAMPING, FREQUENCY and the COMPLEX EIGENVALUE
p = omega (g/2 + i) (real, imaginary); PKNL adds DENSITY and MACH NO. before VELOCITY. POINT is the
root number. As Nastran does, a real root (|Im p| <= 1e-9 |p|; the p-k solver bounds |p| below by
its frequency scale, which only matters for p near 0) prints KFREQ 0, 1./KFREQ 9.9999996E+24
(Nastran's single-precision 1e25), frequency 0 and a zero imaginary part. The DENSITY RATIO is
the density over the sweep's ``rhoref`` attribute (AERO RHOREF; 1.0 when absent, as Nastran
without RHOREF). The unit system (``unit_system`` attribute, see
:func:`flutter.results.label_units`) is printed on each table's configuration line. k-method
tables (K / KE) list the points in increasing k as Nastran's FLFACT order usually is, each root at
its own velocity, and skip the k values where the root has no solution (rigid roots); their
COMPLEX EIGENVALUE is Nastran's K-method one, i V / sqrt(1 + i g) (checked against pt145.f06),
not the p-k form p = omega (g/2 + i) stored in the Dataset. A root the sweep names
(``root_label``, :func:`flutter.rigid_roots.label_rigid_roots`) gets the line ``ROOT = SHORT
PERIOD`` (or ``PLUNGE``, ...) under its POINT line, where Nastran leaves a blank one.

Formatting only: the numbers come from :func:`flutter.pk.pk_solve` / :func:`flutter.kmethod.k_solve`.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from structures.units import unit_labels

INV_K_ZERO = float(np.float32(1e25))   # what Nastran prints as 1./KFREQ of a real root
REAL_ROOT = 1e-9                       # |Im p| <= REAL_ROOT |p|: a real root

_HEAD = ("       KFREQ            1./KFREQ         VELOCITY            DAMPING         FREQUENCY"
         "            COMPLEX   EIGENVALUE")
_HEAD_PKNL = ("    KFREQ          1./KFREQ       DENSITY     MACH NO.      VELOCITY       DAMPING"
              "     FREQUENCY      COMPLEX   EIGENVALUE")


def _rows(ds: xr.Dataset, r: int) -> tuple[np.ndarray, np.ndarray]:
    """Columns (k, 1/k, [density, Mach,] V, g, f, Re p, Im p) of root ``r`` (index), shape
    (npts, 7 or 9), and the point order to print them in."""
    sweep = ds.attrs.get("sweep", "velocity")
    n = ds.sizes[sweep]
    p = ds["eigenvalue"].transpose(sweep, "root").values[:, r]
    g = ds["damping"].transpose(sweep, "root").values[:, r]
    f = ds["frequency"].transpose(sweep, "root").values[:, r]
    if sweep == "k":
        k = ds["k"].values
        V = ds["velocity"].transpose(sweep, "root").values[:, r]
    else:
        k = ds["k"].transpose(sweep, "root").values[:, r]
        V = np.broadcast_to(ds["velocity"].values, (n,))
    real = np.abs(p.imag) <= REAL_ROOT * np.abs(p)
    k, f = np.where(real, 0.0, k), np.where(real, 0.0, f)
    with np.errstate(divide="ignore"):
        inv = np.where(k > 0, 1.0 / np.where(k > 0, k, 1.0), INV_K_ZERO)
    cols = [k, inv]
    if sweep == "density":
        cols += [ds["density"].values, ds["mach"].values]
    if sweep == "k":
        p = 1j * V / np.sqrt(1 + 1j * g)   # Nastran's K / KE eigenvalue (see the module docstring)
    cols += [V, g, f, p.real, np.where(real, 0.0, p.imag)]
    order = np.arange(n)
    if sweep == "k":
        order = np.argsort(k, kind="stable")
        order = order[np.isfinite(V[order])]
    return np.column_stack(cols), order


def format_table(ds: xr.Dataset, root: int, *, title: str = "", case: int = 1) -> str:
    """One FLUTTER SUMMARY table: root ``root`` (1-based) of a sweep Dataset.

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep result (dims (velocity | density | k, root)).
    root : int
        Root number, printed as POINT.
    title : str
        Page heading (e.g. the deck name).
    case : int
        Case number printed in the page heading.

    Returns
    -------
    str
        The table's lines, newline-terminated.
    """
    method = str(ds.attrs.get("method", "PK"))
    labels = unit_labels(ds.attrs.get("unit_system"))
    index = list(ds["root"].values).index(root)
    rows, order = _rows(ds, index)
    name = str(ds["root_label"].values[index]) if "root_label" in ds.coords else ""
    named = f"       ROOT = {name.upper()}" if name else ""
    config = str(ds.attrs.get("configuration", "AEROSG2D")) or "AEROSG2D"
    lines = [f"1    {title}".rstrip(),
             f"0     {method} METHOD{'':<60}CASE {case}",
             "0" + " " * 55 + "FLUTTER  SUMMARY",
             f"{'':25}CONFIGURATION = {config}     UNITS = {labels.system} (VELOCITY {labels.velocity},"
             f" DENSITY {labels.density}, FREQUENCY {labels.frequency})"]
    if ds.attrs.get("sweep") == "density":
        lines += [f"       POINT = {root:4d}     METHOD = {method}", named, "", _HEAD_PKNL]
        lines += ["".join([f"{row[0]:9.4f}", f"{row[1]:18.5E}"] + [f"{x:14.5E}" for x in row[2:]])
                  for row in rows[order]]
    else:
        mach = float(np.atleast_1d(ds["mach"].values)[0])
        rho = float(np.atleast_1d(ds["density"].values)[0])
        ratio = rho / float(ds.attrs.get("rhoref", 1.0))
        lines += [f"       POINT = {root:4d}     MACH NUMBER = {mach:7.4f}     DENSITY RATIO = "
                  f"{ratio:11.4E}     METHOD = {method:<4}", named, "", _HEAD]
        lines += ["".join([f"{row[0]:14.4f}", f"{row[1]:20.7E}"] + [f"{x:18.7E}" for x in row[2:]])
                  for row in rows[order]]
    return "\n".join(lines) + "\n"


def flutter_summary_text(results, *, title: str = "") -> str:
    """FLUTTER SUMMARY tables of one or several sweeps: per sweep (case), one table per root.

    Parameters
    ----------
    results : xarray.Dataset or list of xarray.Dataset
        Sweep results of :func:`flutter.pk.pk_solve` (PK, PKNL) or
        :func:`flutter.kmethod.k_solve` (K).
    title : str
        Page heading.

    Returns
    -------
    str
    """
    sweeps = [results] if isinstance(results, xr.Dataset) else list(results)
    return "".join(format_table(ds, int(r), title=title, case=c + 1)
                   for c, ds in enumerate(sweeps) for r in ds["root"].values)
