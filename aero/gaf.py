"""Generalized aerodynamic forces Q_hh(M, k) from the doublet-lattice method and the splines.

Nastran's definition (MSC Nastran Aeroelastic Analysis User's Guide, section 2.5 "Generalized
aerodynamic forces"; Rodden & Johnson, eqs. 2-35..2-40)::

    Q_hh = Phi^T G_kg^T W_kk S_kj A_jj^-1 D_jk G_kg Phi

so that the generalized aerodynamic force on the modal coordinates u_h is ``q * Q_hh @ u_h`` for
harmonic motion ``u_h e^{i omega t}``, q = rho V^2 / 2. Here:

* G_kg Phi: the box motion of each mode from the splines (:mod:`aero.splines`): normal
  displacement h and slope dh/dx at the 3/4-chord collocation points, h at the 1/4-chord load
  points;
* D_jk = d/dx + i k / b: the normalwash over V of the harmonic motion, ``w/V = dh/dx + i (k/b) h``
  (flow tangency; b = REFC / 2, k = omega b / V);
* A_jj^-1: the doublet-lattice pressure solution, ``Delta Cp = D^-1 (w/V)`` with
  ``D = aero.dlm.dlm_aic`` ({w/V} = D {Delta Cp});
* S_kj: box area integration, the box force ``q * area * Delta Cp`` along the box normal acting at
  the box's 1/4-chord load point; W_kk = I;
* Phi^T G_kg^T: the work of those forces on the modal displacement h at the load points.

The signs and the half-model convention (SYMXZ: forces on the modelled half only) agree with
Nastran's QHH of the BAH wing (tests/aero/test_gaf.py; that run used the parabolic kernel).
Reduced frequency is Nastran's k = omega * b / V with b = REFC / 2.
"""
from __future__ import annotations

import warnings

import numpy as np
import xarray as xr
from scipy.interpolate import CubicSpline

from aero import dlm as _dlm
from aero.splines import SplineMatrices, spline_frame, spline_transform
from structures.common.errors import InputError, MissingReferenceError, card_message
from structures.common.files import read_dataset, write_dataset

K_CONVENTION = "k = omega*b/V, b = refc/2"
METHODS = ("quartic", "parabolic")


def spline_matrices(aero_model) -> SplineMatrices:
    """G_kg of the whole aerodynamic model (every box, every spline grid degree of freedom).

    Parameters
    ----------
    aero_model : aero.model.AeroModel

    Returns
    -------
    SplineMatrices
        Rows in mesh box order; columns (grid, component 1..6) over the union of the splines' grids,
        sorted by grid id. Boxes that no spline covers get zero rows (with a warning).
    """
    mesh = aero_model.mesh
    box_ids = np.asarray(mesh.box_id)
    row_of = {int(b): i for i, b in enumerate(box_ids)}
    grids = np.unique(np.concatenate([s.grid_ids for s in aero_model.splines])) \
        if aero_model.splines else np.zeros(0, dtype=int)
    col_of = {int(g): i for i, g in enumerate(grids)}
    nb, nd = box_ids.size, 6 * grids.size
    h_c, s_c, h_l = np.zeros((nb, nd)), np.zeros((nb, nd)), np.zeros((nb, nd))
    covered = np.zeros(nb, dtype=bool)
    for sp in aero_model.splines:
        panel = aero_model.panel(sp.caero)
        rows = np.array([row_of[b] for b in range(sp.box1, sp.box2 + 1)])
        normal = np.asarray(mesh.normal)[rows[0]]
        origin, axes = spline_frame(sp, normal, panel.p1, aero_model.aero_frame)
        hc, sc, hl = spline_transform(
            sp, grid_aero=aero_model.aero_frame.from_basic(sp.grid_xyz),
            colloc=np.asarray(mesh.collocation)[rows],
            load=0.5 * (mesh.doublet_in[rows] + mesh.doublet_out[rows]),
            frame_origin=origin, frame_axes=axes, aero_axes=aero_model.aero_frame.axes)
        cols = (6 * np.array([col_of[int(g)] for g in sp.grid_ids])[:, None] + np.arange(6)).ravel()
        if sp.usage in ("BOTH", "DISP"):
            h_c[np.ix_(rows, cols)] += hc
            s_c[np.ix_(rows, cols)] += sc
        if sp.usage in ("BOTH", "FORCE"):
            h_l[np.ix_(rows, cols)] += hl
        covered[rows] = True
    if not covered.all():
        missing = box_ids[~covered]
        warnings.warn(card_message(
            f"{missing.size} boxes ({missing[:5].tolist()}...) are on no spline and stay fixed.",
            filename=aero_model.filename, fix="extend the SPLINE1/SPLINE2 BOX1..BOX2 ranges."),
            stacklevel=2)
    return SplineMatrices(box_ids=box_ids, grid=np.repeat(grids, 6),
                          component=np.tile(np.arange(1, 7), grids.size),
                          h_colloc=h_c, slope_colloc=s_c, h_load=h_l)


def mode_columns(modes_ds: xr.Dataset, grid: np.ndarray, component: np.ndarray,
                 grid_xyz: dict | None = None) -> np.ndarray:
    """Mode shapes at the given (grid, component) degrees of freedom.

    Parameters
    ----------
    modes_ds : xarray.Dataset
        The modes contract: ``shape(mode, dof)`` with coordinates ``grid(dof)``, ``component(dof)``.
    grid, component : ndarray, shape (ndof,)
        Wanted degrees of freedom (basic-frame components 1..6).
    grid_xyz : dict, optional
        {grid id: (3,) basic position} to check against the Dataset's ``x, y, z`` coordinates.

    Returns
    -------
    ndarray, shape (ndof, nmode)
    """
    g = np.asarray(modes_ds["grid"].values, dtype=int)
    c = np.asarray(modes_ds["component"].values, dtype=int)
    index = {(int(a), int(b)): i for i, (a, b) in enumerate(zip(g, c))}
    missing = sorted({int(a) for a, b in zip(grid, component) if (int(a), int(b)) not in index})
    if missing:
        raise MissingReferenceError(card_message(
            f"spline grids {missing[:10]} are not in the modes Dataset (source "
            f"{modes_ds.attrs.get('source', '?')}).", card="SET1",
            fix="compute the modes on the deck that holds the splines' grids, or correct the "
                "SET1."))
    idx = np.array([index[(int(a), int(b))] for a, b in zip(grid, component)], dtype=int)
    if grid_xyz and all(name in modes_ds.coords for name in ("x", "y", "z")):
        xyz = np.column_stack([modes_ds[name].values[idx] for name in ("x", "y", "z")])
        ref = np.array([grid_xyz[int(a)] for a in grid])
        size = max(np.ptp(ref, axis=0).max(), 1.0)
        bad = np.abs(xyz - ref).max(axis=1) > 1e-6 * size
        if bad.any():
            raise InputError(card_message(
                f"grids {sorted(set(np.asarray(grid)[bad].tolist()))[:10]} have other positions in "
                "the modes Dataset than in the aerodynamic deck.", card="GRID",
                fix="use modes computed on the same deck."))
    return np.asarray(modes_ds["shape"].values, dtype=float)[:, idx].T


def modal_box_motion(aero_model, modes_ds: xr.Dataset) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """G_kg Phi: the box motion of every mode.

    Returns
    -------
    h_colloc, slope_colloc, h_load : ndarray, shape (nbox, nmode)
        Normal displacement and free-stream slope at the collocation points, normal displacement at
        the load points (mesh box order).
    """
    G = spline_matrices(aero_model)
    xyz = {int(g): p for sp in aero_model.splines for g, p in zip(sp.grid_ids, sp.grid_xyz)}
    phi = mode_columns(modes_ds, G.grid, G.component, xyz)
    return G.h_colloc @ phi, G.slope_colloc @ phi, G.h_load @ phi


def pressure_coefficients(D: np.ndarray, h_colloc: np.ndarray, slope_colloc: np.ndarray,
                          ks: np.ndarray, semichord: float) -> np.ndarray:
    """Delta Cp of harmonic modal motion: solve {w/V} = D {Delta Cp}.

    Parameters
    ----------
    D : ndarray of complex, shape (nk, nbox, nbox)
        Normalwash-from-pressure matrices (``aero.dlm.dlm_aic``).
    h_colloc, slope_colloc : ndarray, shape (nbox, nmode)
    ks : ndarray, shape (nk,)
        Reduced frequencies k = omega * b / V.
    semichord : float
        b = REFC / 2.

    Returns
    -------
    ndarray of complex, shape (nk, nbox, nmode)
    """
    ks = np.asarray(ks, dtype=float).reshape(-1)
    # w/V = D_jk h with D_jk = d/dx + i k/b (flow tangency, Nastran's D1JK + i k D2JK)
    w = slope_colloc[None] + 1j * (ks / semichord)[:, None, None] * h_colloc[None]
    return np.linalg.solve(D, w)


def _warn_k_limit(aero_model, mach: float, ks: np.ndarray) -> None:
    check = getattr(_dlm, "check_mesh_for_k", None)
    if check is None:
        return
    for message in check(aero_model.mesh, mach, float(np.max(ks)), refc=aero_model.refc):
        warnings.warn(message, stacklevel=3)


def _check_points(machs, ks, method: str) -> tuple[np.ndarray, np.ndarray]:
    if method not in METHODS:
        raise InputError(f"generalized_aero_forces: unknown method {method!r}. Fix: use one of "
                         f"{METHODS}.")
    machs = np.atleast_1d(np.asarray(machs, dtype=float))
    ks = np.atleast_1d(np.asarray(ks, dtype=float))
    if machs.ndim != 1 or ks.ndim != 1 or machs.size == 0 or ks.size == 0 or np.any(ks < 0):
        raise InputError("generalized_aero_forces: machs and ks must be non-empty 1-D lists, "
                         "k >= 0. Fix: pass e.g. machs=[0.5], ks=[0.1, 0.5].")
    return machs, ks


def _spline_dofs(aero_model) -> tuple[SplineMatrices, np.ndarray, dict]:
    """The splines' G_kg, the columns (grid degrees of freedom) that move some box, and the
    splines' grid positions {grid id: (3,) basic}."""
    G = spline_matrices(aero_model)
    used = np.flatnonzero((np.abs(G.h_colloc) + np.abs(G.slope_colloc)
                           + np.abs(G.h_load)).sum(axis=0) > 0)
    xyz = {int(g): p for sp in aero_model.splines for g, p in zip(sp.grid_ids, sp.grid_xyz)}
    return G, used, xyz


def grid_aero_forces(aero_model, machs, ks, *, method: str = "quartic") -> xr.Dataset:
    """Q_gg(M, k): the aerodynamic forces on the splines' grid degrees of freedom, the part of
    Q_hh that does not depend on the modes.

    With G_kg restricted to the grid degrees of freedom g that move some box,
    Q_gg = G_kg^T W_kk S_kj A_jj^-1 D_jk G_kg (module docstring) and, for any modes Phi_g of the
    structure at those degrees of freedom, Q_hh = Phi_g^T Q_gg Phi_g (:func:`project_gaf`). The
    doublet-lattice matrices (the cost) are computed once for every set of modes: a tuned model,
    another weight configuration on the same aerodynamic grid.

    Parameters
    ----------
    aero_model : aero.model.AeroModel
    machs : array_like, shape (nm,)
    ks : array_like, shape (nk,)
        Reduced frequencies k = omega * b / V, b = REFC / 2.
    method : {"quartic", "parabolic"}

    Returns
    -------
    xarray.Dataset
        ``Q(mach, k, gdof_i, gdof_j)`` complex with coordinates ``grid(gdof_i)``,
        ``component(gdof_i)`` (basic 1..6) and the grids' ``x, y, z(gdof_i)``; attrs as
        :func:`generalized_aero_forces`.
    """
    machs, ks = _check_points(machs, ks, method)
    G, used, xyz = _spline_dofs(aero_model)
    h_c, s_c, h_l = G.h_colloc[:, used], G.slope_colloc[:, used], G.h_load[:, used]
    area = np.asarray(aero_model.mesh.area, dtype=float)
    b = aero_model.refc / 2.0
    Q = np.empty((machs.size, ks.size, used.size, used.size), dtype=complex)
    for im, mach in enumerate(machs):
        _warn_k_limit(aero_model, mach, ks)
        D = _dlm.dlm_aic(aero_model.mesh, float(mach), ks, refc=aero_model.refc, method=method,
                         symxz=aero_model.symxz)
        dcp = pressure_coefficients(D, h_c, s_c, ks, b)
        Q[im] = np.einsum("bi,b,kbj->kij", h_l, area, dcp)  # G_kg^T S_kj Delta Cp
    grid, comp = G.grid[used], G.component[used]
    pos = np.array([xyz[int(g)] for g in grid], dtype=float).reshape(-1, 3)
    ds = xr.Dataset(
        {"Q": (("mach", "k", "gdof_i", "gdof_j"), Q)},
        coords={"mach": machs, "k": ks, "grid": ("gdof_i", grid), "component": ("gdof_i", comp),
                "x": ("gdof_i", pos[:, 0]), "y": ("gdof_i", pos[:, 1]),
                "z": ("gdof_i", pos[:, 2])},
        attrs={"refc": float(aero_model.refc), "rhoref": float(aero_model.rhoref),
               "symxz": int(aero_model.symxz), "k_convention": K_CONVENTION, "method": method,
               "deck": aero_model.filename})
    ds["Q"].attrs["long_name"] = ("aerodynamic force on the spline grids' degrees of freedom per "
                                  "unit dynamic pressure and unit displacement")
    return ds


def project_gaf(grid_gaf: xr.Dataset, modes_ds: xr.Dataset) -> xr.Dataset:
    """Q_hh = Phi_g^T Q_gg Phi_g of ``modes_ds`` from :func:`grid_aero_forces`.

    Parameters
    ----------
    grid_gaf : xarray.Dataset
        ``Q(mach, k, gdof_i, gdof_j)`` with its grid coordinates.
    modes_ds : xarray.Dataset
        Modes of the structure (DESIGN.md section 6) holding every spline grid, at the positions
        the aerodynamic deck gives them.

    Returns
    -------
    xarray.Dataset
        As :func:`generalized_aero_forces`.
    """
    grid = np.asarray(grid_gaf["grid"].values, dtype=int)
    xyz = {int(g): (x, y, z) for g, x, y, z in zip(grid, grid_gaf["x"].values,
                                                  grid_gaf["y"].values, grid_gaf["z"].values)}
    phi = mode_columns(modes_ds, grid, np.asarray(grid_gaf["component"].values, dtype=int), xyz)
    Q = np.einsum("gi,mkgh,hj->mkij", phi, np.asarray(grid_gaf["Q"].values), phi)
    modes = np.asarray(modes_ds["mode"].values)
    units = modes_ds.attrs.get("units", "model units")
    ds = xr.Dataset(
        {"Q": (("mach", "k", "mode_i", "mode_j"), Q)},
        coords={"mach": grid_gaf["mach"].values, "k": grid_gaf["k"].values, "mode_i": modes,
                "mode_j": modes},
        attrs={**{a: grid_gaf.attrs[a] for a in ("refc", "rhoref", "symxz", "k_convention",
                                                  "method", "deck")},
               "units": f"Q: area x (mode shape units)^2 ({units}); "
                        "generalized force = q * Q @ u_h",
               "modes_source": str(modes_ds.attrs.get("source", ""))})
    ds["Q"].attrs["long_name"] = "generalized aerodynamic force matrix per unit dynamic pressure"
    return ds


def generalized_aero_forces(aero_model, modes_ds: xr.Dataset, machs, ks, *,
                            method: str = "quartic") -> xr.Dataset:
    """Q_hh(M, k) of the modes on the aerodynamic model (Nastran's QHH; see module docstring):
    :func:`project_gaf` of :func:`grid_aero_forces`.

    Parameters
    ----------
    aero_model : aero.model.AeroModel
    modes_ds : xarray.Dataset
        The modes contract (DESIGN.md section 6). With AERO SYMXZ = +1 (-1) the deck is a half model
        and the modes must be its symmetric (antisymmetric) modes.
    machs : array_like, shape (nm,)
        Mach numbers (< 1).
    ks : array_like, shape (nk,)
        Reduced frequencies k = omega * b / V, b = REFC / 2.
    method : {"quartic", "parabolic"}
        Doublet-lattice kernel integration.

    Returns
    -------
    xarray.Dataset
        ``Q(mach, k, mode_i, mode_j)`` complex (generalized force on mode i per unit dynamic
        pressure and unit modal coordinate j); attrs ``refc``, ``rhoref``, ``symxz``,
        ``k_convention``, ``method``, ``units``, ``deck``.
    """
    _check_points(machs, ks, method)
    G, used, xyz = _spline_dofs(aero_model)
    mode_columns(modes_ds, G.grid[used], G.component[used], xyz)  # before the costly part
    return project_gaf(grid_aero_forces(aero_model, machs, ks, method=method), modes_ds)


def interpolate_q(q_ds: xr.Dataset, mach: float, k) -> np.ndarray:
    """Q_hh at one tabulated Mach number and reduced frequencies k (cubic spline in k).

    Parameters
    ----------
    q_ds : xarray.Dataset
        From :func:`generalized_aero_forces`.
    mach : float
        One of the Dataset's Mach numbers.
    k : float or array_like, shape (r,)
        Reduced frequencies k = omega * b / V within the tabulated range.

    Returns
    -------
    ndarray of complex, shape (n, n) for scalar k, else (r, n, n)
    """
    machs = np.asarray(q_ds["mach"].values, dtype=float)
    hit = np.flatnonzero(np.isclose(machs, mach, rtol=0, atol=1e-9))
    if hit.size == 0:
        raise InputError(f"interpolate_q: Mach {mach} is not tabulated (Mach numbers "
                         f"{machs.tolist()}). Fix: compute Q at that Mach or pick a tabulated one.")
    table = q_ds["Q"].isel(mach=int(hit[0])).sortby("k")
    kk = np.asarray(table["k"].values, dtype=float)
    kq = np.asarray(k, dtype=float)
    if kk.size < 2:
        raise InputError(f"interpolate_q: only {kk.size} k value tabulated at Mach {mach}. "
                         "Fix: tabulate at least 2 reduced frequencies.")
    out = (kq < kk[0] - 1e-12) | (kq > kk[-1] + 1e-12)
    if np.any(out):
        raise InputError(f"interpolate_q: k = {np.atleast_1d(kq)[np.atleast_1d(out)].tolist()} is "
                         f"outside the tabulated range [{kk[0]}, {kk[-1]}] at Mach {mach}. "
                         "Fix: add MKAERO reduced frequencies covering it.")
    vals = np.asarray(table.transpose("k", "mode_i", "mode_j").values)
    spline = CubicSpline(kk, vals, axis=0)
    return spline(np.clip(kq, kk[0], kk[-1]))


def write_gaf(ds: xr.Dataset, path) -> None:
    """Write a Q_hh Dataset to netCDF (atomic, complex-safe)."""
    write_dataset(ds, path)


def read_gaf(path) -> xr.Dataset:
    """Read a Q_hh Dataset written by :func:`write_gaf` and check its layout."""
    ds = read_dataset(path)
    if "Q" not in ds or ds["Q"].dims != ("mach", "k", "mode_i", "mode_j"):
        raise InputError(f"file {path}: not a GAF Dataset (needs Q(mach, k, mode_i, mode_j)). "
                         "Fix: write it with aero.gaf.write_gaf.")
    return ds
