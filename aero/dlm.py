"""Doublet-lattice aerodynamic influence coefficients (normalwash factors) D_jj(M, k).

D(k) = D_steady + D_increment(k): the steady part is the horseshoe vortex lattice of
:mod:`aero.vlm`, the unsteady increment integrates the incremental kernel numerators along each
box's 1/4-chord doublet line (Albano & Rodden 1969, AIAA J. 7(2), eqs. 13-16), with the quartic
numerator approximation of Rodden, Taylor & McIntosh 1998 (J. Aircraft 35(5)) or the original
parabolic one; see :mod:`aero.dlm_kernel` for the formulas and the Desmarais approximation of the
kernel integrals.

    w_i / V = sum_j D_ij(k) dCp_j,
    D_ij = D_steady_ij + chord_j / (8 pi) int_{-e}^{e} [P1(eta)/r1^2 + P2(eta)/r1^4] d eta

(A&R eq. 16; chord_j the mean box chord, e_j the semi-width of the doublet line in the y-z plane)
with P1 = -(K1 exp(-i omega x0/V) - K10) T1 and P2 = -(K2 exp(-i omega x0/V) - K20) T2* (RTM).
The minus sign makes the kernel consistent with the horseshoe lattice: at k = 0,
-chord/(8 pi) int (K10 T1/r1^2 + K20 T2*/r1^4) d eta is exactly the horseshoe normalwash of
:mod:`aero.vlm` (checked by tests/aero/test_dlm.py::test_steady_kernel_equals_horseshoe).
Conventions: k = omega b / V with b = refc / 2 (Nastran), time dependence exp(i omega t),
w the induced velocity along the receiving box's normal, dCp = (p_lower - p_upper)/q positive
along the sending box's normal (:mod:`aero.panels`), so D's steady diagonal is negative.
"""
from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from aero import dlm_kernel as dk
from aero.panels import BoxMesh, mirror_xz
from aero.vlm import check_mach, check_symxz, steady_aic
from structures.errors import InputError, card_message

__all__ = ["dlm_aic", "check_mesh_for_k", "METHODS"]

METHODS = ("quartic", "parabolic")
_TARGET_POINTS = 1 << 16        # kernel points x frequencies per block (~30 MB of temporaries)


def _senders(mesh: BoxMesh, samples: np.ndarray) -> dict:
    """Sending-box frames: midpoint, semi-width e, unit y_e and normal, sweep, sample x."""
    d = mesh.doublet_out - mesh.doublet_in
    e = 0.5 * np.hypot(d[:, 1], d[:, 2])
    ye = np.zeros_like(d)
    ye[:, 1:] = d[:, 1:] / (2.0 * e[:, None])
    mid = 0.5 * (mesh.doublet_in + mesh.doublet_out)
    tanl = d[:, 0] / (2.0 * e)                                   # tan(sweep of the doublet line)
    eta = e[:, None, None] * samples[None, :, None]              # (n, nq, 1)
    pts = mid[:, None, :] + eta * (ye + np.outer(tanl, [1.0, 0.0, 0.0]))[:, None, :]
    # sample points shared by neighbouring boxes (strip edges) are evaluated once
    upts, inv = np.unique(pts.reshape(-1, 3), axis=0, return_inverse=True)
    return {"mid": mid, "e": e, "ye": ye, "n": np.array(mesh.normal), "tanl": tanl,
            "chord": np.array(mesh.chord), "upts": upts, "inv": inv.ravel()}


def _strip_setup(yz, nrm, snd, wv, method):
    """Everything that depends only on a receiving strip's y, z and normal (all its boxes)."""
    sig = dk.SAMPLES[method]
    e = snd["e"]
    dyz = yz[None, :] - snd["mid"][:, 1:]                        # (n, 2) y-z offset to midpoint
    yh = np.einsum("ni,ni->n", dyz, snd["ye"][:, 1:]) / e        # ybar / e, sending frame
    zh = np.einsum("ni,ni->n", dyz, snd["n"][:, 1:]) / e         # zbar / e
    t1 = snd["n"] @ nrm                                          # T1 = n_r . n_s (A&R eq. 8)
    w1, w2 = dk.span_weights(yh, zh, method)                     # (n, nq)
    upts = snd["upts"]                                           # U distinct sample points
    r1u = np.sqrt((yz[0] - upts[:, 1]) ** 2 + (yz[1] - upts[:, 2]) ** 2)
    cq, sq = dk.sincos(wv[:, None] * upts[None, :, 0])
    # P1 = -(K1 e^{-i w x0} - K10) T1 (RTM); A&R eq. 16 with the 1/e of the span weights
    setup = {"r1u": r1u, "freq": dk.frequency_factors(r1u, wv), "cq": cq, "sq": sq,
             "om": w1 * ((-snd["chord"] / (8.0 * np.pi * e)) * t1)[:, None]}
    js = np.nonzero(np.abs(zh) > dk.NEAR_PLANAR)[0]
    setup["js"] = js
    if js.size:
        es = e[js]
        dnr = dyz[js] @ nrm[1:]                                  # d . n_r at the midpoint
        yn = snd["ye"][js] @ nrm                                 # y_e(sender) . n_r
        t2 = (zh[js] * es)[:, None] * (dnr[:, None] - es[:, None] * sig * yn[:, None])
        c2 = -snd["chord"][js] / (8.0 * np.pi * es ** 3)         # P2 = -(dK2) T2*, 1/e^3 weights
        setup["om2"] = w2[js] * t2 * c2[:, None]
        setup["pts"] = snd["inv"][(js[:, None] * sig.size + np.arange(sig.size)).ravel()]
    return setup


def _increment_rows(xr, setup, snd, mach, wv, nq):
    """Unsteady increment for receivers at x = xr (one strip) against all n senders.

    Returns complex (nk, r, n).
    """
    upts, inv = snd["upts"], snd["inv"]
    x0u = xr[:, None] - upts[None, :, 0]                         # (r, U), x0 = x_r - x_q
    geo = dk.kernel_geometry(x0u, setup["r1u"], mach)
    # cos/sin(omega x0/V) as separable products of receiver and sender terms
    cr, sr = dk.sincos(wv[:, None] * xr[None, :])
    cr, sr = cr[:, :, None], sr[:, :, None]
    cq, sq = setup["cq"][:, None, :], setup["sq"][:, None, :]
    cosx = cr * cq + sr * sq
    sinx = sr * cq - cr * sq
    re, im = dk.incremental_k1(geo, setup["freq"], wv, cosx, sinx)   # (nk, r, U)
    nk, r, n = wv.size, xr.size, snd["e"].size
    re, im = re.take(inv, axis=-1), im.take(inv, axis=-1)        # (nk, r, n*nq)
    om = setup["om"]
    out = (np.einsum("krnq,nq->krn", re.reshape(nk, r, n, nq), om)
           + 1j * np.einsum("krnq,nq->krn", im.reshape(nk, r, n, nq), om))
    js = setup["js"]
    if js.size:
        pts = setup["pts"]
        geo2 = {key: (val[..., pts] if np.ndim(val) else val) for key, val in geo.items()}
        ex = cosx[..., pts] - 1j * sinx[..., pts]
        dk2 = dk.incremental_k2(geo2, mach, wv, ex).reshape(nk, r, js.size, nq)
        out[..., js] += np.einsum("krpq,pq->krp", dk2, setup["om2"])
    return out


def _strips(mesh: BoxMesh):
    """Groups of receiving boxes sharing collocation y, z and normal (one strip of a panel)."""
    key = np.concatenate([mesh.collocation[:, 1:], mesh.normal[:, 1:]], axis=1)
    _, inverse = np.unique(key, axis=0, return_inverse=True)
    order = np.argsort(inverse.ravel(), kind="stable")
    bounds = np.flatnonzero(np.diff(inverse.ravel()[order])) + 1
    return np.split(order, bounds)


def dlm_aic(mesh: BoxMesh, mach: float, k, *, refc: float, method: str = "quartic",
            symxz: int = 0, chunk_size: int | None = None,
            workers: int | None = None) -> np.ndarray:
    """Doublet-lattice normalwash matrices D(M, k) for several reduced frequencies at once.

    Parameters
    ----------
    mesh : BoxMesh
        n boxes (only the modelled half when ``symxz != 0``).
    mach : float
        0 <= M < 1; M >= 1 is outside the subsonic method's range and raises InputError.
    k : float or (nk,) array_like
        Reduced frequencies k = omega b / V with b = refc / 2 (Nastran's convention), k >= 0.
    refc : float, keyword-only
        Reference chord (AERO/AEROS REFC), > 0.
    method : {"quartic", "parabolic"}
        Span-wise approximation of the incremental kernel numerator (RTM 1998 / A&R 1969).
    symxz : {0, +1, -1}
        No symmetry, symmetric or antisymmetric about y = 0.
    chunk_size : int, optional
        Receiving boxes per block (blocks never mix strips). A block's temporaries take about
        0.5 kB per (receiver, sample point, k); the default sizes blocks to ~2^16 such entries
        (~30 MB per thread) whatever n and nk; the peak is that, the (nk, n, n) complex result
        and the (n, n) steady matrix.
    workers : int, optional
        Threads over receiving strips (default: the number of CPUs); each thread holds one
        block's temporaries.

    Returns
    -------
    (nk, n, n) complex
        D[k, i, j]: w_i / V per unit dCp_j; D[k] -> steady_aic(mesh, mach) as k -> 0.

    Raises
    ------
    InputError
        Mach outside [0, 1), unknown method (the message lists the valid ones), negative or
        non-finite k, refc <= 0, chunk_size < 1, or a collocation point on the side-edge line of
        a coplanar box (singular kernel; the message names both boxes).
    """
    m = check_mach(mach)
    s = check_symxz(symxz)
    if method not in METHODS:
        raise InputError(card_message(f"unknown doublet-lattice method {method!r}.",
                                      fix=f"use one of {list(METHODS)}."))
    kk = np.atleast_1d(np.asarray(k, dtype=float))
    if kk.ndim != 1 or kk.size == 0 or not np.all(np.isfinite(kk)) or np.any(kk < 0.0):
        raise InputError(card_message(
            f"reduced frequencies {np.asarray(k).tolist()} must be a non-empty list of finite "
            "values k >= 0 (k = omega b / V, b = REFC/2).", card="MKAERO1",
            fix="list non-negative reduced frequencies."))
    refc = float(refc)
    if not np.isfinite(refc) or refc <= 0.0:
        raise InputError(card_message(f"reference chord REFC={refc} must be > 0.",
                                      card="AERO/AEROS", fix="give the reference chord."))
    n, nk = mesh.n, kk.size
    nq = dk.SAMPLES[method].size
    if chunk_size is None:
        rows = max(1, _TARGET_POINTS // max(1, n * nq * nk))
    else:
        rows = int(chunk_size)
        if rows < 1:
            raise InputError(card_message(f"chunk_size={chunk_size} must be >= 1.",
                                          fix="give a positive number of receiving boxes."))
    wv = kk / (0.5 * refc)                                       # omega / V = k / b
    senders = [(1.0, _senders(mesh, dk.SAMPLES[method]))]
    if s:
        senders.append((-float(s), _senders(mirror_xz(mesh), dk.SAMPLES[method])))
    out = np.empty((nk, n, n), dtype=complex)
    out[:] = steady_aic(mesh, m, symxz=s)[None]
    strips = _strips(mesh)

    def run(idx):
        """One receiving strip: shared set-up once, then blocks of at most `rows` boxes."""
        yz, nrm = mesh.collocation[idx[0], 1:], mesh.normal[idx[0]]
        for factor, snd in senders:
            setup = _strip_setup(yz, nrm, snd, wv, method)
            for i0 in range(0, idx.size, rows):                  # strips' rows are disjoint
                sub = idx[i0:i0 + rows]
                out[:, sub] += factor * _increment_rows(mesh.collocation[sub, 0], setup, snd,
                                                        m, wv, nq)

    nthreads = min(len(strips), os.cpu_count() or 1) if workers is None else int(workers)
    if nthreads > 1:                                             # numpy releases the GIL
        with ThreadPoolExecutor(max_workers=nthreads) as pool:
            list(pool.map(run, strips))
    else:
        for idx in strips:
            run(idx)
    bad = ~np.isfinite(out)
    if bad.any():
        _, i, j = (int(v[0]) for v in np.nonzero(bad))
        raise InputError(card_message(
            f"the doublet-lattice AIC is singular for receiving box {mesh.box_id[i]} and sending "
            f"box {mesh.box_id[j]} (or its XZ image): the collocation point lies on the "
            "streamwise extension of a side edge of the sending box in its plane, or on its "
            "doublet line (overlapping panels).",
            card="CAERO1", card_id=int(mesh.panel_id[j]),
            fix="align the spanwise divisions (NSPAN/LSPAN) of coplanar panels, remove overlaps, "
                "or move one panel slightly out of the other's plane."))
    return out


def check_mesh_for_k(mesh: BoxMesh, mach: float, kmax: float, refc: float) -> list[str]:
    """Box-size checks of a mesh for reduced frequencies up to ``kmax``.

    Two modelling rules for the doublet-lattice method from Rodden & Johnson, MSC.Nastran
    Aeroelastic Analysis User's Guide (1994), chapter 2 (doublet-lattice modelling guidelines):
    the streamwise box chord should satisfy dx < 0.08 V/f, i.e. at least 12.5 boxes per
    wavelength V/f = 2 pi b / k (b = refc/2), and boxes should be roughly square; the guide asks
    for aspect ratios of a few at most, and the band [0.25, 4] flagged here is our reading of it.

    Parameters
    ----------
    mesh : BoxMesh
    mach : float
        Checked for range only (the rule is stated in the free-stream wavelength).
    kmax : float
        Largest reduced frequency k = omega b / V to be used.
    refc : float
        Reference chord, b = refc / 2.

    Returns
    -------
    list of str
        One message per offending CAERO1 panel (empty when the mesh is fine).
    """
    check_mach(mach)
    if not (np.isfinite(kmax) and kmax >= 0.0 and np.isfinite(refc) and refc > 0.0):
        raise InputError(card_message(f"kmax={kmax} and refc={refc} must be >= 0 and > 0.",
                                      fix="give the largest reduced frequency and REFC."))
    messages = []
    limit = np.inf if kmax == 0.0 else 0.08 * 2.0 * np.pi * (0.5 * refc) / kmax
    ar = mesh.span / mesh.chord
    for pid in np.unique(mesh.panel_id):
        sel = mesh.panel_id == pid
        worst = float(mesh.chord[sel].max())
        if worst > limit:
            messages.append(card_message(
                f"box chord {worst:.4g} exceeds 0.08 V/f = {limit:.4g} at k = {kmax:g} "
                f"(fewer than 12.5 boxes per wavelength; doublet-lattice accuracy degrades).",
                card="CAERO1", card_id=int(pid),
                fix=f"use at least {int(np.ceil(worst / limit))} times as "
                    "many chordwise boxes (NCHORD/LCHORD) or lower kmax."))
        lo, hi = float(ar[sel].min()), float(ar[sel].max())
        if lo < 0.25 or hi > 4.0:
            messages.append(card_message(
                f"box aspect ratio (span/chord) ranges {lo:.3g}..{hi:.3g}, outside [0.25, 4].",
                card="CAERO1", card_id=int(pid),
                fix="choose NSPAN/NCHORD (or AEFACT lists) giving nearly square boxes."))
    return messages
