"""The k-method (Nastran K / KE) as a cross-check of the p-k solution.

For each reduced frequency k = omega b / V the harmonic flutter equation with artificial structural
damping g (Nastran Aeroelastic Analysis User's Guide, K method; Bisplinghoff, Ashley & Halfman
sec. 9-6)

    [ -omega^2 (M_hh + (rho/2) (b/k)^2 Q_hh(k)) + (1 + i g) K_hh ] u = 0

is solved as the eigenproblem (M + (rho/2)(b/k)^2 Q)^-1 K u = mu u with mu = omega^2 / (1 + i g),
so omega = 1 / sqrt(Re(1/mu)), g = Im(1/mu) / Re(1/mu) and V = omega b / k. g is the damping the
structure would need for neutral motion: flutter where it crosses zero upward as V grows. Only
g = 0 points are physical; they coincide with p-k crossings. Roots are tracked across k by
eigenvector correlation (flutter.tracking).
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from flutter.crossings import Crossing, find_brackets, interpolate_zero
from flutter.gafinterp import GafInterpolator
from flutter.results import attach_crossings, vg_dataset
from flutter.system import ModalSystem
from flutter.tracking import assign
from structures.common.errors import InputError


def k_solve(system: ModalSystem, gaf, k, *, density: float, mach: float,
            refc: float | None = None, interpolation: str = "linear") -> xr.Dataset:
    """k-method V-g / V-f solution over reduced frequencies.

    Parameters
    ----------
    system : ModalSystem
        Modal mass and stiffness (structural damping is the unknown g here and is not used).
    gaf : xarray.Dataset or callable
        ``Q(mach, k, mode_i, mode_j)`` with attrs ``refc``, or ``gaf(mach, k) -> (nk, n, n)``.
    k : array_like, shape (nk,)
        Reduced frequencies k = omega b / V (b = refc / 2), > 0; solved from high to low k (low to
        high speed).
    density, mach : float
        Flight condition.

    Returns
    -------
    xarray.Dataset
        dims (k, root), the sweep dimension ``k`` (attrs ``sweep = "k"``, ``method = "K"``):
        ``velocity`` V = omega b / k of each root, ``damping`` (required g), ``frequency`` [Hz],
        ``eigenvalue`` p = omega (g/2 + i) (the p-k form of the same root, DESIGN.md section 3),
        ``converged`` (False where the root has no k-method solution); ``eigenvector``
        (k, root, mode), largest component 1; coordinates ``density`` and ``mach`` along ``k``.
        Crossings (g = 0, linear in k) on dim ``crossing`` as in :func:`flutter.pk.pk_solve`
        (``crossing_velocity``, ``crossing_frequency``, ``crossing_root``, ``crossing_kind`` =
        "flutter", ...). Rigid-body roots (omega = 0) have no k-method solution and are NaN.
    """
    k = np.asarray(k, dtype=float)
    if k.ndim != 1 or np.any(k <= 0) or np.unique(k).size != k.size:
        raise InputError("k-method: reduced frequencies must be distinct and > 0. Fix: pass a list "
                         "of positive k values (k = omega*b/V) without duplicates.")
    if refc is None:
        if "refc" not in getattr(gaf, "attrs", {}):
            raise InputError("k-method: no refc. Fix: pass refc= (the AERO card's REFC).")
        refc = float(gaf.attrs["refc"])
    b = 0.5 * refc
    k = np.sort(k)[::-1]
    interp = GafInterpolator(gaf, mach, interpolation)
    QR, D, outside = interp(k)
    if outside.any():
        raise InputError(f"k-method: k values {k[outside].tolist()} lie above the tabulated GAF range "
                         f"(max {interp.k_max}). Fix: restrict the k list or extend MKAERO1.")
    Q = QR + 1j * k[:, None, None] * D
    M, K = system.mass, system.stiffness
    n = system.n
    lam = np.full((k.size, n), np.nan + 0j)
    vec = np.zeros((k.size, n, n), dtype=complex)
    for i, ki in enumerate(k):
        A = M + 0.5 * density * (b / ki) ** 2 * Q[i]  # BAH eq. 9-37, Nastran K method
        mu, X = np.linalg.eig(np.linalg.solve(A, K))
        order = np.argsort(np.abs(mu))
        mu, X = mu[order], X[:, order].T
        if i > 0:
            perm = assign(lam[i - 1], vec[i - 1], mu, X)
            mu, X = mu[perm], X[perm]
        lam[i], vec[i] = mu, X
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / lam
        ok = (np.abs(lam) > 1e-12 * np.abs(lam).max()) & (inv.real > 0)
        omega = np.where(ok, 1.0 / np.sqrt(np.where(ok, inv.real, 1.0)), np.nan)
        g = np.where(ok, inv.imag / inv.real, np.nan)
    V = omega * b / k[:, None]
    ones = np.ones(k.size)
    ds = vg_dataset(omega * (0.5 * g + 1j), vec, g, np.isfinite(g), V, density * ones, mach * ones,
                    b=b, modes=system.modes, sweep="k", method="K", k=k,
                    attrs={"density": density, "mach": mach})
    ds["damping"].attrs["long_name"] = "required structural damping g (k method)"
    ds["eigenvalue"].attrs["long_name"] = "p = omega (g/2 + i), the p-k form of the k-method root"
    rows, vectors = [], []
    for r, i in find_brackets(np.nan_to_num(g, nan=-np.inf)):
        if not (np.isfinite(g[i, r]) and np.isfinite(g[i + 1, r])):
            continue
        t = interpolate_zero(g[i, r], g[i + 1, r])
        rows.append(Crossing(root=r + 1, index=int(i), t=float(t),
                             velocity=float(V[i, r] + t * (V[i + 1, r] - V[i, r])),
                             density=float(density), mach=float(mach),
                             frequency=float((omega[i, r] + t * (omega[i + 1, r] - omega[i, r]))
                                             / (2 * np.pi)),
                             kind="flutter", converged=True, refined=False))
        vectors.append(vec[i + (t >= 0.5), r])
    return attach_crossings(ds, rows, np.array(vectors).reshape(len(rows), n))
